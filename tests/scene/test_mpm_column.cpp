// A tall elastic column (H = 4 W, nu = 0, small strain) settling under gravity
// on a no-slip level-set ground with backward Euler: the kinetic energy decays
// by six orders, no particle passes the ground, and the drop of the centre of
// mass matches rho g H^2 / (3 E) within 5 %, improving as dx is refined.
#include <gtest/gtest.h>

#include "common/mpm_fixtures.hpp"

using namespace bfemp;
using namespace bfemp::fixtures;

namespace {

constexpr double W = 0.25, H = 1.0, rho = 1000.0, g = 10.0, E = 1e6;

struct Settled { double drop, ke_ratio, min_y; int steps; };

Settled settle(double dx) {
  auto s = mpm_rect_setup(W, H, Vec<2>(0.0, H / 2), dx, 4, Vec<2>(-0.5, -0.25), Vec<2>(0.5, 1.25),
                          TransferScheme::APIC, E, 0.0, rho);
  s.gravity = {0.0, -g, 0.0};
  s.integrator = TimeIntegrator::backward_euler();
  s.dt = 0.02;
  s.newton.eps_d = 1e-10;
  LevelSet ground;
  ground.name = "ground";
  ground.kind = LevelSetKind::HalfPlane;
  ground.point = {0.0, 0.0, 0.0};
  ground.normal = {0.0, 1.0, 0.0};
  s.level_sets.push_back(ground);
  Simulation<2> sim(s, fixtures::comm());
  const double y0 = particle_mean(sim.mpm()->particles(), 1);
  double ke_max = 0, ke = 0, min_y = 1e300;
  int k = 0;
  for (; k < 400; ++k) {
    ke = sim.step().kinetic;
    ke_max = std::max(ke_max, ke);
    auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sim.mpm()->particles().x);
    for (std::size_t q = 0; q < x.extent(0); ++q) min_y = std::min(min_y, x(q, 1));
    if (k > 10 && ke < 1e-7 * ke_max) break;
  }
  return {y0 - particle_mean(sim.mpm()->particles(), 1), ke / ke_max, min_y, k + 1};
}

}  // namespace

TEST(MpmColumn, SettlesToTheAnalyticSelfWeightCompression) {
  const double exact = rho * g * H * H / (3 * E);
  const Settled coarse = settle(0.05);
  const Settled fine = settle(0.025);
  for (const auto& r : {coarse, fine}) {
    EXPECT_LT(r.ke_ratio, 1e-6) << "kinetic energy must decay by six orders";
    EXPECT_GT(r.min_y, 0.0) << "a particle passed the ground";
  }
  const double err_c = std::abs(coarse.drop - exact) / exact, err_f = std::abs(fine.drop - exact) / exact;
  EXPECT_LT(err_f, 0.05);
  EXPECT_LT(err_f, err_c) << "the error must fall as dx is refined";
  std::cout << "column drop: exact " << exact << ", dx 0.05: " << coarse.drop << " (" << err_c * 100
            << " %, " << coarse.steps << " steps), dx 0.025: " << fine.drop << " (" << err_f * 100 << " %, "
            << fine.steps << " steps)\n";
}

// A step 100x past the explicit CFL limit (dx / sqrt(E / rho)) still
// converges and never inverts a particle, at any Newton iterate.
TEST(MpmExtremeStep, HundredTimesCflConvergesInversionFree) {
  const double dx = 0.05, c = std::sqrt(E / rho);
  auto s = mpm_rect_setup(0.5, 0.5, Vec<2>(0.0, 0.3), dx, 4, Vec<2>(-1.0, -0.25), Vec<2>(1.0, 1.0),
                          TransferScheme::APIC, E, 0.3, rho);
  s.gravity = {0.0, -g, 0.0};
  s.integrator = TimeIntegrator::backward_euler();
  s.dt = 100 * dx / c;
  s.newton.eps_d = 1e-7;
  s.newton.max_iterations = 500;
  LevelSet ground;
  ground.point = {0.0, 0.0, 0.0};
  ground.normal = {0.0, 1.0, 0.0};
  s.level_sets.push_back(ground);
  Simulation<2> sim(s, fixtures::comm());
  // Throw the block down hard as well.
  Kokkos::deep_copy(Kokkos::subview(sim.mpm()->particles().v, Kokkos::ALL(), 1), -5.0);
  double min_J_iterates = 1e300;
  int iterates = 0;
  sim.newton().on_iterate = [&](Kokkos::View<const double*, MemSpace> x) {
    min_J_iterates = std::min(min_J_iterates, deformation_min_J(sim.mpm()->term().stencils(), x));
    ++iterates;
  };
  for (int k = 0; k < 5; ++k) {
    const StepReport r = sim.step();
    EXPECT_GT(r.min_J, 0.0) << "step " << k + 1;
    EXPECT_TRUE(std::isfinite(r.total_energy()));
  }
  EXPECT_GT(min_J_iterates, 0.0);
  std::cout << "dt = " << s.dt << " s (100x CFL): " << iterates << " Newton iterates in 5 steps, min J over iterates "
            << min_J_iterates << "\n";
}

// A particle that leaves the grid domain stops the run with an error naming
// the particle and the step, never a crash.
TEST(MpmDomain, ParticleLeavingTheGridIsAClearError) {
  auto s = mpm_rect_setup(0.2, 0.2, Vec<2>(0.5, 0.5), 0.05, 4, Vec<2>(0.0, 0.0), Vec<2>(1.0, 1.0),
                          TransferScheme::PIC, E, 0.3, rho);
  s.dt = 0.05;
  Simulation<2> sim(s, fixtures::comm());
  Kokkos::deep_copy(Kokkos::subview(sim.mpm()->particles().v, Kokkos::ALL(), 0), 2.0);
  try {
    for (int k = 0; k < 20; ++k) sim.step();
    FAIL() << "the block left the grid without an error";
  } catch (const std::runtime_error& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("MPM particle"), std::string::npos) << msg;
    EXPECT_NE(msg.find("left the grid domain"), std::string::npos) << msg;
    EXPECT_NE(msg.find("step "), std::string::npos) << msg;
  }
}
