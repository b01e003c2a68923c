// Contact distances (kernels/contact/distance.hpp): every point-edge (2D, 3D)
// and point-triangle case with points placed in its region, against analytic
// values and brute-force minimisation over the feature's parameters; case
// labels and closest parameters; degenerate and nearly degenerate features;
// random configurations.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>

#include "kernels/contact/distance.hpp"

namespace {

using namespace bfemp;

template <int dim>
Vec<dim> v(double x, double y, double z = 0.0) {
  Vec<dim> a;
  a(0) = x;
  a(1) = y;
  if constexpr (dim == 3) a(2) = z;
  return a;
}

// min over beta in [0,1] of |p - e0 - beta (e1 - e0)|^2: a fine sampling, then
// golden-section refinement around the best sample (the function is convex).
template <int dim>
double brute_point_edge(const Vec<dim>& p, const Vec<dim>& e0, const Vec<dim>& e1) {
  auto f = [&](double b) { return (p - (e0 + b * (e1 - e0))).squaredNorm(); };
  const int n = 200;
  int best = 0;
  for (int i = 1; i <= n; ++i)
    if (f(double(i) / n) < f(double(best) / n)) best = i;
  double lo = std::max(0.0, (best - 1.0) / n), hi = std::min(1.0, (best + 1.0) / n);
  for (int it = 0; it < 100; ++it) {
    const double a = lo + (hi - lo) * 0.381966, b = lo + (hi - lo) * 0.618034;
    (f(a) < f(b) ? hi : lo) = (f(a) < f(b) ? b : a);
  }
  return std::min({f(0.0), f(1.0), f(0.5 * (lo + hi))});
}

// min over the triangle: the exact minimum over each sampled line b2 = const
// (a point-edge distance), then golden-section over b2 (convex in b2).
double brute_point_triangle(const Vec<3>& p, const Vec<3>& t0, const Vec<3>& t1, const Vec<3>& t2) {
  auto g = [&](double b2) {  // segment {(1-b1-b2) t0 + b1 t1 + b2 t2 : b1 in [0, 1-b2]}
    const Vec<3> a = (1 - b2) * t0 + b2 * t2, b = (1 - b2) * t1 + b2 * t2;
    return brute_point_edge<3>(p, a, b);
  };
  const int n = 200;
  int best = 0;
  for (int i = 1; i <= n; ++i)
    if (g(double(i) / n) < g(double(best) / n)) best = i;
  double lo = std::max(0.0, (best - 1.0) / n), hi = std::min(1.0, (best + 1.0) / n);
  for (int it = 0; it < 80; ++it) {
    const double a = lo + (hi - lo) * 0.381966, b = lo + (hi - lo) * 0.618034;
    (g(a) < g(b) ? hi : lo) = (g(a) < g(b) ? b : a);
  }
  return std::min({g(0.0), g(1.0), g(0.5 * (lo + hi))});
}

// ------------------------------------------------------------ point-edge

template <int dim>
void check_point_edge_cases() {
  const Vec<dim> e0 = v<dim>(0, 0, 0), e1 = v<dim>(2, 0, 0);
  struct Case {
    Vec<dim> p;
    PointEdgeCase c;
    double d2, beta;
  };
  const Case cases[] = {
      {v<dim>(-1, 1, dim == 3 ? 1 : 0), PointEdgeCase::P_E0, dim == 3 ? 3.0 : 2.0, 0.0},
      {v<dim>(3, -2, 0), PointEdgeCase::P_E1, 5.0, 1.0},
      {v<dim>(0.5, 0.75, dim == 3 ? 1 : 0), PointEdgeCase::P_E, dim == 3 ? 1.5625 : 0.5625, 0.25},
      {v<dim>(1.5, -0.3, 0), PointEdgeCase::P_E, 0.09, 0.75},
  };
  for (const Case& k : cases) {
    EXPECT_EQ(point_edge_case<dim>(k.p, e0, e1), k.c);
    EXPECT_NEAR(point_edge_distance2<dim>(k.p, e0, e1), k.d2, 1e-14);
    EXPECT_NEAR(point_edge_closest_parameter<dim>(k.p, e0, e1), k.beta, 1e-15);
    EXPECT_NEAR(point_edge_distance2<dim>(k.p, e0, e1), brute_point_edge<dim>(k.p, e0, e1), 1e-12);
  }
}

TEST(ContactDistance, PointEdgeCases2D) { check_point_edge_cases<2>(); }
TEST(ContactDistance, PointEdgeCases3D) { check_point_edge_cases<3>(); }

TEST(ContactDistance, PointPoint) {
  EXPECT_DOUBLE_EQ(point_point_distance2<2>(v<2>(1, 2), v<2>(4, -2)), 25.0);
  EXPECT_DOUBLE_EQ(point_point_distance2<3>(v<3>(1, 2, 3), v<3>(1, 2, 3)), 0.0);
}

template <int dim>
void check_point_edge_random(unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  auto rv = [&] {
    Vec<dim> a;
    for (int i = 0; i < dim; ++i) a(i) = u(rng);
    return a;
  };
  double worst = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const Vec<dim> p = rv(), e0 = rv(), e1 = rv();
    const double d2 = point_edge_distance2<dim>(p, e0, e1);
    const double beta = point_edge_closest_parameter<dim>(p, e0, e1);
    ASSERT_GE(beta, 0.0);
    ASSERT_LE(beta, 1.0);
    EXPECT_NEAR((p - ((1 - beta) * e0 + beta * e1)).squaredNorm(), d2, 1e-14);
    worst = std::max(worst, std::abs(d2 - brute_point_edge<dim>(p, e0, e1)));
  }
  EXPECT_LT(worst, 1e-12);
}

