// Level-set kinds: sign of phi and the unit normal used by slip constraints
// (half-plane normal; sine: normalised gradient of the contour function y -
// y_c(x), extruded along z in 3D; box: nearest face), moving with a constant
// velocity.
#include <gtest/gtest.h>

#include <random>

#include "kernels/level_set.hpp"

using namespace bfemp;

namespace {

LevelSet sine(bool above) {
  LevelSet s;
  s.kind = LevelSetKind::Sine;
  s.height = 0.3;
  s.amplitude = 1.0 / 40.0;
  s.wavelength = 0.1;
  s.solid_above = above;
  s.velocity = {0.5, -1.0, 0.25};
  return s;
}

// y of the contour at (x, t).
double contour(const LevelSet& s, double x, double t) {
  return s.height + s.velocity[1] * t + s.amplitude * std::cos(2 * M_PI * (x - s.velocity[0] * t) / s.wavelength);
}

}  // namespace

TEST(LevelSet, SineSignAndNormalIsTheNormalisedContourGradient) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> ux(-0.3, 0.3), uy(-0.05, 0.05);
  for (bool above : {false, true}) {
    const LevelSet s = sine(above);
    for (int k = 0; k < 200; ++k) {
      const double t = 0.01 * (k % 5), x = ux(rng), y = contour(s, x, t) + uy(rng);
      const Vec<2> p(x, y);
      const double f = y - contour(s, x, t);
      const double phi = s.phi<2>(p, t);
      EXPECT_EQ(phi < 0, above ? f > 0 : f < 0) << "x " << x << " y " << y;
      // Normal: gradient of sign * (y - y_c(x)) by central differences, normalised.
      const double h = 1e-7, sg = above ? -1.0 : 1.0;
      Vec<2> grad((-(contour(s, x + h, t) - contour(s, x - h, t)) / (2 * h)) * sg, sg);
      grad.normalize();
      const Vec<2> n = s.unit_normal<2>(p, t);
      EXPECT_NEAR(n.norm(), 1.0, 1e-14);
      EXPECT_NEAR((n - grad).norm(), 0.0, 1e-7);
      // phi is the first-order distance: f / |grad f| (sign as above).
      EXPECT_NEAR(phi, sg * f / std::sqrt(1 + std::pow((contour(s, x + h, t) - contour(s, x - h, t)) / (2 * h), 2)),
                  1e-9);
      // 3D: the same contour extruded along z; the normal has no z part.
      const Vec<3> p3(x, y, 0.37 * k);
      EXPECT_DOUBLE_EQ(s.phi<3>(p3, t), phi);
      const Vec<3> n3 = s.unit_normal<3>(p3, t);
      EXPECT_NEAR(n3(0), n(0), 1e-15);
      EXPECT_NEAR(n3(1), n(1), 1e-15);
      EXPECT_EQ(n3(2), 0.0);
    }
  }
  // At a crest the normal points straight up (solid below) / down (above).
  const LevelSet b = sine(false), a = sine(true);
  EXPECT_NEAR(b.unit_normal<2>(Vec<2>(0.0, 0.3), 0.0)(1), 1.0, 1e-15);
  EXPECT_NEAR(a.unit_normal<2>(Vec<2>(0.0, 0.3), 0.0)(1), -1.0, 1e-15);
  // Moving: the point on the crest moves with the velocity.
  EXPECT_NEAR(b.phi<2>(Vec<2>(0.5 * 0.2, 0.3 + 1.0 / 40.0 - 0.2), 0.2), 0.0, 1e-14);
}

