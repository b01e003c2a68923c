// Grid nodes that particles reach with B-spline weight 0 (9 particles per cell
// in 2D, 27 in 3D put a particle at each cell centre, 1.5 dx from the far
// nodes, where the quadratic B-spline and its gradient vanish) used to enter
// the Newton system with zero mass and zero stiffness: CHOLMOD_NOT_POSDEF at
// step 1. They are now held in place. A block in free fall must then keep
// falling exactly: total momentum M g t (no boundary touches it), every
// particle with the same velocity (rigid motion), the block undeformed.
#include <gtest/gtest.h>

#include "common/mpm_fixtures.hpp"

using namespace bfemp;
using namespace bfemp::fixtures;

namespace {

template <int dim>
void expect_free_fall(Simulation<dim>& sim, int steps, double dt, double g) {
  for (int k = 0; k < steps; ++k) ASSERT_NO_THROW(sim.step()) << "step " << k + 1;
  const auto& p = sim.mpm()->particles();
  auto v = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.v);
  auto F = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.F);
  const double vz = g * steps * dt;  // backward Euler: v^n = n g dt exactly for a free body
  double worst_v = 0, worst_F = 0;
  for (std::size_t q = 0; q < p.size(); ++q) {
    for (int c = 0; c < dim; ++c) {
      worst_v = std::max(worst_v, std::abs(v(q, c) - (c == dim - 1 ? vz : 0.0)));
      for (int d = 0; d < dim; ++d) worst_F = std::max(worst_F, std::abs(F(q, c, d) - (c == d ? 1.0 : 0.0)));
    }
  }
  EXPECT_LT(worst_v, 1e-9 * std::abs(vz)) << "particle velocities differ from g t";
  EXPECT_LT(worst_F, 1e-9) << "the falling block deformed";
  const StepReport r = sim.diagnostics();
  double mass = 0;
  auto m = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.mass);
  for (std::size_t q = 0; q < p.size(); ++q) mass += m(q);
  EXPECT_NEAR(r.momentum[dim - 1], mass * vz, 1e-9 * mass * std::abs(vz));
}

}  // namespace

TEST(MpmMasslessNodes, NineParticlesPerCell2DFallsFreely) {
  auto s = mpm_rect_setup(0.3, 0.2, Vec<2>(0.5, 0.5), 0.05, 9, Vec<2>(0.0, 0.0), Vec<2>(1.0, 1.0),
                          TransferScheme::APIC);
  s.dt = 0.01;
  s.gravity = {0.0, -9.81, 0.0};
  Simulation<2> sim(s, comm());
  expect_free_fall(sim, 5, s.dt, -9.81);
}

TEST(MpmMasslessNodes, TwentySevenParticlesPerCell3DFallsFreely) {
  auto s = cube_setup(Vec<3>(0.5, 0.5, 0.5), Vec<3>(0.2, 0.2, 0.2), 0.1, Vec<3>(0.0, 0.0, 0.0),
                      Vec<3>(1.0, 1.0, 1.0), 27);
  s.dt = 0.01;
  s.gravity = {0.0, 0.0, -9.81};
  Simulation<3> sim(s, comm());
  expect_free_fall(sim, 3, s.dt, -9.81);
}