TEST(ContactDistance, PointEdgeRandom2D) { check_point_edge_random<2>(1); }
TEST(ContactDistance, PointEdgeRandom3D) { check_point_edge_random<3>(2); }

template <int dim>
void check_point_edge_degenerate() {
  const Vec<dim> p = v<dim>(0.3, 0.4, dim == 3 ? 1.2 : 0), e0 = v<dim>(0.1, -0.2, 0.05);
  // Zero length: point-point to e0.
  EXPECT_EQ(point_edge_case<dim>(p, e0, e0), PointEdgeCase::P_E0);
  EXPECT_EQ(point_edge_distance2<dim>(p, e0, e0), (p - e0).squaredNorm());
  EXPECT_EQ(point_edge_closest_parameter<dim>(p, e0, e0), 0.0);
  // Nearly zero length, down to underflow of |e|^2: finite, right value.
  for (double len : {1e-8, 1e-12, 1e-100, 1e-160, 1e-200, 1e-300}) {
    const Vec<dim> e1 = e0 + len * v<dim>(0.6, 0.8, 0);
    const double d2 = point_edge_distance2<dim>(p, e0, e1);
    ASSERT_TRUE(std::isfinite(d2)) << len;
    EXPECT_NEAR(d2, (p - e0).squaredNorm(), 4 * len + 1e-15) << len;
    const double beta = point_edge_closest_parameter<dim>(p, e0, e1);
    EXPECT_TRUE(beta >= 0 && beta <= 1) << len;
  }
  // Point on the edge's line, on the edge, and exactly at an endpoint.
  const Vec<dim> a = v<dim>(0, 0, 0), b = v<dim>(1, 1, 1);
  EXPECT_NEAR(point_edge_distance2<dim>(0.5 * b, a, b), 0.0, 1e-30);
  EXPECT_EQ(point_edge_distance2<dim>(b, a, b), 0.0);
  EXPECT_EQ(point_edge_distance2<dim>(2.0 * b, a, b), b.squaredNorm());
}

TEST(ContactDistance, PointEdgeDegenerate2D) { check_point_edge_degenerate<2>(); }
TEST(ContactDistance, PointEdgeDegenerate3D) { check_point_edge_degenerate<3>(); }

// ------------------------------------------------------------ point-triangle

struct TriCase {
  Vec<3> p;
  PointTriangleCase c;
  double d2;
  Vec<2> b;
};

