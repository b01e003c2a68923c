// MPM in 3D beyond the derivative checks: a free-falling cube follows the
// integrators' exact discrete recurrences; a cube read from a 3D scene file
// slides on a frictionless plane whose normal is tilted out of every
// coordinate plane, with downhill acceleration g sin(theta) and no particle
// crossing; a block on the z-extruded sine contour slides down its flank in x
// with no z motion (the contour's normal has no z part), while no-slip holds it.
#include <gtest/gtest.h>

#include "common/mpm_fixtures.hpp"
#include "io/scene.hpp"

using namespace bfemp;
using namespace bfemp::fixtures;

namespace {

constexpr double g = 10.0;

std::array<double, 3> momentum(const Particles<3>& p, double& M) {
  auto v = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.v);
  auto m = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.mass);
  std::array<double, 3> P{0, 0, 0};
  M = 0;
  for (std::size_t q = 0; q < m.extent(0); ++q) {
    M += m(q);
    for (int c = 0; c < 3; ++c) P[c] += m(q) * v(q, c);
  }
  return P;
}

double min_phi(const Particles<3>& p, const LevelSet& ls, double t) {
  auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.x);
  double mn = 1e300;
  for (std::size_t q = 0; q < x.extent(0); ++q) mn = std::min(mn, ls.phi<3>(Vec<3>(x(q, 0), x(q, 1), x(q, 2)), t));
  return mn;
}

}  // namespace

TEST(Mpm3d, FreeFallFollowsTheDiscreteRecurrence) {
  for (const auto& ti : {TimeIntegrator::backward_euler(), TimeIntegrator::newmark()}) {
    auto s = cube_setup(Vec<3>(0.5, 0.7, 0.5), Vec<3>(0.2, 0.2, 0.2), 0.05, Vec<3>(0, 0, 0), Vec<3>(1, 1, 1));
    s.gravity = {0.0, -g, 0.0};
    s.integrator = ti;
    s.dt = 0.02;
    Simulation<3> sim(s, fixtures::comm());
    const double y0 = particle_mean(sim.mpm()->particles(), 1);
    double y = 0, v = 0, a = -g, M = 0;
    for (int k = 0; k < 6; ++k) {
      const StepReport r = sim.step();
      EXPECT_NEAR(r.min_J, 1.0, 1e-10);
      y = y + s.dt * v + ti.predictor_acc_scale(s.dt) * a + ti.potential_scale(s.dt) * -g;
      v += s.dt * ((1 - ti.gamma) * a + ti.gamma * -g);
      EXPECT_NEAR(particle_mean(sim.mpm()->particles(), 1) - y0, y, 1e-10) << ti.name << " step " << k + 1;
      const auto P = momentum(sim.mpm()->particles(), M);
      EXPECT_NEAR(P[1] / M, v, 1e-9) << ti.name << " step " << k + 1;
      EXPECT_NEAR(P[0] / M, 0.0, 1e-12);
      EXPECT_NEAR(P[2] / M, 0.0, 1e-12);
    }
  }
}

