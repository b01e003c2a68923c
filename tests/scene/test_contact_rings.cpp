// Colliding rings (paper section 6.1, VALIDATION A1) at a ci size
// (inputs/contact_rings.yaml): an MPM ring at +40 m/s hits a free FEM ring at
// -40 m/s across a 2 m gap, frictionless, Newmark. Checks through the contact
// start and some steps of contact:
//  - total linear momentum (MPM particles + FEM nodes) constant to within the
//    Newton tolerance: drift < 1e-6 of |p| of one ring, every step;
//  - contact begins (first step with pairs, first nonzero force) at the
//    analytic step: the first step whose free motion closes the initial
//    particle-to-FEM-node gap d0 to below dhat, t = (d0 - dhat) / 80 m/s
//    (d0 = 2 m plus the particle inset from the ring surface);
//  - no particle inside the FEM ring at any Newton iterate;
//  - the contact force on the FEM ring pushes it along +x.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <limits>

#include "common/fem_fixtures.hpp"
#include "io/scene.hpp"

using namespace bfemp;

namespace {

const std::string scene_file = std::string(BFEMP_SOURCE_DIR) + "/inputs/contact_rings.yaml";

// Smallest distance between an MPM particle and an FEM node (the rings face
// each other across the x axis, so this is the particle-to-boundary gap up to
// the chord sagitta h^2 / (8 R) of the FEM boundary).
double initial_gap(Simulation<2>& sim) {
  auto xp = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sim.mpm()->particles().x);
  auto xf = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sim.positions());
  const std::size_t nf = xf.extent(0) / 2;
  double d0 = std::numeric_limits<double>::infinity();
  for (std::size_t q = 0; q < xp.extent(0); ++q)
    for (std::size_t a = 0; a < nf; ++a)
      d0 = std::min(d0, std::hypot(xp(q, 0) - xf(2 * a), xp(q, 1) - xf(2 * a + 1)));
  return d0;
}

}  // namespace

TEST(ContactRings, MomentumConservedContactStartsOnTimeNoPenetration) {
  const Scene scene = load_scene(scene_file);
  const auto& p = scene.params;
  const double dt = p.sublist("Time").get<double>("dt");
  const double end = p.sublist("Time").get<double>("end time");
  const double dhat = p.sublist("Contact").get<double>("dhat");
  const double h = p.sublist("FEM Bodies").sublist("right").sublist("Mesh").get<double>("element size");
  const double R = 4.0, v = 40.0;
  ASSERT_EQ(p.sublist("Time").get<std::string>("integrator"), "newmark");

  Simulation<2> sim(build_setup<2>(scene), fixtures::comm());
  long iterates = 0, inside = 0;
  sim.newton().on_iterate = [&](Kokkos::View<const double*, MemSpace> x) {
    ++iterates;
    if (sim.contact()->particle_inside_at(x) >= 0) ++inside;
  };

  // |p| of one ring: the MPM ring's particle mass times 40 m/s.
  auto mass = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sim.mpm()->particles().mass);
  double m_ring = 0;
  for (std::size_t q = 0; q < mass.extent(0); ++q) m_ring += mass(q);
  const double p_ring = m_ring * v;
  ASSERT_NEAR(m_ring, 1000.0 * M_PI * (R * R - 9.0), 0.05 * m_ring);

  // Analytic contact start: free motion closes the gap at 2 v = 80 m/s; the
  // first step whose end-of-step gap is below dhat has pairs. The node-based
  // gap overestimates the true one by at most the sagitta: allow one step.
  const double d0 = initial_gap(sim);
  ASSERT_GT(d0, 2.0);
  ASSERT_LT(d0, 2.0 + 0.5 * p.sublist("MPM").get<double>("grid spacing"));
  const double t_contact = (d0 - dhat) / (2 * v);
  const double t_contact_lo = (d0 - h * h / (8 * R) - dhat) / (2 * v);
  const long n_expected = static_cast<long>(std::floor(t_contact / dt)) + 1;
  const long n_expected_lo = static_cast<long>(std::floor(t_contact_lo / dt)) + 1;

  const StepReport r0 = sim.diagnostics();
  const std::array<double, 3> p0 = r0.momentum;
  const double e0 = r0.total_energy();
  double drift = 0, drift_y = 0, fmax = 0;
  long first_pairs = -1, first_force = -1, contact_steps = 0;
  double t_first = -1;
  const long steps = std::lround(end / dt);
  for (long n = 0; n < steps; ++n) {
    const StepReport r = sim.step();
    drift = std::max(drift, std::abs(r.momentum[0] - p0[0]));
    drift_y = std::max(drift_y, std::abs(r.momentum[1] - p0[1]));
    if (r.contact_pairs > 0) {
      if (first_pairs < 0) first_pairs = r.step, t_first = r.time;
      ++contact_steps;
      EXPECT_GT(r.min_distance, 0.0) << "step " << r.step;
      EXPECT_LT(r.min_distance, dhat) << "step " << r.step;
      EXPECT_GT(r.contact_force[0], 0.0) << "step " << r.step << ": the MPM ring pushes the FEM ring along +x";
    } else {
      EXPECT_EQ(r.contact_force[0], 0.0) << "step " << r.step << ": a force without pairs";
    }
    if (first_force < 0 && r.contact_force[0] != 0.0) first_force = r.step;
    fmax = std::max(fmax, r.contact_force[0]);
    EXPECT_LT(std::abs(r.momentum[0] - p0[0]), 1e-6 * p_ring)
        << "step " << r.step << ": x momentum " << r.momentum[0] << " vs " << p0[0];
    EXPECT_LT(std::abs(r.momentum[1] - p0[1]), 1e-6 * p_ring)
        << "step " << r.step << ": y momentum " << r.momentum[1] << " vs " << p0[1];
  }
  const StepReport r_end = sim.diagnostics();

  EXPECT_EQ(inside, 0) << "Newton iterates with a particle inside the FEM ring (of " << iterates << ")";
  // The cached graph always held every coupling the terms assembled (a miss
  // would have been caught by the sink and forced a rebuild).
  EXPECT_EQ(sim.newton().dof_space().missing_block_rebuilds(), 0);
  std::cout << "rings: " << sim.newton().dof_space().graph_builds() << " graph builds, "
            << sim.newton().dof_space().graph_reuses() << " reuses in " << steps << " steps\n";
  ASSERT_GT(first_pairs, 0) << "no contact in " << steps << " steps";
  EXPECT_GE(first_pairs, n_expected_lo) << "contact began before the analytic time " << t_contact << " s";
  EXPECT_LE(first_pairs, n_expected) << "contact began after the analytic time " << t_contact << " s";
  EXPECT_EQ(first_force, first_pairs);
  EXPECT_GT(contact_steps, 10);
  EXPECT_GT(fmax, 0.0);
  std::cout << "rings: |p| of one ring " << p_ring << " kg m/s (per m), total p0 (" << p0[0] << ", " << p0[1]
            << "), max drift (" << drift << ", " << drift_y << ") = (" << drift / p_ring << ", "
            << drift_y / p_ring << ") of |p_ring|; gap " << d0 << " m, analytic contact t = " << t_contact
            << " s (2/80 = 0.025 s), first contact step " << first_pairs << " (t = " << t_first
            << " s), expected step " << n_expected_lo << ".." << n_expected << "; " << contact_steps
            << " contact steps, peak force " << fmax << " N/m; " << iterates << " Newton iterates; energy "
            << e0 << " -> " << r_end.total_energy() << " J/m\n";
}