// Triangle t0 = 0, t1 = (1,0,0), t2 = (0,1,0); one point in each region,
// lifted off the plane by z.
std::vector<TriCase> triangle_cases() {
  const double z = 0.5, z2 = z * z;
  return {
      {v<3>(-0.5, -0.25, z), PointTriangleCase::P_T0, 0.25 + 0.0625 + z2, Vec<2>(0, 0)},
      {v<3>(1.5, -0.5, -z), PointTriangleCase::P_T1, 0.5 + z2, Vec<2>(1, 0)},
      {v<3>(-0.2, 1.3, z), PointTriangleCase::P_T2, 0.04 + 0.09 + z2, Vec<2>(0, 1)},
      {v<3>(0.3, -0.7, z), PointTriangleCase::P_E01, 0.49 + z2, Vec<2>(0.3, 0)},
      {v<3>(0.8, 0.6, -z), PointTriangleCase::P_E12, 0.08 + z2, Vec<2>(0.6, 0.4)},
      {v<3>(-0.4, 0.25, z), PointTriangleCase::P_E20, 0.16 + z2, Vec<2>(0, 0.25)},
      {v<3>(0.2, 0.3, -z), PointTriangleCase::P_T, z2, Vec<2>(0.2, 0.3)},
  };
}

TEST(ContactDistance, PointTriangleCases) {
  const Vec<3> t0 = v<3>(0, 0, 0), t1 = v<3>(1, 0, 0), t2 = v<3>(0, 1, 0);
  for (const TriCase& k : triangle_cases()) {
    SCOPED_TRACE(static_cast<int>(k.c));
    EXPECT_EQ(point_triangle_case(k.p, t0, t1, t2), k.c);
    EXPECT_NEAR(point_triangle_distance2(k.p, t0, t1, t2), k.d2, 1e-14);
    EXPECT_NEAR(point_triangle_distance2(k.p, t0, t1, t2), brute_point_triangle(k.p, t0, t1, t2), 1e-11);
    const Vec<2> b = point_triangle_closest_barycentric(k.p, t0, t1, t2);
    EXPECT_NEAR(b(0), k.b(0), 1e-14);
    EXPECT_NEAR(b(1), k.b(1), 1e-14);
  }
}

// A general (rotated, scaled, translated) triangle: the same cases keep their
// labels and values, since distances are invariant under rigid motion.
TEST(ContactDistance, PointTriangleCasesTransformed) {
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.7, Vec<3>(1, 2, -0.5).normalized()).toRotationMatrix();
  const double s = 3.0;
  const Vec<3> off(10, -4, 2);
  auto T = [&](const Vec<3>& x) -> Vec<3> { return R * (s * x) + off; };
  const Vec<3> t0 = T(v<3>(0, 0, 0)), t1 = T(v<3>(1, 0, 0)), t2 = T(v<3>(0, 1, 0));
  for (const TriCase& k : triangle_cases()) {
    SCOPED_TRACE(static_cast<int>(k.c));
    EXPECT_EQ(point_triangle_case(T(k.p), t0, t1, t2), k.c);
    EXPECT_NEAR(point_triangle_distance2(T(k.p), t0, t1, t2), s * s * k.d2, 1e-12);
    const Vec<2> b = point_triangle_closest_barycentric(T(k.p), t0, t1, t2);
    EXPECT_NEAR(b(0), k.b(0), 1e-13);
    EXPECT_NEAR(b(1), k.b(1), 1e-13);
  }
}