// The scene: a 0.15 m cube above a slip plane through (0, 0, 0) with normal
// (-sin th cos ph, cos th, -sin th sin ph), th = 10 deg, ph = 30 deg.
TEST(Mpm3d, SceneCubeSlidesOnATiltedSlipPlane) {
  const double th = 10.0 * M_PI / 180.0, ph = 30.0 * M_PI / 180.0;
  const Vec<3> n(-std::sin(th) * std::cos(ph), std::cos(th), -std::sin(th) * std::sin(ph));
  char normal[128];
  std::snprintf(normal, sizeof normal, "[%.17g, %.17g, %.17g]", n(0), n(1), n(2));
  const std::string yaml = std::string(R"(%YAML 1.1
---
bfemp:
  dimension: 3
  gravity: [0.0, -10.0, 0.0]
  Time: {dt: 0.02, end time: 0.12, integrator: backward-euler}
  Newton: {eps_d: 1.0e-9}
  Materials:
    rubber: {E: 1.0e6, nu: 0.3, density: 1000.0}
  MPM:
    grid spacing: 0.05
    domain min: [-0.4, -0.3, -0.4]
    domain max: [0.4, 0.4, 0.4]
    particles per cell: 8
    transfer: APIC
    when particles leave: extend
  MPM Bodies:
    cube: {material: rubber, shape: box, center: [0.0, 0.125, 0.0], size: [0.15, 0.15, 0.15]}
  Level Sets:
    incline: {type: half-plane, slip: true, point: [0.0, 0.0, 0.0], normal: )") +
                           normal + R"(}
...
)";
  Scene scene = load_scene_from_string(yaml, ".", {});
  auto setup = build_setup<3>(scene);
  ASSERT_EQ(setup.level_sets.size(), 1u);
  ASSERT_TRUE(setup.mpm->extend_domain);
  const LevelSet plane = setup.level_sets[0];
  Simulation<3> sim(setup, fixtures::comm());
  // Downhill direction: gravity's tangential part.
  const Vec<3> gv(0, -g, 0);
  const Vec<3> gt = gv - gv.dot(n) * n;
  const Vec<3> down = gt.normalized();
  EXPECT_NEAR(gt.norm(), g * std::sin(th), 1e-12);
  double worst = 0, M = 0, mphi = 1e300, worst_violation = 0;
  sim.newton().on_iterate = [&](Kokkos::View<const double*, MemSpace> x) {
    worst_violation = std::max(worst_violation, sim.newton().slip_constraints().violation(x));
  };
  auto P = momentum(sim.mpm()->particles(), M);
  double Pd = 0;
  long constrained = 0;
  for (int k = 0; k < 6; ++k) {
    sim.step();
    constrained += sim.newton().slip_constraints().count();
    P = momentum(sim.mpm()->particles(), M);
    const double Pd1 = P[0] * down(0) + P[1] * down(1) + P[2] * down(2);
    const double acc = (Pd1 - Pd) / (M * 0.02);
    worst = std::max(worst, std::abs(acc / (g * std::sin(th)) - 1));
    EXPECT_NEAR(acc, g * std::sin(th), 1e-6 * g * std::sin(th)) << "step " << k + 1;
    Pd = Pd1;
    mphi = std::min(mphi, min_phi(sim.mpm()->particles(), plane, sim.time()));
  }
  // The momentum across the slope (tangential, normal to `down`) stays zero:
  // gravity has no part there and the constraint forces are along n.
  const Vec<3> across = n.cross(down);
  EXPECT_NEAR((P[0] * across(0) + P[1] * across(1) + P[2] * across(2)) / M, 0.0, 1e-9);
  EXPECT_GT(constrained, 0) << "the cube never reached the plane";
  EXPECT_GT(mphi, 0.0) << "a particle crossed the slip plane";
  EXPECT_LT(worst_violation, 1e-13);
  std::cout << "3D tilted plane: worst |a / (g sin th) - 1| = " << worst << ", min particle distance "
            << mphi << " m, worst constraint violation " << worst_violation << " m, "
            << sim.mpm()->particles().size() << " particles\n";
}

// A 0.1 m cube (dx 0.05) on the flank of the z-extruded contour y = 0.1 cos(2 pi x), its
// bottom following the contour at rest: slip slides it towards the trough in
// x, with no z momentum; no-slip holds it.
TEST(Mpm3d, ExtrudedSineSlipSlidesNoSlipHolds) {
  LevelSet sine;
  sine.kind = LevelSetKind::Sine;
  sine.amplitude = 0.1;
  sine.wavelength = 1.0;
  double moved[2] = {0, 0}, pz = 0, mphi = 1e300;
  for (int slip = 0; slip < 2; ++slip) {
    auto s = cube_setup(Vec<3>(0.25, 0.05, 0.0), Vec<3>(0.1, 0.1, 0.1), 0.05, Vec<3>(0.0, -0.15, -0.1),
                        Vec<3>(0.6, 0.25, 0.1));
    {
      auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), s.mpm->particles.x);
      for (std::size_t q = 0; q < x.extent(0); ++q) x(q, 1) += 0.1 * std::cos(2 * M_PI * x(q, 0));
      Kokkos::deep_copy(s.mpm->particles.x, x);
    }
    s.gravity = {0.0, -g, 0.0};
    s.dt = 0.02;
    s.newton.eps_d = 1e-8;
    sine.slip = slip == 1;
    s.level_sets = {sine};
    Simulation<3> sim(s, fixtures::comm());
    const double x0 = particle_mean(sim.mpm()->particles(), 0);
    double M = 0;
    for (int k = 0; k < 5; ++k) {
      sim.step();
      if (slip) mphi = std::min(mphi, min_phi(sim.mpm()->particles(), sine, sim.time()));
    }
    moved[slip] = particle_mean(sim.mpm()->particles(), 0) - x0;
    const auto P = momentum(sim.mpm()->particles(), M);
    if (slip) pz = P[2] / M;
  }
  std::cout << "3D extruded sine, 0.1 s: x moved " << moved[1] << " m with slip, " << moved[0]
            << " m with no-slip; z velocity " << pz << " m/s; min particle phi " << mphi << " m\n";
  EXPECT_GT(moved[1], 0.01);
  EXPECT_LT(std::abs(moved[0]), 0.1 * moved[1]);
  EXPECT_NEAR(pz, 0.0, 1e-10);
  EXPECT_GT(mphi, 0.0);
}
