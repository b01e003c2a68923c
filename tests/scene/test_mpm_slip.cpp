// Slip level sets as exact constraints of the Newton system (paper §6.2
// baseline): zero normal velocity relative to the boundary along the level
// set's normal at every grid node inside, tangential motion free.
//  - A block on a frictionless plane inclined at theta (a rotated half-plane,
//    normal not along an axis) slides with centre-of-mass acceleration
//    g sin(theta): the constraint forces are exactly normal, so the discrete
//    tangential momentum follows P_t^{n+1} = P_t^n + dt M g sin(theta). No
//    particle crosses the plane; every Newton iterate meets the constraint to
//    round-off, with Cholmod, KLU2 and CG alike.
//  - On a sine contour, slip lets a block slide down the flank towards the
//    trough, no-slip holds it.
#include <gtest/gtest.h>

#include "common/mpm_fixtures.hpp"

using namespace bfemp;
using namespace bfemp::fixtures;

namespace {

constexpr double g = 10.0;

// Particles of setup s, sampled axis-aligned as (s, r), moved to
// c0 + s t + r n with t = (cos th, sin th), n = (-sin th, cos th).
void rotate_particles(SimulationSetup<2>& s, double th, Vec<2> c0) {
  auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), s.mpm->particles.x);
  for (std::size_t q = 0; q < x.extent(0); ++q) {
    const double a = x(q, 0), r = x(q, 1);
    x(q, 0) = c0(0) + a * std::cos(th) - r * std::sin(th);
    x(q, 1) = c0(1) + a * std::sin(th) + r * std::cos(th);
  }
  Kokkos::deep_copy(s.mpm->particles.x, x);
}

template <int dim>
std::array<double, 3> particle_momentum(const Particles<dim>& p, double& mass) {
  auto v = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.v);
  auto m = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.mass);
  std::array<double, 3> P{0, 0, 0};
  mass = 0;
  for (std::size_t q = 0; q < m.extent(0); ++q) {
    mass += m(q);
    for (int c = 0; c < dim; ++c) P[c] += m(q) * v(q, c);
  }
  return P;
}

template <int dim>
double min_particle_phi(const Particles<dim>& p, const LevelSet& ls, double t) {
  auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.x);
  double mn = 1e300;
  for (std::size_t q = 0; q < x.extent(0); ++q) {
    Vec<dim> xq;
    for (int c = 0; c < dim; ++c) xq(c) = x(q, c);
    mn = std::min(mn, ls.phi<dim>(xq, t));
  }
  return mn;
}

}  // namespace

class MpmSlipIncline : public ::testing::TestWithParam<std::string> {};