TEST(ContactDistance, PointTriangleRandom) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  auto rv = [&] { return Vec<3>(u(rng), u(rng), u(rng)); };
  double worst = 0;
  int counts[7] = {};
  for (int trial = 0; trial < 300; ++trial) {
    const Vec<3> p = 1.5 * rv(), t0 = rv(), t1 = rv(), t2 = rv();
    const double d2 = point_triangle_distance2(p, t0, t1, t2);
    const Vec<2> b = point_triangle_closest_barycentric(p, t0, t1, t2);
    ASSERT_GE(b(0), 0.0);
    ASSERT_GE(b(1), 0.0);
    ASSERT_LE(b(0) + b(1), 1.0 + 1e-15);
    EXPECT_NEAR((p - ((1 - b(0) - b(1)) * t0 + b(0) * t1 + b(1) * t2)).squaredNorm(), d2, 1e-13);
    worst = std::max(worst, std::abs(d2 - brute_point_triangle(p, t0, t1, t2)));
    ++counts[static_cast<int>(point_triangle_case(p, t0, t1, t2))];
  }
  EXPECT_LT(worst, 1e-10);
  for (int c = 0; c < 7; ++c) EXPECT_GT(counts[c], 0) << "case " << c << " never sampled";
}

TEST(ContactDistance, PointTriangleDegenerate) {
  const Vec<3> p(0.3, 0.7, 0.4);
  // Collinear vertices (zero area): the nearest of the three point-edge distances.
  const Vec<3> a(0, 0, 0), b(1, 0, 0), c(2, 0, 0);
  const double expect = std::min({point_edge_distance2<3>(p, a, b), point_edge_distance2<3>(p, b, c),
                                  point_edge_distance2<3>(p, c, a)});
  EXPECT_DOUBLE_EQ(point_triangle_distance2(p, a, b, c), expect);
  EXPECT_DOUBLE_EQ(point_triangle_distance2(p, b, a, c), expect);
  EXPECT_NE(point_triangle_case(p, a, b, c), PointTriangleCase::P_T);
  // Two or three coincident vertices.
  EXPECT_DOUBLE_EQ(point_triangle_distance2(p, a, a, b), point_edge_distance2<3>(p, a, b));
  EXPECT_DOUBLE_EQ(point_triangle_distance2(p, a, a, a), (p - a).squaredNorm());
  // Nearly collinear / nearly zero-area: finite and equal to brute force.
  for (double h : {1e-4, 1e-7, 1e-9, 1e-12, 1e-200}) {
    const Vec<3> t2(0.5, h, 0);
    for (const Vec<3>& q : {p, Vec<3>(0.5, 1e-3, 1e-3), Vec<3>(0.4, 0.3 * h, 1e-5), Vec<3>(-0.5, 0.2, -0.1)}) {
      const double d2 = point_triangle_distance2(q, a, b, t2);
      ASSERT_TRUE(std::isfinite(d2)) << h;
      // The sliver's plane is ill-defined below sin = 1e-8: the fallback's
      // distance error is at most the sliver's width h (in d, so ~2 d h in d2).
      const double tol = h > 1e-8 ? 1e-12 : 1e-12 + 2 * h * std::sqrt(d2);
      EXPECT_NEAR(d2, brute_point_triangle(q, a, b, t2), tol) << h;
      const Vec<2> bb = point_triangle_closest_barycentric(q, a, b, t2);
      EXPECT_TRUE(bb(0) >= 0 && bb(1) >= 0 && bb(0) + bb(1) <= 1 + 1e-15) << h;
    }
  }
  // Tiny but well-shaped triangle (scale invariance).
  for (double s : {1e-6, 1e-12, 1e-100}) {
    const Vec<3> q = s * Vec<3>(0.2, 0.3, 0.5);
    EXPECT_EQ(point_triangle_case(q, Vec<3>::Zero(), s * Vec<3>(1, 0, 0), s * Vec<3>(0, 1, 0)),
              PointTriangleCase::P_T);
    EXPECT_NEAR(point_triangle_distance2(q, Vec<3>::Zero(), s * Vec<3>(1, 0, 0), s * Vec<3>(0, 1, 0)) / (s * s),
                0.25, 1e-14);
  }
}

// ------------------------------------------------------------ derivatives

// Finite-difference check of one stencil function F(x) -> Distance2<n> at x:
// gradient against central differences of the value, Hessian against central
// differences of the gradient, step h = 1e-6 * (1 + |x|_inf). `same_case`
// tells whether x + dx lies in the case of x (checks are on one case only).
struct FdErrors {
  double grad = 0, hess = 0;
};