TEST(LevelSet, BoxNormalIsThatOfTheNearestFace) {
  LevelSet b;
  b.kind = LevelSetKind::Box;
  b.box_min = {0.0, 0.0, 0.0};
  b.box_max = {1.0, 0.5, 2.0};
  b.velocity = {0.1, 0.0, 0.0};
  // Inside, nearest face per point (t = 0).
  EXPECT_EQ(b.unit_normal<2>(Vec<2>(0.1, 0.25), 0.0), Vec<2>(-1, 0));
  EXPECT_EQ(b.unit_normal<2>(Vec<2>(0.95, 0.25), 0.0), Vec<2>(1, 0));
  EXPECT_EQ(b.unit_normal<2>(Vec<2>(0.5, 0.45), 0.0), Vec<2>(0, 1));
  EXPECT_EQ(b.unit_normal<2>(Vec<2>(0.5, 0.02), 0.0), Vec<2>(0, -1));
  EXPECT_EQ(b.unit_normal<3>(Vec<3>(0.5, 0.25, 1.97), 0.0), Vec<3>(0, 0, 1));
  EXPECT_LT(b.phi<2>(Vec<2>(0.1, 0.25), 0.0), 0.0);
  // Moved by 0.1 * 2 s = 0.2 along x: x = 0.1 is now outside, left of the box.
  EXPECT_GT(b.phi<2>(Vec<2>(0.1, 0.25), 2.0), 0.0);
  EXPECT_EQ(b.unit_normal<2>(Vec<2>(0.25, 0.25), 2.0), Vec<2>(-1, 0));
}

TEST(LevelSet, HalfPlaneNormal) {
  LevelSet h;
  const double c = std::cos(0.3), s = std::sin(0.3);
  h.normal = {-s, c, 0.0};
  h.point = {1.0, 2.0, 0.0};
  const Vec<2> n = h.unit_normal<2>(Vec<2>(5.0, -3.0), 0.0);
  EXPECT_EQ(n, Vec<2>(-s, c));
  EXPECT_NEAR(h.phi<2>(Vec<2>(1.0 - s, 2.0 + c), 0.0), 1.0, 1e-15);
}

// Piecewise motion (A2: down, left, up at 1 m/s for 0.04, 0.05, 0.08 s, then
// at rest): the offset integrates the segments, the step velocity is the mean
// over a step, exact when a segment ends inside it, and a half-plane moves
// with the offset.
TEST(LevelSet, PiecewiseMotionIntegratesTheSegments) {
  LevelSet s;
  s.kind = LevelSetKind::HalfPlane;
  s.normal = {0, -1, 0};  // solid above y = 0.5
  s.point = {0, 0.5, 0};
  s.segments = 3;
  const double ends[] = {0.04, 0.09, 0.17}, vel[][3] = {{0, -1, 0}, {-1, 0, 0}, {0, 1, 0}};
  for (int k = 0; k < 3; ++k) {
    s.seg_end[k] = ends[k];
    for (int c = 0; c < 3; ++c) s.seg_velocity[k][c] = vel[k][c];
  }
  EXPECT_NEAR(s.offset(1, 0.02), -0.02, 1e-15);
  EXPECT_NEAR(s.offset(0, 0.02), 0.0, 1e-15);
  EXPECT_NEAR(s.offset(0, 0.06), -0.02, 1e-15);
  EXPECT_NEAR(s.offset(1, 0.06), -0.04, 1e-15);
  EXPECT_NEAR(s.offset(1, 0.17), 0.04, 1e-15);
  EXPECT_NEAR(s.offset(1, 0.5), 0.04, 1e-15) << "at rest after the last segment";
  EXPECT_NEAR(s.offset(0, 0.5), -0.05, 1e-15);
  // A step of 0.01 s across the end of the down segment: half down, half left.
  EXPECT_NEAR(s.step_velocity(1, 0.035, 0.01), -0.5, 1e-12);
  EXPECT_NEAR(s.step_velocity(0, 0.035, 0.01), -0.5, 1e-12);
  EXPECT_NEAR(s.step_velocity(1, 0.3, 0.01), 0.0, 1e-15);
  // The plane y = 0.5 + offset: phi = -(y - y_plane).
  const Vec<2> x(0.0, 0.47);
  EXPECT_NEAR(s.phi<2>(x, 0.02), -(0.47 - 0.48), 1e-15);
  EXPECT_NEAR(s.phi<2>(x, 0.17), -(0.47 - 0.54), 1e-15);
  // Without segments, the constant velocity.
  LevelSet c = s;
  c.segments = 0;
  c.velocity = {0, 2, 0};
  EXPECT_NEAR(c.offset(1, 0.3), 0.6, 1e-15);
  EXPECT_EQ(c.step_velocity(1, 0.3, 0.1), 2.0);
}
