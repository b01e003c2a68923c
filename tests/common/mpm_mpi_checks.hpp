#pragma once
// The MPM MPI tests' runs and their comparison with one rank alone
// (test_mpm_mpi, test_mpm_boxes_mpi).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <iostream>
#include <string>
#include <vector>

#include "common/mpi_checks.hpp"
#include "common/mpm_fixtures.hpp"

namespace bfemp::fixtures {

struct Result {
  std::vector<double> x, v;  // gathered particles (rank 0), id order
  std::vector<int> iterations;
  double kinetic = 0, elastic = 0;
  std::array<double, 3> momentum{0, 0, 0}, momentum0{0, 0, 0};
  long long migrated = 0;
  std::size_t local_particles = 0;
  double worst_imbalance = 1.0;  // largest / mean particles per rank, the worst step end
};

// `steps` steps; before_step(s) before step s (0-based) when given.
template <int dim>
Result run_steps(Simulation<dim>& sim, int steps, const std::function<void(int)>& before_step = {}) {
  Result r;
  r.momentum0 = sim.diagnostics().momentum;
  for (int s = 0; s < steps; ++s) {
    if (before_step) before_step(s);
    const StepReport rep = sim.step();
    r.iterations.push_back(rep.newton.iterations);
    r.kinetic = rep.kinetic;
    r.elastic = rep.elastic;
    r.momentum = rep.momentum;
    r.worst_imbalance = std::max(r.worst_imbalance, sim.mpm()->imbalance());
  }
  const Particles<dim> p = sim.mpm()->gathered_particles();
  auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.x);
  auto v = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.v);
  r.x.assign(x.data(), x.data() + x.size());
  r.v.assign(v.data(), v.data() + v.size());
  r.migrated = sim.mpm()->migrated_particles();
  r.local_particles = sim.mpm()->particles().size();
  return r;
}

template <int dim>
void set_velocity(Particles<dim>& p, std::size_t first, std::size_t last, const Vec<dim>& vel) {
  auto v = p.v;
  Kokkos::parallel_for(
      "test_velocity", Kokkos::RangePolicy<ExecSpace>(first, last), KOKKOS_LAMBDA(const std::size_t q) {
        for (int c = 0; c < dim; ++c) v(q, c) = vel(c);
      });
  Kokkos::fence();
}

// CG (any rank count) to 1e-13, Newton to |p|_inf / dt < 1e-9 m/s: the runs
// on several ranks and on one then agree to about 1e-12 m.
template <int dim>
void tight_cg(SimulationSetup<dim>& s) {
  s.linear_solver.set("type", std::string("CG"));
  s.linear_solver.sublist("CG").set("tolerance", 1e-13);
  s.newton.eps_d = 1e-9;
}

template <int dim>
void compare(const Comm& world, const Result& d, const Result& s, double x_tol, const std::string& what) {
  expect_same_on_every_rank(world, d.iterations);
  if (world.getRank() != 0) return;
  ASSERT_EQ(d.x.size(), s.x.size()) << what;
  ASSERT_FALSE(d.x.empty()) << what;
  double ex = 0, ev = 0, vs = 0;
  for (std::size_t i = 0; i < d.x.size(); ++i) {
    ex = std::max(ex, std::abs(d.x[i] - s.x[i]));
    ev = std::max(ev, std::abs(d.v[i] - s.v[i]));
    vs = std::max(vs, std::abs(s.v[i]));
  }
  EXPECT_LT(ex, x_tol) << what;
  EXPECT_LT(ev, 1e-6 * vs) << what;
  EXPECT_NEAR(d.kinetic, s.kinetic, 1e-7 * s.kinetic) << what;
  EXPECT_NEAR(d.elastic, s.elastic, 1e-6 * std::max(s.elastic, 1e-12)) << what;
  std::cout << what << ", " << world.getSize() << " rank(s): |x - x_alone| = " << ex << " m, |v - v_alone| = " << ev
            << " m/s, " << d.migrated << " particle migrations\n";
}

// Two 0.3 x 0.3 MPM blocks (APIC, dx 0.05, 4 per cell) centred at a and b
// on a grid covering [0, domain_max], bodies named `names`; the first moves
// at `velocity`, the second rests. Backward Euler, dt 5e-3, tight_cg.
inline SimulationSetup<2> two_mpm_blocks(Vec<2> a, Vec<2> b, Vec<2> domain_max, Vec<2> velocity,
                                         std::vector<std::string> names) {
  auto s = mpm_rect_setup(0.3, 0.3, a, 0.05, 4, Vec<2>(0.0, 0.0), domain_max, TransferScheme::APIC);
  auto other = mpm_rect_setup(0.3, 0.3, b, 0.05, 4, Vec<2>(0.0, 0.0), domain_max, TransferScheme::APIC);
  const std::size_t nl = s.mpm->particles.size();
  s.mpm->particles = concatenate<2>({s.mpm->particles, other.mpm->particles});
  auto body = s.mpm->particles.body;
  Kokkos::parallel_for(
      "test_body", Kokkos::RangePolicy<ExecSpace>(nl, s.mpm->particles.size()),
      KOKKOS_LAMBDA(const std::size_t q) { body(q) = 1; });
  s.mpm->body_names = std::move(names);
  set_velocity<2>(s.mpm->particles, 0, nl, velocity);
  s.dt = 5e-3;
  s.integrator = TimeIntegrator::backward_euler();
  tight_cg(s);
  return s;
}

}  // namespace bfemp::fixtures