template <int n, class F, class SameCase>
FdErrors fd_check(const Eigen::Matrix<double, n, 1>& x, const F& f, const SameCase& same_case) {
  const double h = 1e-6 * (1 + x.template lpNorm<Eigen::Infinity>());
  const Distance2<n> d = f(x);
  EXPECT_NEAR(d.d2, f(x).d2, 0.0);
  EXPECT_LE((d.hess - d.hess.transpose()).norm(), 1e-14 * (1 + d.hess.norm()));
  Eigen::Matrix<double, n, 1> g_fd;
  Eigen::Matrix<double, n, n> H_fd;
  for (int j = 0; j < n; ++j) {
    Eigen::Matrix<double, n, 1> xp = x, xm = x;
    xp(j) += h;
    xm(j) -= h;
    EXPECT_TRUE(same_case(xp) && same_case(xm)) << "step crosses a case boundary";
    const Distance2<n> dp = f(xp), dm = f(xm);
    g_fd(j) = (dp.d2 - dm.d2) / (2 * h);
    H_fd.col(j) = (dp.grad - dm.grad) / (2 * h);
  }
  FdErrors e;
  e.grad = (d.grad - g_fd).norm() / std::max(d.grad.norm(), 1e-300);
  e.hess = (d.hess - H_fd).norm() / std::max(d.hess.norm(), 1e-300);
  return e;
}

template <int dim>
Eigen::Matrix<double, 3 * dim, 1> stack(const Vec<dim>& a, const Vec<dim>& b, const Vec<dim>& c) {
  Eigen::Matrix<double, 3 * dim, 1> x;
  x << a, b, c;
  return x;
}

template <int dim>
void check_point_edge_derivatives() {
  constexpr int n = 3 * dim;
  auto f = [](const Eigen::Matrix<double, n, 1>& x) {
    return point_edge_distance2_derivatives<dim>(x.template segment<dim>(0), x.template segment<dim>(dim),
                                                 x.template segment<dim>(2 * dim));
  };
  auto kase = [](const Eigen::Matrix<double, n, 1>& x) {
    return point_edge_case<dim>(x.template segment<dim>(0), x.template segment<dim>(dim),
                                x.template segment<dim>(2 * dim));
  };
  // One point per case on a general edge, plus random configurations.
  const Vec<dim> e0 = v<dim>(0.1, -0.2, 0.3), e1 = v<dim>(1.7, 0.4, -0.5);
  std::vector<Eigen::Matrix<double, n, 1>> xs = {
      stack<dim>(v<dim>(-0.8, 0.5, 0.2), e0, e1),  // P_E0
      stack<dim>(v<dim>(2.5, 0.1, 0.4), e0, e1),   // P_E1
      stack<dim>(v<dim>(0.9, 0.9, 0.6), e0, e1),   // P_E
  };
  const PointEdgeCase expected[] = {PointEdgeCase::P_E0, PointEdgeCase::P_E1, PointEdgeCase::P_E};
  std::mt19937 rng(10 + dim);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int i = 0; i < 200; ++i) {
    Eigen::Matrix<double, n, 1> x;
    for (int k = 0; k < n; ++k) x(k) = u(rng);
    xs.push_back(x);
  }
  FdErrors worst[3];
  int tested[3] = {};
  for (size_t i = 0; i < xs.size(); ++i) {
    const PointEdgeCase c = kase(xs[i]);
    if (i < 3) {
      EXPECT_EQ(c, expected[i]);
    }
    const auto same = [&](const Eigen::Matrix<double, n, 1>& y) { return kase(y) == c; };
    // Random samples near a case boundary are skipped, not tested across it.
    bool inside = true;
    for (int j = 0; j < n && i >= 3; ++j)
      for (double sgn : {-1.0, 1.0}) {
        Eigen::Matrix<double, n, 1> y = xs[i];
        y(j) += sgn * 1e-6 * (1 + xs[i].template lpNorm<Eigen::Infinity>());
        inside = inside && same(y);
      }
    if (!inside) continue;
    const FdErrors e = fd_check<n>(xs[i], f, same);
    const int k = static_cast<int>(c);
    ++tested[k];
    worst[k].grad = std::max(worst[k].grad, e.grad);
    worst[k].hess = std::max(worst[k].hess, e.hess);
    // The value of the derivatives struct is the value function's.
    EXPECT_EQ(f(xs[i]).d2, point_edge_distance2<dim>(xs[i].template segment<dim>(0),
                                                     xs[i].template segment<dim>(dim),
                                                     xs[i].template segment<dim>(2 * dim)));
  }
  for (int k = 0; k < 3; ++k) {
    EXPECT_GT(tested[k], 1) << "case " << k;
    EXPECT_LT(worst[k].grad, 1e-6) << "case " << k;
    EXPECT_LT(worst[k].hess, 1e-5) << "case " << k;
    std::printf("point-edge %dD case %d: %d configurations, worst rel. error grad %.2e hess %.2e\n", dim, k,
                tested[k], worst[k].grad, worst[k].hess);
  }
}