// Backward Euler and Newmark, on a resting plane and on one moving along its
// normal at 0.2 m/s (pushing the block): the tangential acceleration is g sin
// theta either way.
TEST_P(MpmSlipIncline, BlockSlidesWithGSinTheta) {
  const double th = 30.0 * M_PI / 180.0, dx = 0.025, dt = 0.01;
  for (const auto& ti : {TimeIntegrator::backward_euler(), TimeIntegrator::newmark()})
    for (const double vn : {0.0, 0.2}) {
      SCOPED_TRACE(ti.name + (vn > 0 ? ", moving plane" : ", resting plane"));
      // Block 0.2 x 0.1 with its bottom face on the plane through the origin.
      auto s = mpm_rect_setup(0.2, 0.1, Vec<2>(0.0, 0.05), dx, 4, Vec<2>(-0.6, -0.6), Vec<2>(0.6, 0.6),
                              TransferScheme::APIC, 1e6, 0.3, 1000.0);
      rotate_particles(s, th, Vec<2>(0.0, 0.0));
      s.linear_solver.set("type", GetParam());
      s.gravity = {0.0, -g, 0.0};
      s.integrator = ti;
      s.dt = dt;
      s.newton.eps_d = 1e-9;
      LevelSet plane;
      plane.name = "incline";
      plane.slip = true;
      plane.normal = {-std::sin(th), std::cos(th), 0.0};
      plane.velocity = {vn * plane.normal[0], vn * plane.normal[1], 0.0};
      s.level_sets.push_back(plane);
      Simulation<2> sim(s, fixtures::comm());
      const Vec<2> down(-std::cos(th), -std::sin(th));
      double worst_violation = 0, last_violation = 0;
      long iterates = 0;
      sim.newton().on_iterate = [&](Kokkos::View<const double*, MemSpace> x) {
        last_violation = sim.newton().slip_constraints().violation(x);
        if (vn == 0) worst_violation = std::max(worst_violation, last_violation);
        ++iterates;
      };
      double M = 0;
      auto P = particle_momentum(sim.mpm()->particles(), M);
      double Pt = P[0] * down(0) + P[1] * down(1);
      const double x0 = particle_mean(sim.mpm()->particles(), 0), y0 = particle_mean(sim.mpm()->particles(), 1);
      double min_phi = 1e300, worst_acc = 0;
      const int steps = 15;
      for (int k = 0; k < steps; ++k) {
        sim.step();
        EXPECT_GT(sim.newton().slip_constraints().count(), 0);
        worst_violation = std::max(worst_violation, last_violation);  // moving: the converged iterate
        P = particle_momentum(sim.mpm()->particles(), M);
        const double Pt1 = P[0] * down(0) + P[1] * down(1);
        const double acc = (Pt1 - Pt) / (M * dt);
        worst_acc = std::max(worst_acc, std::abs(acc / (g * std::sin(th)) - 1.0));
        EXPECT_NEAR(acc, g * std::sin(th), 1e-6 * g * std::sin(th)) << "step " << k + 1;
        Pt = Pt1;
        min_phi = std::min(min_phi, min_particle_phi(sim.mpm()->particles(), plane, sim.time()));
      }
      const double along = (particle_mean(sim.mpm()->particles(), 0) - x0) * down(0) +
                           (particle_mean(sim.mpm()->particles(), 1) - y0) * down(1);
      const double expect = dt * dt * g * std::sin(th) * steps * (steps + 1) / 2.0;
      // Backward Euler from rest: the centre of mass moved sum_k dt (k dt g sin th) along the slope.
      // Newmark (trapezoidal) from rest with a^0 = g sin th: exactly 1/2 g sin th T^2.
      const double T = steps * dt;
      if (ti.name == TimeIntegrator::backward_euler().name) EXPECT_NEAR(along, expect, 1e-6 * expect);
      else EXPECT_NEAR(along, 0.5 * g * std::sin(th) * T * T, 1e-6 * expect);
      EXPECT_GT(min_phi, 0.0) << "a particle crossed the slip plane";
      EXPECT_LT(worst_violation, 1e-13) << "a Newton iterate left the slip constraint";
      if (vn > 0) {  // the block is pushed along the normal: its normal velocity follows the plane's
        const Vec<2> n(plane.normal[0], plane.normal[1]);
        EXPECT_GT((P[0] * n(0) + P[1] * n(1)) / M, 0.5 * vn);
      }
      std::cout << GetParam() << ", " << ti.name << (vn > 0 ? ", plane moving 0.2 m/s" : ", plane at rest")
                << ": slide " << along << " m in " << steps * dt << " s (BE exact discrete " << expect
                << "), worst |a / (g sin th) - 1| = " << worst_acc << ", min particle distance to plane "
                << min_phi << " m, worst constraint violation " << worst_violation << " m over " << iterates
                << " iterates\n";
    }
}

INSTANTIATE_TEST_SUITE_P(Solvers, MpmSlipIncline, ::testing::Values("Cholmod", "KLU2", "CG"));

// No-slip on the same incline holds the block: its bottom nodes cannot move.
TEST(MpmSlipIncline, NoSlipHoldsTheBlock) {
  const double th = 30.0 * M_PI / 180.0;
  auto s = mpm_rect_setup(0.2, 0.1, Vec<2>(0.0, 0.05), 0.025, 4, Vec<2>(-0.6, -0.6), Vec<2>(0.6, 0.6),
                          TransferScheme::APIC, 1e6, 0.3, 1000.0);
  rotate_particles(s, th, Vec<2>(0.0, 0.0));
  s.gravity = {0.0, -g, 0.0};
  s.dt = 0.01;
  LevelSet plane;
  plane.normal = {-std::sin(th), std::cos(th), 0.0};
  s.level_sets.push_back(plane);
  Simulation<2> sim(s, fixtures::comm());
  const double x0 = particle_mean(sim.mpm()->particles(), 0);
  for (int k = 0; k < 15; ++k) sim.step();
  EXPECT_EQ(sim.newton().slip_constraints().count(), 0);
  EXPECT_LT(std::abs(particle_mean(sim.mpm()->particles(), 0) - x0), 1e-3);
}

