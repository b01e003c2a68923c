// Conservative CCD (kernels/contact/ccd.hpp, additive CCD): analytic times of
// impact (the step must be below the TOI and, for head-on motion, within the
// band additive CCD with s_frac = 0.1 reaches: 0.9 TOI), no-contact motion
// (t_max), and adversarial motion where only conservativeness is asked:
// grazing, parallel edge motion, hitting a vertex exactly, both sides moving,
// displacements that pass through the facet within one step, random motion
// against exactly computed crossing times.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "kernels/contact/ccd.hpp"

namespace {

using namespace bfemp;
using V2 = Vec<2>;
using V3 = Vec<3>;

// Distance of each stencil at time s along its motion.
template <int dim>
double pp_dist(const Vec<dim>& p, const Vec<dim>& q, const Vec<dim>& dp, const Vec<dim>& dq, double s) {
  return std::sqrt(point_point_distance2<dim>(p + s * dp, q + s * dq));
}
template <int dim>
double pe_dist(const Vec<dim>& p, const Vec<dim>& e0, const Vec<dim>& e1, const Vec<dim>& dp,
               const Vec<dim>& de0, const Vec<dim>& de1, double s) {
  return std::sqrt(point_edge_distance2<dim>(p + s * dp, e0 + s * de0, e1 + s * de1));
}
double pt_dist(const V3& p, const V3& t0, const V3& t1, const V3& t2, const V3& dp, const V3& dt0, const V3& dt1,
               const V3& dt2, double s) {
  return std::sqrt(point_triangle_distance2(p + s * dp, t0 + s * dt0, t1 + s * dt1, t2 + s * dt2));
}

// The returned step is in (0, t_max] and the distance is > 0 at it and at
// samples s in [0, t].
template <class Dist>
void expect_safe(double t, double t_max, const Dist& dist, int samples = 1000) {
  EXPECT_GT(t, 0.0);
  EXPECT_LE(t, t_max);
  EXPECT_GT(dist(t), 0.0) << "distance 0 at the returned step " << t;
  for (int k = 0; k <= samples; ++k) {
    const double s = t * k / samples;
    ASSERT_GT(dist(s), 0.0) << "distance 0 at s = " << s << " <= t = " << t;
  }
}

// Head-on motion: the distance falls at exactly the bound l_p, so additive
// CCD stops at 0.9 TOI (first advance (1 - 0.1) d0 / l_p, the next one drops
// below 0.1 d0). The band [0.85, 1) TOI holds that; a non-conservative step
// (>= TOI) or a needlessly short one fails.
void expect_band(double t, double toi) {
  EXPECT_LT(t, toi);
  EXPECT_GE(t, 0.85 * toi);
}

TEST(ContactCcd, PointPointHeadOn) {
  const V2 p(0, 0), q(1, 0), dp(1, 0), dq(-1, 0);
  const double t = point_point_ccd<2>(p, q, dp, dq, 1.0);
  expect_band(t, 0.5);
  expect_safe(t, 1.0, [&](double s) { return pp_dist<2>(p, q, dp, dq, s); });
  const V3 a(0, 0, 0), b(0, 0, 3), da(0, 0, 1), db(0, 0, 0);
  const double t3 = point_point_ccd<3>(a, b, da, db, 10.0);
  expect_band(t3, 3.0);
  expect_safe(t3, 10.0, [&](double s) { return pp_dist<3>(a, b, da, db, s); });
}

TEST(ContactCcd, PointEdgeInteriorHeadOn) {
  // 2D: the point falls onto the edge's interior; TOI = 0.5.
  const V2 p(0.3, 1), e0(0, 0), e1(1, 0), dp(0, -2), z(0, 0);
  const double t = point_edge_ccd<2>(p, e0, e1, dp, z, z, 1.0);
  expect_band(t, 0.5);
  expect_safe(t, 1.0, [&](double s) { return pe_dist<2>(p, e0, e1, dp, z, z, s); });
  // 2D, both moving: point down at 1, edge up at 3: TOI = 1 / 4.
  const V2 up(0, 3), down(0, -1);
  const double t2 = point_edge_ccd<2>(p, e0, e1, down, up, up, 1.0);
  expect_band(t2, 0.25);
  expect_safe(t2, 1.0, [&](double s) { return pe_dist<2>(p, e0, e1, down, up, up, s); });
  // 3D: edge along x, point falling in z from 2 at speed 4; TOI = 0.5.
  const V3 q(0.6, 0, 2), a(0, 0, 0), b(1, 0, 0), dq(0, 0, -4), o(0, 0, 0);
  const double t3 = point_edge_ccd<3>(q, a, b, dq, o, o, 1.0);
  expect_band(t3, 0.5);
  expect_safe(t3, 1.0, [&](double s) { return pe_dist<3>(q, a, b, dq, o, o, s); });
}

TEST(ContactCcd, PointTriangleInteriorHeadOn) {
  const V3 p(0.2, 0.3, 1), t0(0, 0, 0), t1(1, 0, 0), t2(0, 1, 0), o(0, 0, 0);
  const V3 dp(0, 0, -1);
  const double t = point_triangle_ccd(p, t0, t1, t2, dp, o, o, o, 1.0);
  expect_band(t, 1.0);
  expect_safe(t, 1.0, [&](double s) { return pt_dist(p, t0, t1, t2, dp, o, o, o, s); });
  // Both moving toward each other: relative speed 4 over distance 1.
  const V3 down(0, 0, -1), up(0, 0, 3);
  const double t2b = point_triangle_ccd(p, t0, t1, t2, down, up, up, up, 1.0);
  expect_band(t2b, 0.25);
  expect_safe(t2b, 1.0, [&](double s) { return pt_dist(p, t0, t1, t2, down, up, up, up, s); });
}

// The point aims exactly at a vertex (the closest feature is that vertex
// along the whole path): TOI = 0.5 in each case.
TEST(ContactCcd, PointHitsVertexExactly) {
  const V2 p(2, 1), e0(0, 0), e1(1, 0), dp(-2, -2), z(0, 0);
  const double t = point_edge_ccd<2>(p, e0, e1, dp, z, z, 1.0);
  expect_band(t, 0.5);
  expect_safe(t, 1.0, [&](double s) { return pe_dist<2>(p, e0, e1, dp, z, z, s); });
  const V3 q(1.5, -0.5, 0.5), t0(0, 0, 0), t1(1, 0, 0), t2(0, 1, 0), o(0, 0, 0), dq(-1, 1, -1);
  const double t3 = point_triangle_ccd(q, t0, t1, t2, dq, o, o, o, 1.0);
  expect_band(t3, 0.5);
  expect_safe(t3, 1.0, [&](double s) { return pt_dist(q, t0, t1, t2, dq, o, o, o, s); });
  // The point runs along the edge's line into its endpoint.
  const V2 r(3, 0), dr(-4, 0);
  const double tl = point_edge_ccd<2>(r, e0, e1, dr, z, z, 1.0);
  expect_band(tl, 0.5);
  expect_safe(tl, 1.0, [&](double s) { return pe_dist<2>(r, e0, e1, dr, z, z, s); });
}

TEST(ContactCcd, NoContactReturnsTmax) {
  const V2 p(0.3, 1), e0(0, 0), e1(1, 0), z(0, 0);
  EXPECT_EQ(point_edge_ccd<2>(p, e0, e1, V2(0, 5), z, z, 1.0), 1.0);              // moving away
  EXPECT_EQ(point_edge_ccd<2>(p, e0, e1, z, z, z, 1.0), 1.0);                     // no motion
  EXPECT_EQ(point_edge_ccd<2>(p, e0, e1, V2(3, 7), V2(3, 7), V2(3, 7), 1.0), 1.0);  // common translation
  EXPECT_EQ(point_edge_ccd<2>(p, e0, e1, V2(0, -0.4), z, z, 1.0), 1.0);           // TOI = 2.5 > t_max
  EXPECT_EQ(point_edge_ccd<2>(p, e0, e1, V2(0, -0.4), z, z, 0.5), 0.5);           // t_max honoured
  EXPECT_EQ(point_edge_ccd<2>(V2(-1, 0), e0, e1, V2(0, 1), z, z, 1.0), 1.0);      // passes beside e0
  const V3 q(0.2, 0.3, 1), t0(0, 0, 0), t1(1, 0, 0), t2(0, 1, 0), o(0, 0, 0);
  EXPECT_EQ(point_triangle_ccd(q, t0, t1, t2, V3(2, 2, 0.1), o, o, o, 1.0), 1.0);
  EXPECT_EQ(point_triangle_ccd(V3(2, 2, -0.1), t0, t1, t2, V3(0, 0, 2), o, o, o, 1.0), 1.0);  // beside
  EXPECT_EQ(point_point_ccd<3>(q, t0, V3(1, 0, 0), o, 1.0), 1.0);
}

TEST(ContactCcd, InitialContactReturnsZero) {
  const V2 e0(0, 0), e1(1, 0), z(0, 0);
  EXPECT_EQ(point_edge_ccd<2>(V2(0.5, 0), e0, e1, V2(0, 1), z, z, 1.0), 0.0);
  EXPECT_EQ(point_edge_ccd<2>(e1, e0, e1, z, z, z, 1.0), 0.0);
  const V3 t0(0, 0, 0), t1(1, 0, 0), t2(0, 1, 0), o(0, 0, 0);
  EXPECT_EQ(point_triangle_ccd(V3(0.2, 0.2, 0), t0, t1, t2, V3(0, 0, 1), o, o, o, 1.0), 0.0);
  EXPECT_EQ(point_point_ccd<3>(t1, t1, o, V3(1, 0, 0), 1.0), 0.0);
}

// The point slides parallel to the edge (or triangle) over its interior at a
// small distance: the distance never falls, the whole step is safe. At a tiny
// distance the iteration cap ends the advance early: still > 0 and safe.
TEST(ContactCcd, Grazing) {
  const V2 e0(0, 0), e1(1, 0), z(0, 0);
  for (double h : {1e-2, 1e-4}) {
    const V2 p(0.1, h), dp(0.8, 0);
    EXPECT_EQ(point_edge_ccd<2>(p, e0, e1, dp, z, z, 1.0), 1.0) << h;
  }
  {
    const V2 p(0.1, 1e-9), dp(0.8, 0);
    const double t = point_edge_ccd<2>(p, e0, e1, dp, z, z, 1.0);
    expect_safe(t, 1.0, [&](double s) { return pe_dist<2>(p, e0, e1, dp, z, z, s); });
  }
  // Arriving from beside the edge and grazing it: the distance falls from 0.5
  // to h, below s_frac of the start, so additive CCD stops early (safe, short).
  for (double h : {1e-3, 1e-9}) {
    const V2 p(-0.5, h), dp(2, 0);
    const double t = point_edge_ccd<2>(p, e0, e1, dp, z, z, 1.0);
    expect_safe(t, 1.0, [&](double s) { return pe_dist<2>(p, e0, e1, dp, z, z, s); });
  }
  // Grazing while slowly approaching the line, which it would reach beyond e1.
  {
    const V2 p(-0.5, 1e-3), dp(2, -1e-3 / 0.8);
    const double t = point_edge_ccd<2>(p, e0, e1, dp, z, z, 1.0);
    expect_safe(t, 1.0, [&](double s) { return pe_dist<2>(p, e0, e1, dp, z, z, s); });
  }
  const V3 t0(0, 0, 0), t1(1, 0, 0), t2(0, 1, 0), o(0, 0, 0);
  const V3 q(0.1, 0.3, 1e-4), dq(0.5, 0, 0);
  EXPECT_EQ(point_triangle_ccd(q, t0, t1, t2, dq, o, o, o, 1.0), 1.0);
  const V3 r(-0.2, 0.3, 1e-6), dr(1, 0, 0);
  const double tr = point_triangle_ccd(r, t0, t1, t2, dr, o, o, o, 1.0);
  expect_safe(tr, 1.0, [&](double s) { return pt_dist(r, t0, t1, t2, dr, o, o, o, s); });
}

// Edges translating along their own line next to a point: over the interior
// the distance is constant (t_max); arriving from afar it is safe; closing in
// perpendicularly at the same time, the step stays below the TOI.
TEST(ContactCcd, ParallelEdgeMotion) {
  const V2 z(0, 0), p(0.5, 1e-3), along(4, 0);
  EXPECT_EQ(point_edge_ccd<2>(p, V2(-1, 0), V2(3, 0), z, V2(1, 0), V2(1, 0), 1.0), 1.0);
  const V2 e0(-2, 0), e1(-1, 0);
  const double tf = point_edge_ccd<2>(p, e0, e1, z, along, along, 1.0);
  expect_safe(tf, 1.0, [&](double s) { return pe_dist<2>(p, e0, e1, z, along, along, s); });
  const V2 toward(0, 1e-3 / 0.4);  // the edge's line reaches p at 0.4, when x in [-0.4, 0.6]
  const double t = point_edge_ccd<2>(p, e0, e1, z, along + toward, along + toward, 1.0);
  EXPECT_LT(t, 0.4);
  expect_safe(t, 1.0, [&](double s) { return pe_dist<2>(p, e0, e1, z, along + toward, along + toward, s); });
  // 3D: an edge sliding along itself toward the point, which lies on its line.
  const V3 q(2, 0, 0), a(0, 0, 0), b(1, 0, 0), v(2, 0, 0), o(0, 0, 0);
  const double t3 = point_edge_ccd<3>(q, a, b, o, v, v, 1.0);
  expect_band(t3, 0.5);
  expect_safe(t3, 1.0, [&](double s) { return pe_dist<3>(q, a, b, o, v, v, s); });
}

// Displacements far larger than the gap: the path passes through the facet
// and ends on the other side at a positive distance; checking the end point
// alone would miss the crossing.
TEST(ContactCcd, LargeDisplacementThroughFacet) {
  const V2 p(0.4, 0.1), e0(0, 0), e1(1, 0), dp(0, -100), z(0, 0);
  EXPECT_GT(pe_dist<2>(p, e0, e1, dp, z, z, 1.0), 1.0);
  const double t = point_edge_ccd<2>(p, e0, e1, dp, z, z, 1.0);
  expect_band(t, 1e-3);
  expect_safe(t, 1.0, [&](double s) { return pe_dist<2>(p, e0, e1, dp, z, z, s); });
  const V3 q(0.2, 0.2, 0.1), t0(0, 0, 0), t1(1, 0, 0), t2(0, 1, 0), o(0, 0, 0), dq(0.3, -0.1, -100);
  const V3 up(0, 0, 50);
  const double t3 = point_triangle_ccd(q, t0, t1, t2, dq, up, up, up, 1.0);
  EXPECT_LT(t3, 0.1 / 150);
  expect_safe(t3, 1.0, [&](double s) { return pt_dist(q, t0, t1, t2, dq, up, up, up, s); });
  // A triangle vertex swinging through the point (non-rigid facet motion).
  const V3 r(0.25, 0.25, 0.05), sw(0, 0, 0), dt2(0, 0, 10);  // t2 rises: the plane sweeps past r
  const double ts = point_triangle_ccd(r, t0, t1, t2, sw, sw, sw, dt2, 1.0);
  // The plane through t0, t1, t2(s) contains r when z_r = b2 * 10 s, b2 = 0.25: s = 0.02.
  EXPECT_LT(ts, 0.02);
  expect_safe(ts, 1.0, [&](double s) { return pt_dist(r, t0, t1, t2, sw, sw, sw, dt2, s); });
}

// Random 2D point-edge motion: the true first crossing is a root of the
// quadratic cross(e(t), r(t)) = 0 (e = e1 - e0, r = p - e0, both linear in t)
// with the closest parameter in [0, 1]. The step must stay below it.
TEST(ContactCcd, RandomPointEdge2DAgainstExactCrossing) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  auto rv = [&] { return V2(u(rng), u(rng)); };
  int hits = 0;
  double worst_ratio = 1, mean_ratio = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const V2 p = rv(), e0 = rv(), e1 = rv(), dp = 3 * rv(), de0 = 3 * rv(), de1 = 3 * rv();
    const V2 e = e1 - e0, de = de1 - de0, r = p - e0, dr = dp - de0;
    auto cr = [](const V2& a, const V2& b) { return (long double)a(0) * b(1) - (long double)a(1) * b(0); };
    const long double A = cr(de, dr), B = cr(e, dr) + cr(de, r), C = cr(e, r);
    long double roots[2];
    int nr = 0;
    if (std::abs(A) < 1e-14L) {
      if (std::abs(B) > 0) roots[nr++] = -C / B;
    } else {
      const long double disc = B * B - 4 * A * C;
      if (disc >= 0) {
        const long double sq = std::sqrt(disc);
        roots[nr++] = (-B - sq) / (2 * A);
        roots[nr++] = (-B + sq) / (2 * A);
      }
    }
    std::sort(roots, roots + nr);
    double toi = 2.0;  // none in [0, 1]
    for (int k = 0; k < nr; ++k) {
      const double s = (double)roots[k];
      if (s < 0 || s > 1) continue;
      const V2 es = e + s * de, rs = r + s * dr;
      const double beta = rs.dot(es) / es.squaredNorm();
      if (beta >= 0 && beta <= 1) {
        toi = s;
        break;
      }
    }
    const double t = point_edge_ccd<2>(p, e0, e1, dp, de0, de1, 1.0);
    const auto dist = [&](double s) { return pe_dist<2>(p, e0, e1, dp, de0, de1, s); };
    expect_safe(t, 1.0, dist, 200);
    if (toi <= 1) {
      ++hits;
      ASSERT_LT(t, toi) << "trial " << trial;
      worst_ratio = std::min(worst_ratio, t / toi);
      mean_ratio += t / toi;
    }
  }
  EXPECT_GT(hits, 100);
  std::printf("random 2D point-edge: %d crossings, t/TOI worst %.3f mean %.3f\n", hits, worst_ratio,
              mean_ratio / hits);
}