TEST(ContactDistance, PointEdgeDerivatives2D) { check_point_edge_derivatives<2>(); }
TEST(ContactDistance, PointEdgeDerivatives3D) { check_point_edge_derivatives<3>(); }

TEST(ContactDistance, PointPointDerivatives) {
  auto f = [](const Eigen::Matrix<double, 6, 1>& x) {
    return point_point_distance2_derivatives<3>(x.segment<3>(0), x.segment<3>(3));
  };
  Eigen::Matrix<double, 6, 1> x;
  x << 0.3, -0.2, 0.9, 1.1, 0.4, -0.7;
  const FdErrors e = fd_check<6>(x, f, [](const auto&) { return true; });
  EXPECT_LT(e.grad, 1e-6);
  EXPECT_LT(e.hess, 1e-5);
  EXPECT_DOUBLE_EQ(f(x).d2, point_point_distance2<3>(x.segment<3>(0), x.segment<3>(3)));
}

using X12 = Eigen::Matrix<double, 12, 1>;

Distance2<12> pt_derivs(const X12& x) {
  return point_triangle_distance2_derivatives(x.segment<3>(0), x.segment<3>(3), x.segment<3>(6), x.segment<3>(9));
}
PointTriangleCase pt_case(const X12& x) {
  return point_triangle_case(x.segment<3>(0), x.segment<3>(3), x.segment<3>(6), x.segment<3>(9));
}
double pt_value(const X12& x) {
  return point_triangle_distance2(x.segment<3>(0), x.segment<3>(3), x.segment<3>(6), x.segment<3>(9));
}

TEST(ContactDistance, PointTriangleDerivatives) {
  // The seven region points on a general (rotated, scaled) triangle, then
  // random configurations.
  const Eigen::Matrix3d R = Eigen::AngleAxisd(-1.1, Vec<3>(0.3, -1, 2).normalized()).toRotationMatrix();
  auto T = [&](const Vec<3>& y) -> Vec<3> { return R * Vec<3>(1.3 * y(0) + 0.4 * y(1), 0.9 * y(1), y(2)); };
  std::vector<X12> xs;
  for (const TriCase& k : triangle_cases()) {
    X12 x;
    x << T(k.p), T(v<3>(0, 0, 0)), T(v<3>(1, 0, 0)), T(v<3>(0, 1, 0));
    EXPECT_EQ(pt_case(x), k.c);
    xs.push_back(x);
  }
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int i = 0; i < 400; ++i) {
    X12 x;
    for (int k = 0; k < 12; ++k) x(k) = u(rng);
    x.segment<3>(0) *= 1.5;
    xs.push_back(x);
  }
  FdErrors worst[7];
  int tested[7] = {};
  for (size_t i = 0; i < xs.size(); ++i) {
    const PointTriangleCase c = pt_case(xs[i]);
    const auto same = [&](const X12& y) { return pt_case(y) == c; };
    bool inside = true;
    for (int j = 0; j < 12 && i >= 7; ++j)
      for (double sgn : {-1.0, 1.0}) {
        X12 y = xs[i];
        y(j) += sgn * 1e-6 * (1 + xs[i].lpNorm<Eigen::Infinity>());
        inside = inside && same(y);
      }
    if (!inside) continue;
    const FdErrors e = fd_check<12>(xs[i], pt_derivs, same);
    const int k = static_cast<int>(c);
    ++tested[k];
    worst[k].grad = std::max(worst[k].grad, e.grad);
    worst[k].hess = std::max(worst[k].hess, e.hess);
    EXPECT_EQ(pt_derivs(xs[i]).d2, pt_value(xs[i]));
  }
  for (int k = 0; k < 7; ++k) {
    EXPECT_GT(tested[k], 1) << "case " << k;
    EXPECT_LT(worst[k].grad, 1e-6) << "case " << k;
    EXPECT_LT(worst[k].hess, 1e-5) << "case " << k;
    std::printf("point-triangle case %d: %d configurations, worst rel. error grad %.2e hess %.2e\n", k, tested[k],
                worst[k].grad, worst[k].hess);
  }
}