// A block resting on the flank of the sine contour y = 0.1 cos(2 pi x)
// (solid below; slope about 32 degrees): with slip it slides towards the
// trough at x = 0.5; with no-slip it stays. The slip constraint uses the contour's normal at each node.
TEST(MpmSlipSine, SlipSlidesDownTheFlankNoSlipHolds) {
  LevelSet sine;
  sine.name = "waves";
  sine.kind = LevelSetKind::Sine;
  sine.height = 0.0;
  sine.amplitude = 0.1;
  sine.wavelength = 1.0;
  double dxs[2] = {0, 0};
  double min_phi_slip = 1e300, violation = 0;
  for (int slip = 0; slip < 2; ++slip) {
    // Block 0.1 x 0.1 over x in [0.2, 0.3] (where the contour falls from
    // y = 0.031 to -0.031), sheared at rest so that its bottom follows the
    // contour (lowest particles dx/4 above it).
    auto s = mpm_rect_setup(0.1, 0.1, Vec<2>(0.25, 0.05), 0.0125, 4, Vec<2>(-0.2, -0.3), Vec<2>(1.0, 0.5),
                            TransferScheme::APIC, 1e6, 0.3, 1000.0);
    {
      auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), s.mpm->particles.x);
      for (std::size_t q = 0; q < x.extent(0); ++q) x(q, 1) += 0.1 * std::cos(2 * M_PI * x(q, 0));
      Kokkos::deep_copy(s.mpm->particles.x, x);
    }
    s.gravity = {0.0, -g, 0.0};
    s.dt = 0.01;
    s.newton.eps_d = 1e-8;
    sine.slip = slip == 1;
    s.level_sets.push_back(sine);
    Simulation<2> sim(s, fixtures::comm());
    if (slip)
      sim.newton().on_iterate = [&](Kokkos::View<const double*, MemSpace> x) {
        violation = std::max(violation, sim.newton().slip_constraints().violation(x));
      };
    const double x0 = particle_mean(sim.mpm()->particles(), 0);
    long constrained = 0;
    for (int k = 0; k < 20; ++k) {
      sim.step();
      constrained += sim.newton().slip_constraints().count();
      if (slip) min_phi_slip = std::min(min_phi_slip, min_particle_phi(sim.mpm()->particles(), sine, sim.time()));
    }
    dxs[slip] = particle_mean(sim.mpm()->particles(), 0) - x0;
    if (slip) EXPECT_GT(constrained, 0);
    else EXPECT_EQ(constrained, 0);
  }
  std::cout << "sine flank, 0.2 s: centre of mass moved " << dxs[1] << " m in x with slip, " << dxs[0]
            << " m with no-slip; min particle phi (slip) " << min_phi_slip << " m, worst constraint violation "
            << violation << " m\n";
  EXPECT_GT(dxs[1], 0.02) << "with slip the block must slide towards the trough";
  EXPECT_LT(std::abs(dxs[0]), 0.1 * dxs[1]) << "no-slip must hold the block";
  EXPECT_GT(min_phi_slip, 0.0) << "a particle passed the sine contour";
  EXPECT_LT(violation, 1e-13);
}

// Level Sets/<name>/until: a no-slip floor holds a block until t = 0.1 s and
// is then removed: the block rests on it (its centre of mass moves < 1e-3 m)
// and from then on falls freely: with no constraint left, the particles'
// centre of mass follows backward Euler's free-fall recurrence
// v += -g dt, y += dt v to round-off (the transfers keep the mass-weighted
// mean velocity), starting from the centre-of-mass velocity at removal.
TEST(MpmLevelSetUntil, RemovedFloorReleasesTheBlockIntoFreeFall) {
  auto s = mpm_rect_setup(0.2, 0.1, Vec<2>(0.0, 0.05), 0.025, 4, Vec<2>(-0.6, -0.6), Vec<2>(0.6, 0.6),
                          TransferScheme::APIC, 1e6, 0.3, 1000.0);
  s.gravity = {0.0, -g, 0.0};
  s.dt = 0.01;
  LevelSet floor;  // solid below y = 0
  floor.normal = {0.0, 1.0, 0.0};
  floor.until = 0.1;
  s.level_sets.push_back(floor);
  Simulation<2> sim(s, fixtures::comm());
  const auto& p = sim.mpm()->particles();
  const double y0 = particle_mean(p, 1);
  while (sim.time() < 0.1 - 1e-12) sim.step();
  EXPECT_LT(std::abs(particle_mean(p, 1) - y0), 1e-3) << "the floor holds the block until it is removed";
  double mass = 0;
  double y = particle_mean(p, 1), v = particle_momentum(p, mass)[1] / mass;
  for (int k = 0; k < 10; ++k) {
    sim.step();
    v -= g * s.dt;
    y += s.dt * v;
  }
  EXPECT_NEAR(particle_mean(p, 1), y, 1e-10);
  EXPECT_NEAR(particle_momentum(p, mass)[1] / mass, v, 1e-10);
  EXPECT_LT(y, y0 - 0.04) << "it fell";
}
