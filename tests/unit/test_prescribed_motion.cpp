// Prescribed rigid motion: piecewise sequences of fixed, constant-velocity and
// rotation segments, and a fully prescribed body following them with zero
// elastic energy.
#include <gtest/gtest.h>

#include "common/fem_fixtures.hpp"
#include "fem/prescribed_motion.hpp"

using namespace bfemp;

TEST(PrescribedMotion, PiecewiseSequenceOfSegments) {
  PrescribedMotion m;
  MotionSegment down;
  down.type = MotionType::Velocity;
  down.velocity = {0.0, -0.5, 0.0};
  down.duration = 1.0;
  MotionSegment twist;
  twist.type = MotionType::Rotation;
  twist.angular_velocity = M_PI / 5;
  twist.center = {0.0, 0.0, 0.0};
  twist.axis = {0.0, 0.0, 1.0};
  twist.duration = 4.5;
  m.segments = {down, twist, MotionSegment{}};
  const Vec<3> X(1.0, 0.0, 2.0);
  EXPECT_TRUE(m.position<3>(X, 0.0).isApprox(X));
  EXPECT_TRUE(m.position<3>(X, 0.5).isApprox(Vec<3>(1.0, -0.25, 2.0)));
  EXPECT_TRUE(m.velocity<3>(X, 0.5).isApprox(Vec<3>(0.0, -0.5, 0.0)));
  // After the descent (y: -0.5) the point rotates about z by pi/5 rad/s.
  const double th = M_PI / 5 * 2.0;
  const Vec<3> at3 = m.position<3>(X, 3.0);
  EXPECT_NEAR(at3(0), std::cos(th) * 1.0 + std::sin(th) * 0.5, 1e-14);
  EXPECT_NEAR(at3(1), std::sin(th) * 1.0 - std::cos(th) * 0.5, 1e-14);
  EXPECT_NEAR(at3(2), 2.0, 1e-14);
  // Velocity of a rotation: omega x (x - c).
  const Vec<3> v3 = m.velocity<3>(X, 3.0);
  EXPECT_NEAR(v3(0), -M_PI / 5 * at3(1), 1e-14);
  EXPECT_NEAR(v3(1), M_PI / 5 * at3(0), 1e-14);
  // Fixed at the end: position frozen at t = 5.5, zero velocity.
  EXPECT_TRUE(m.position<3>(X, 9.0).isApprox(m.position<3>(X, 5.5)));
  EXPECT_NEAR(m.velocity<3>(X, 9.0).norm(), 0.0, 1e-14);
}

TEST(PrescribedMotion, RigidlyRotatedBodyStaysUndeformed) {
  auto s = fixtures::block_setup<2>(0.25);
  s.dt = 0.05;
  MotionSegment spin;
  spin.type = MotionType::Rotation;
  spin.angular_velocity = 2.0;
  spin.center = {0.5, 0.5, 0.0};
  PrescribedMotion all;
  all.name = "all";
  for (LO n = 0; n < static_cast<LO>(s.bodies[0].mesh.num_nodes()); ++n) all.nodes.push_back(n);
  all.segments = {spin};
  s.motions.push_back(all);
  Simulation<2> sim(s, fixtures::comm());
  for (int k = 0; k < 10; ++k) {
    const StepReport r = sim.step();
    EXPECT_NEAR(r.elastic, 0.0, 1e-9);
    EXPECT_NEAR(r.min_J, 1.0, 1e-12);
  }
  auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sim.positions());
  const auto& X = s.bodies[0].mesh.coords;
  const double th = 2.0 * 0.5;
  for (std::size_t n = 0; n < X.size() / 2; ++n) {
    const double rx = X[2 * n] - 0.5, ry = X[2 * n + 1] - 0.5;
    EXPECT_NEAR(x(2 * n), 0.5 + std::cos(th) * rx - std::sin(th) * ry, 1e-12);
    EXPECT_NEAR(x(2 * n + 1), 0.5 + std::sin(th) * rx + std::cos(th) * ry, 1e-12);
  }
}