// Collinear triangles: the derivatives are those of the nearest edge's
// point-edge case, mapped into the 12-vector (p, t0, t1, t2).
TEST(ContactDistance, PointTriangleDegenerateDerivatives) {
  const Vec<3> a(0, 0, 0), b(1, 0, 0), c(2, 0, 0);
  // On a collinear triangle the long edge contains the short ones, so two
  // edges tie; the first in the order E01, E12, E20 is reported.
  // t = (a, b, c): p over x = 0.3 is nearest to E01 (= E20), over x = 1.6 to
  // E12 (= E20); beyond c it is the vertex t2.
  struct Case {
    Vec<3> p;
    PointTriangleCase c;
    int slot[3];  // triangle stencil slots of the edge stencil (p, ea, eb)
    Vec<3> ea, eb;
  };
  const Case cases[] = {
      {Vec<3>(0.3, 0.7, 0.4), PointTriangleCase::P_E01, {0, 1, 2}, a, b},
      {Vec<3>(1.6, -0.2, 0.5), PointTriangleCase::P_E12, {0, 2, 3}, b, c},
      {Vec<3>(2.5, 0.1, 0.2), PointTriangleCase::P_T2, {0, 2, 3}, b, c},
  };
  for (const Case& k : cases) {
    X12 x;
    x << k.p, a, b, c;
    EXPECT_EQ(pt_case(x), k.c);
    const Distance2<12> d = pt_derivs(x);
    const Distance2<9> e = point_edge_distance2_derivatives<3>(k.p, k.ea, k.eb);
    EXPECT_DOUBLE_EQ(d.d2, e.d2);
    Distance2<12> m;  // the edge derivatives scattered into (p, t0, t1, t2)
    m.grad.setZero();
    m.hess.setZero();
    for (int i = 0; i < 3; ++i) {
      m.grad.segment<3>(3 * k.slot[i]) = e.grad.segment<3>(3 * i);
      for (int j = 0; j < 3; ++j) m.hess.block<3, 3>(3 * k.slot[i], 3 * k.slot[j]) = e.hess.block<3, 3>(3 * i, 3 * j);
    }
    EXPECT_LT((d.grad - m.grad).norm(), 1e-14);
    EXPECT_LT((d.hess - m.hess).norm(), 1e-13);
  }
  // Nearly degenerate triangles and edges: finite derivatives.
  for (double hgt : {1e-6, 1e-9, 1e-14, 0.0}) {
    X12 y;
    y << Vec<3>(0.5, 1e-7, 1e-7), a, b, Vec<3>(0.5, hgt, 0);
    const Distance2<12> dy = pt_derivs(y);
    EXPECT_TRUE(std::isfinite(dy.d2) && dy.grad.allFinite() && dy.hess.allFinite()) << hgt;
    const Distance2<9> de = point_edge_distance2_derivatives<3>(Vec<3>(0.5, 1, 0), a, a + Vec<3>(hgt, 0, 0));
    EXPECT_TRUE(std::isfinite(de.d2) && de.grad.allFinite() && de.hess.allFinite()) << hgt;
  }
}

}  // namespace
