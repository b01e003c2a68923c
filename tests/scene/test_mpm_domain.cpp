// Particles leaving the grid domain: with 'MPM/when particles leave: extend'
// the grid grows by whole cells between steps and the flight goes on exactly
// as on a large enough grid; without it, the run stops with the error naming
// the particle and the step.
#include <gtest/gtest.h>

#include "common/mpm_fixtures.hpp"

using namespace bfemp;
using namespace bfemp::fixtures;

namespace {

// A 0.2 x 0.2 block thrown at (vx, vy) without gravity from the middle of the
// unit-square grid; PIC keeps it rigid (free flight).
SimulationSetup<2> thrown(bool extend) {
  auto s = mpm_rect_setup(0.2, 0.2, Vec<2>(0.5, 0.5), 0.05, 4, Vec<2>(0.0, 0.0), Vec<2>(1.0, 1.0),
                          TransferScheme::PIC, 1e6, 0.3, 1000.0);
  s.dt = 0.05;
  s.mpm->extend_domain = extend;
  return s;
}

void throw_block(Simulation<2>& sim, double vx, double vy) {
  Kokkos::deep_copy(Kokkos::subview(sim.mpm()->particles().v, Kokkos::ALL(), 0), vx);
  Kokkos::deep_copy(Kokkos::subview(sim.mpm()->particles().v, Kokkos::ALL(), 1), vy);
}

}  // namespace

TEST(MpmDomain, ExtendGrowsTheGridAndTheFlightContinues) {
  const double vx = -2.0, vy = 1.5;
  Simulation<2> sim(thrown(true), fixtures::comm());
  throw_block(sim, vx, vy);
  const GridSpec<2> g0 = sim.mpm()->grid();
  const double x0 = particle_mean(sim.mpm()->particles(), 0), y0 = particle_mean(sim.mpm()->particles(), 1);
  const int steps = 20;  // 2 m left and 1.5 m up: far outside the initial unit square
  for (int k = 0; k < steps; ++k) ASSERT_NO_THROW(sim.step()) << "step " << k + 1;
  const GridSpec<2>& g = sim.mpm()->grid();
  const double t = steps * 0.05;
  EXPECT_NEAR(particle_mean(sim.mpm()->particles(), 0) - x0, vx * t, 1e-9);
  EXPECT_NEAR(particle_mean(sim.mpm()->particles(), 1) - y0, vy * t, 1e-9);
  EXPECT_GT(sim.mpm()->domain_extensions(), 0);
  // Grown by whole cells on the lattice of the original grid, both ways it had to.
  EXPECT_EQ(g.dx, g0.dx);
  for (int d = 0; d < 2; ++d) {
    const double cells = (g.origin[d] - g0.origin[d]) / g.dx;
    EXPECT_NEAR(cells, std::round(cells), 1e-9) << "axis " << d;
  }
  EXPECT_LT(g.origin[0], g0.origin[0] - 1.5);
  EXPECT_GT(g.origin[0] + g.dx * g.n_cells[0], 1.0);
  EXPECT_GT(g.origin[1] + g.dx * g.n_cells[1], g0.origin[1] + g0.dx * g0.n_cells[1] + 1.2);
  EXPECT_EQ(particle_outside(g, sim.mpm()->particles()), -1);
  std::cout << "grid grew " << sim.mpm()->domain_extensions() << " times: origin (" << g0.origin[0] << ", "
            << g0.origin[1] << ") -> (" << g.origin[0] << ", " << g.origin[1] << "), cells " << g0.n_cells[0]
            << " x " << g0.n_cells[1] << " -> " << g.n_cells[0] << " x " << g.n_cells[1] << "\n";
}

TEST(MpmDomain, WithoutExtendTheSameThrowIsAClearError) {
  Simulation<2> sim(thrown(false), fixtures::comm());
  throw_block(sim, -2.0, 1.5);
  long failed_at = -1;
  std::string msg;
  for (int k = 0; k < 20 && failed_at < 0; ++k) {
    try {
      sim.step();
    } catch (const std::runtime_error& e) {
      failed_at = k + 1;
      msg = e.what();
    }
  }
  ASSERT_GT(failed_at, 0) << "the block left the grid without an error";
  EXPECT_NE(msg.find("step " + std::to_string(failed_at) + ": MPM particle "), std::string::npos) << msg;
  EXPECT_NE(msg.find("left the grid domain"), std::string::npos) << msg;
  EXPECT_NE(msg.find("when particles leave: extend"), std::string::npos) << msg;
  EXPECT_EQ(sim.mpm()->domain_extensions(), 0);
}

TEST(MpmDomain, GridExtendedCoversTheBoxOnTheSameLattice) {
  const GridSpec<3> g = grid_covering<3>(Vec<3>(0.0, 0.0, 0.0), Vec<3>(1.0, 1.0, 1.0), 0.1);
  const GridSpec<3> e = grid_extended(g, Vec<3>(-0.73, 0.2, 0.1), Vec<3>(0.5, 2.31, 0.9), 3);
  EXPECT_TRUE(e.contains(Vec<3>(-0.73, 0.2, 0.1)));
  EXPECT_TRUE(e.contains(Vec<3>(0.5, 2.31, 0.9)));
  EXPECT_EQ(e.n_cells[2], g.n_cells[2]);  // z did not need to grow
  EXPECT_EQ(e.origin[2], g.origin[2]);
  for (int d = 0; d < 3; ++d) {
    const double cells = (e.origin[d] - g.origin[d]) / g.dx;
    EXPECT_NEAR(cells, std::round(cells), 1e-12);
  }
  // Without margin it is tight: one cell less on the grown side is not enough.
  const GridSpec<3> t = grid_extended(g, Vec<3>(-0.73, 0.2, 0.1), Vec<3>(0.5, 0.5, 0.5), 0);
  GridSpec<3> smaller = t;
  smaller.origin[0] += smaller.dx;
  smaller.n_cells[0] -= 1;
  EXPECT_TRUE(t.contains(Vec<3>(-0.73, 0.2, 0.1)));
  EXPECT_FALSE(smaller.contains(Vec<3>(-0.73, 0.2, 0.1)));
  EXPECT_THROW(grid_extended(g, Vec<3>(NAN, 0, 0), Vec<3>(1, 1, 1), 0), std::invalid_argument);
}