// Random 3D point-triangle motion: the first crossing of the moving plane
// with p inside the triangle, found by dense sampling of the signed plane
// distance (a cubic in t) and bisection. The step must stay below it.
TEST(ContactCcd, RandomPointTriangleAgainstCrossing) {
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> u(-1, 1);
  auto rv = [&] { return V3(u(rng), u(rng), u(rng)); };
  int hits = 0;
  for (int trial = 0; trial < 1000; ++trial) {
    const V3 p = rv(), t0 = rv(), t1 = rv(), t2 = rv();
    const V3 dp = 3 * rv(), d0 = rv(), d1 = rv(), d2 = rv();
    auto signed_plane = [&](double s) {
      const V3 a = t0 + s * d0, b = t1 + s * d1, c = t2 + s * d2, q = p + s * dp;
      return (q - a).dot((b - a).cross(c - a));
    };
    double toi = 2.0;
    const int n = 4000;
    for (int k = 0; k < n && toi > 1; ++k) {
      double lo = double(k) / n, hi = double(k + 1) / n;
      if ((signed_plane(lo) > 0) == (signed_plane(hi) > 0)) continue;
      for (int it = 0; it < 60; ++it) {
        const double mid = 0.5 * (lo + hi);
        ((signed_plane(lo) > 0) == (signed_plane(mid) > 0) ? lo : hi) = mid;
      }
      const double s = 0.5 * (lo + hi);
      const V3 q = p + s * dp, a = t0 + s * d0, b = t1 + s * d1, c = t2 + s * d2;
      const Vec<2> bc = point_triangle_closest_barycentric(q, a, b, c);
      if (point_triangle_case(q, a, b, c) == PointTriangleCase::P_T || (bc(0) > 0 && bc(1) > 0 && bc.sum() < 1))
        if (point_triangle_distance2(q, a, b, c) < 1e-20) toi = s;
    }
    const double t = point_triangle_ccd(p, t0, t1, t2, dp, d0, d1, d2, 1.0);
    expect_safe(t, 1.0, [&](double s) { return pt_dist(p, t0, t1, t2, dp, d0, d1, d2, s); }, 200);
    if (toi <= 1) {
      ++hits;
      ASSERT_LT(t, toi) << "trial " << trial;
    }
  }
  EXPECT_GT(hits, 20);
  std::printf("random 3D point-triangle: %d crossings\n", hits);
}

// The parameters: a smaller s_frac goes closer to the TOI; an iteration cap
// of 1 returns the first (always safe) advance.
TEST(ContactCcd, Parameters) {
  const V3 p(0.2, 0.3, 1), t0(0, 0, 0), t1(1, 0, 0), t2(0, 1, 0), o(0, 0, 0), dp(0, 0, -1);
  const double t01 = point_triangle_ccd(p, t0, t1, t2, dp, o, o, o, 1.0, 0.01);
  EXPECT_LT(t01, 1.0);
  EXPECT_GT(t01, 0.98);
  const double t1it = point_triangle_ccd(p, t0, t1, t2, dp, o, o, o, 1.0, 0.5, 1);
  EXPECT_NEAR(t1it, 0.5, 1e-15);
}

}  // namespace
