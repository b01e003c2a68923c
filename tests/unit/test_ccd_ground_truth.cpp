// point_triangle_ccd (kernels/contact/ccd.hpp) on the 3085 vertex-face CCD
// queries with exact ground truth of ../shared/data/ccd-queries/ (Wang et al.
// 2021; format and conversion in tests/common/ccd_queries.hpp). The CCD
// returns a conservative step bound t in [0, t_max] (t_max = 1: no contact
// found; 0: touching already). Asserted:
//  * no false negative: ground truth 1 -> t < 1;
//  * no step at or past the time of impact: for every ground-truth-1 query
//    t < L, where L is a certified lower bound of the exact earliest time of
//    impact computed here by an independent method (below), or t = 0 where
//    the TOI is 0;
// reported: the conservative false positives (ground truth 0, t < 1), how
// close the steps come to the TOI, and the CCD's time per query (mean and
// worst; informational, see perf/bench_ccd for the benchmark).
//
// The reference TOI (inclusion-based root finding, as in Wang et al.'s
// exact-enclosure CCD): contact at time t means p(t) = (1-u-v) a(t) + u b(t)
// + v c(t) for some u, v >= 0, u + v <= 1, i.e. F(t, u, v) = 0 with
//   F = beta_p x_p(t) + sum_i beta_i x_i(t),  beta_p = 1, beta_a = -(1-u-v), beta_b = -u, beta_c = -v,
// each vertex moving linearly. Every component of F is affine in each of t,
// u, v separately (multilinear), so its exact range over a box [t0,t1] x
// [u0,u1] x [v0,v1] is the hull of its values at the 8 corners. The corner
// values are evaluated in long double at dyadic corners (exact inputs) with a
// rigorous rounding bound (16 LDBL_EPSILON times the sum of the magnitudes of
// the 8 products; the true error is below 5 LDBL_EPSILON times that sum), so a
// box is excluded only when some component of F is certainly nonzero on it
// (or u0 + v0 > 1). Boxes are refined best-first by t0 (smallest first),
// splitting the widest side, down to widths 2^-40 in t, u and v. The t0 of the
// first box that reaches that size without being excluded is L: every time
// below L lies in excluded boxes, so L <= TOI holds exactly (not only up to
// round-off), and L is within 2^-40 (~1e-12) of a time at which some point
// (u, v) within 2^-40 of the triangle makes |F| smaller than F's variation
// over such a box, i.e. L is the TOI to ~1e-12 unless the motion nearly
// touches earlier than it touches. With a budget of box evaluations spent,
// the smallest t0 left is returned: still a lower bound, only a looser one.
// Two motions are checked: the exact one of the query, x(t) = (1-t) x0 + t x1,
// and the one the CCD is given, x0 + t fl(x1 - x0) (1007 of the 37020
// displacement components are not exact in double).
#include <gtest/gtest.h>

#include <algorithm>
#include <cfloat>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <queue>
#include <vector>

#include "common/ccd_queries.hpp"
#include "kernels/contact/ccd.hpp"

namespace {

using namespace bfemp;
using ccd_queries::Query;
using LD = long double;

static_assert(LDBL_MANT_DIG >= 53, "long double must be at least double");

// x(t) = tau0(t) Y0 + tau1(t) Y1 per vertex: the exact query ((1 - t) x0 +
// t x1) or the CCD's motion (x0 + t dx).
struct Motion {
  bool affine_form;  // true: (1 - t) Y0 + t Y1; false: Y0 + t Y1
  LD Y0[4][3], Y1[4][3];
};

Motion exact_motion(const Query& q) {
  Motion m{true, {}, {}};
  for (int i = 0; i < 4; ++i)
    for (int c = 0; c < 3; ++c) {
      m.Y0[i][c] = q.x0[i][c];
      m.Y1[i][c] = q.x1[i][c];
    }
  return m;
}

Motion ccd_motion(const Query& q) {
  Motion m{false, {}, {}};
  for (int i = 0; i < 4; ++i)
    for (int c = 0; c < 3; ++c) {
      m.Y0[i][c] = q.x0[i][c];
      m.Y1[i][c] = q.x1[i][c] - q.x0[i][c];  // the double the CCD receives
    }
  return m;
}

struct Box {
  LD t0, t1, u0, u1, v0, v1;
};

// Corner values of F and their rounding bounds.
void corner(const Motion& m, LD t, LD u, LD v, LD val[3], LD err[3]) {
  const LD tau0 = m.affine_form ? 1 - t : LD(1), tau1 = t;  // 1 - t exact: t dyadic, few bits
  const LD w = 1 - u - v;                                    // exact likewise
  const LD beta[4] = {1, -w, -u, -v};
  for (int c = 0; c < 3; ++c) {
    LD s = 0, mag = 0;
    for (int i = 0; i < 4; ++i) {
      const LD a = (beta[i] * tau0) * m.Y0[i][c];
      const LD b = (beta[i] * tau1) * m.Y1[i][c];
      s += a;
      s += b;
      mag += std::fabs(a) + std::fabs(b);
    }
    val[c] = s;
    err[c] = 16 * LDBL_EPSILON * mag + LDBL_MIN;
  }
}

// The triangle's normal at time t (double; any vector gives a valid test).
void normal_at(const Motion& m, double t, double n[3]) {
  double x[4][3];
  for (int i = 0; i < 4; ++i)
    for (int c = 0; c < 3; ++c)
      x[i][c] = static_cast<double>(m.affine_form ? (1 - t) * m.Y0[i][c] + t * m.Y1[i][c] : m.Y0[i][c] + t * m.Y1[i][c]);
  double e1[3], e2[3];
  for (int c = 0; c < 3; ++c) {
    e1[c] = x[2][c] - x[1][c];
    e2[c] = x[3][c] - x[1][c];
  }
  n[0] = e1[1] * e2[2] - e1[2] * e2[1];
  n[1] = e1[2] * e2[0] - e1[0] * e2[2];
  n[2] = e1[0] * e2[1] - e1[1] * e2[0];
  const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  for (int c = 0; c < 3; ++c) n[c] = len > 0 ? n[c] / len : 0.0;
}

// True when F certainly has no zero on the box: one of its x, y, z
// components, or its component along the triangle's normal at the box's
// middle time (which separates grazing motion at a small distance from the
// plane without refining the box down to that distance), keeps one sign.
bool excluded(const Motion& m, const Box& b) {
  if (b.u0 + b.v0 > 1) return true;
  double n[3];
  normal_at(m, static_cast<double>((b.t0 + b.t1) / 2), n);
  LD lo[4], hi[4];
  for (int c = 0; c < 4; ++c) {
    lo[c] = INFINITY;
    hi[c] = -INFINITY;
  }
  for (int k = 0; k < 8; ++k) {
    LD val[4], err[4];
    corner(m, k & 1 ? b.t1 : b.t0, k & 2 ? b.u1 : b.u0, k & 4 ? b.v1 : b.v0, val, err);
    // n . F: the components' bounds carried through, plus the rounding of
    // the three products and two sums (< 3 LDBL_EPSILON sum |n_c val_c|).
    LD g = 0, gmag = 0, gerr = 0;
    for (int c = 0; c < 3; ++c) {
      g += n[c] * val[c];
      gmag += std::fabs(n[c] * val[c]);
      gerr += std::fabs(static_cast<LD>(n[c])) * err[c];
    }
    val[3] = g;
    err[3] = 2 * gerr + 8 * LDBL_EPSILON * gmag + LDBL_MIN;
    for (int c = 0; c < 4; ++c) {
      lo[c] = std::min(lo[c], val[c] - err[c]);
      hi[c] = std::max(hi[c], val[c] + err[c]);
    }
  }
  for (int c = 0; c < 4; ++c)
    if (lo[c] > 0 || hi[c] < 0) return true;
  return false;
}

struct ToiBound {
  bool possible = false;  // false: no root in [0, 1] (all boxes excluded)
  bool resolved = false;  // true: the bound is within ~1e-12 of a near-contact time
  double lower = 1;       // certified lower bound of the earliest TOI (rounded down to double)
  long boxes = 0;
};

ToiBound toi_lower_bound(const Motion& m, long max_boxes) {
  const LD tol = std::ldexp(LD(1), -40);
  auto later = [](const Box& a, const Box& b) {
    if (a.t0 != b.t0) return a.t0 > b.t0;
    return (a.t1 - a.t0) > (b.t1 - b.t0);  // ties: the narrower box first (depth first)
  };
  std::priority_queue<Box, std::vector<Box>, decltype(later)> heap(later);
  heap.push({0, 1, 0, 1, 0, 1});
  ToiBound r;
  while (!heap.empty()) {
    const Box b = heap.top();
    if (r.boxes >= max_boxes) {  // budget spent: the smallest t0 left bounds the TOI
      r.possible = true;
      r.lower = static_cast<double>(b.t0);
      if (static_cast<LD>(r.lower) > b.t0) r.lower = std::nextafter(r.lower, -1.0);
      return r;
    }
    heap.pop();
    ++r.boxes;
    if (excluded(m, b)) continue;
    const LD wt = b.t1 - b.t0, wu = b.u1 - b.u0, wv = b.v1 - b.v0;
    if (wt <= tol && wu <= tol && wv <= tol) {
      r.possible = r.resolved = true;
      r.lower = static_cast<double>(b.t0);  // t0 = k 2^-40: exact in double
      return r;
    }
    Box l = b, h = b;
    if (wt >= wu && wt >= wv) {
      l.t1 = h.t0 = (b.t0 + b.t1) / 2;
    } else if (wu >= wv) {
      l.u1 = h.u0 = (b.u0 + b.u1) / 2;
    } else {
      l.v1 = h.v0 = (b.v0 + b.v1) / 2;
    }
    heap.push(l);
    heap.push(h);
  }
  return r;  // every box excluded: no contact over [0, 1]
}

// Whether fl(a - b) == a - b (Knuth's TwoSum: the rounding error is exactly
// (a - (s - bb)) + (-b - bb) for s = fl(a - b), bb = s - a).
bool subtraction_is_exact(double a, double b) {
  const double s = a - b, bb = s - a;
  return (a - (s - bb)) + (-b - bb) == 0.0;
}

Vec<3> vec(const std::array<double, 3>& a) { return Vec<3>(a[0], a[1], a[2]); }

std::filesystem::path data_dir() { return std::filesystem::path(BFEMP_SOURCE_DIR) / ".." / "shared" / "data" / "ccd-queries"; }

// The exact rational -> nearest double conversion (ties to even).
TEST(CcdGroundTruth, RationalToNearestDouble) {
  using ccd_queries::rational_to_double;
  bool exact = false;
  EXPECT_EQ(rational_to_double("6004799503160661", "36028797018963968", &exact), 6004799503160661.0 / 36028797018963968.0);
  EXPECT_TRUE(exact);
  EXPECT_EQ(rational_to_double("-18765", "562949953421312", &exact), -18765.0 / 562949953421312.0);
  EXPECT_TRUE(exact);
  // 2^111 as the denominator (beyond 64-bit integers).
  EXPECT_EQ(rational_to_double("3", "2596148429267413814265248164610048", &exact), std::ldexp(3.0, -111));
  EXPECT_TRUE(exact);
  EXPECT_EQ(rational_to_double("1", "3", &exact), 1.0 / 3.0);
  EXPECT_FALSE(exact);
  EXPECT_EQ(rational_to_double("0", "7", &exact), 0.0);
  EXPECT_TRUE(exact);
  // Halfway cases round to even: 2^53 + 1 -> 2^53, 2^53 + 3 -> 2^53 + 4.
  EXPECT_EQ(rational_to_double("9007199254740993", "1", &exact), 9007199254740992.0);
  EXPECT_FALSE(exact);
  EXPECT_EQ(rational_to_double("9007199254740995", "1", &exact), 9007199254740996.0);
  // Just above a halfway point: rounds up (the sticky bit).
  EXPECT_EQ(rational_to_double("90071992547409930000000000000001", "10000000000000000", &exact), 9007199254740994.0);
  // IEEE division of exact doubles is correctly rounded: the same answer.
  for (long long n : {1LL, 7LL, 123456789LL, 9007199254740991LL, 4503599627370497LL})
    for (long long d : {3LL, 10LL, 49LL, 1000000007LL, 9007199254740881LL})
      EXPECT_EQ(rational_to_double(std::to_string(n), std::to_string(d)), static_cast<double>(n) / static_cast<double>(d))
          << n << "/" << d;
}

// The reference itself, on queries with a known answer.
TEST(CcdGroundTruth, ReferenceToiOnAnalyticMotions) {
  auto make = [](std::array<double, 3> p0, std::array<double, 3> p1) {
    Query q;
    q.x0 = {p0, std::array<double, 3>{0, 0, 0}, std::array<double, 3>{1, 0, 0}, std::array<double, 3>{0, 1, 0}};
    q.x1 = {p1, q.x0[1], q.x0[2], q.x0[3]};
    return q;
  };
  // Head-on through the interior at t = 0.25 (z: 1 -> -3).
  ToiBound b = toi_lower_bound(exact_motion(make({0.2, 0.3, 1}, {0.2, 0.3, -3})), 1 << 22);
  ASSERT_TRUE(b.possible && b.resolved);
  EXPECT_LE(b.lower, 0.25);
  EXPECT_GT(b.lower, 0.25 - 1e-11);
  // Through the edge u + v = 1 exactly at t = 1/3 (the crossing point (0.5, 0.5, 0)).
  b = toi_lower_bound(exact_motion(make({0.5, 0.5, 1}, {0.5, 0.5, -2})), 1 << 22);
  ASSERT_TRUE(b.possible && b.resolved);
  EXPECT_LE(b.lower, 1.0 / 3);
  EXPECT_GT(b.lower, 1.0 / 3 - 1e-11);
  // Beside the triangle: no contact.
  b = toi_lower_bound(exact_motion(make({0.7, 0.7, 1}, {0.7, 0.7, -1})), 1 << 22);
  EXPECT_FALSE(b.possible);
  // In the plane, sliding into the edge x = 0 at t = 0.5 (x: 0.5 -> -0.5 at y = 0.2).
  b = toi_lower_bound(exact_motion(make({-0.5, 0.2, 0}, {0.5, 0.2, 0})), 1 << 22);
  ASSERT_TRUE(b.possible && b.resolved);
  EXPECT_LE(b.lower, 0.5);
  EXPECT_GT(b.lower, 0.5 - 1e-11);
}

TEST(CcdGroundTruth, VertexFaceQueries) {
  const auto dir = data_dir();
  if (!std::filesystem::is_directory(dir))
    GTEST_SKIP() << "CCD ground-truth data not found at " << dir.string()
                 << " (../shared/data/ccd-queries relative to the repository root)";
  const ccd_queries::QuerySet set = ccd_queries::load_vertex_face_queries(dir);
  ASSERT_EQ(set.queries.size(), 3085u) << "the data set's README says 3085 vertex-face queries (" << set.files
                                       << " files read)";
  // All rationals are exact doubles, so the reference on the doubles is the exact query.
  EXPECT_EQ(set.inexact_conversions, 0u);

  std::size_t positives = 0, negatives = 0, false_neg = 0, false_pos = 0, past_toi = 0, past_toi_ccd_motion = 0;
  std::size_t neg_excluded = 0, neg_near = 0;
  std::size_t toi_zero = 0, unresolved = 0, reference_misses = 0;
  std::vector<double> ratios;  // step / L over the positives with L > 0
  double total_s = 0, worst_s = 0;
  std::string worst_name;
  long max_boxes_used = 0;
  for (const Query& q : set.queries) {
    const std::string name = q.file + " query " + std::to_string(q.index);
    const Vec<3> p = vec(q.x0[0]), a = vec(q.x0[1]), b = vec(q.x0[2]), c = vec(q.x0[3]);
    const Vec<3> dp = vec(q.x1[0]) - p, da = vec(q.x1[1]) - a, db = vec(q.x1[2]) - b, dc = vec(q.x1[3]) - c;
    const auto start = std::chrono::steady_clock::now();
    const double t = point_triangle_ccd(p, a, b, c, dp, da, db, dc, 1.0);
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    total_s += s;
    if (s > worst_s) {
      worst_s = s;
      worst_name = name;
    }
    ASSERT_TRUE(t >= 0 && t <= 1) << name << ": step " << t << " outside [0, 1]";
    const bool hit = t < 1;
    if (q.truth == 0) {
      ++negatives;
      false_pos += hit;
      // The reference against the exact ground truth the other way round: it
      // should exclude the whole of [0, 1] (or find only a near contact).
      const ToiBound ref = toi_lower_bound(exact_motion(q), 1 << 16);
      neg_excluded += !ref.possible;
      neg_near += ref.possible && ref.resolved;
      continue;
    }
    ++positives;
    if (!hit) {
      ++false_neg;
      ADD_FAILURE() << name << ": false negative (ground truth 1, step 1)";
    }
    bool displacements_exact = true;  // then the CCD's motion is the exact one
    for (int i = 0; i < 4; ++i)
      for (int c = 0; c < 3; ++c)
        displacements_exact = displacements_exact && subtraction_is_exact(q.x1[i][c], q.x0[i][c]);
    for (int motion = 0; motion < (displacements_exact ? 1 : 2); ++motion) {
      const ToiBound ref = toi_lower_bound(motion == 0 ? exact_motion(q) : ccd_motion(q), 1 << 22);
      max_boxes_used = std::max(max_boxes_used, ref.boxes);
      if (!ref.possible) {  // the reference contradicts the exact ground truth
        ++reference_misses;
        ADD_FAILURE() << name << ": the reference finds no contact on the "
                      << (motion == 0 ? "exact" : "CCD's") << " motion, ground truth 1";
        continue;
      }
      unresolved += !ref.resolved;
      if (motion == 0) toi_zero += ref.lower == 0;
      const bool safe = t < ref.lower || (t == 0 && ref.lower == 0);
      if (!safe) {
        ++(motion == 0 ? past_toi : past_toi_ccd_motion);
        ADD_FAILURE() << name << ": step " << t << " is not below the certified TOI lower bound " << ref.lower
                      << (ref.resolved ? " (resolved to ~1e-12: at or past the TOI)" : " (unresolved bound)") << " of the "
                      << (motion == 0 ? "exact" : "CCD's") << " motion";
      }
      if (motion == 0 && ref.lower > 0) ratios.push_back(t / ref.lower);
    }
  }
  std::sort(ratios.begin(), ratios.end());
  const double mean_us = 1e6 * total_s / set.queries.size();
  std::printf(
      "CCD ground truth: %zu queries (%zu with contact, %zu without) from %zu files\n"
      "  false negatives %zu, steps at or past the exact TOI %zu (CCD's rounded motion: %zu), "
      "conservative false positives %zu\n"
      "  TOI = 0 (touching at t = 0, step 0 expected): %zu; reference bounds not resolved to 2^-40: %zu; "
      "most boxes for one reference: %ld\n"
      "  reference on the %zu queries without contact: no contact %zu, a near contact within 2^-40 %zu, "
      "undecided within 2^16 boxes %zu\n"
      "  step / TOI lower bound over %zu positives with TOI > 0: min %.3g, median %.3g, max %.3g\n"
      "  time per query (single pass, timer around each call; informational): mean %.2f us, worst %.1f us (%s)\n",
      set.queries.size(), positives, negatives, set.files, false_neg, past_toi, past_toi_ccd_motion, false_pos,
      toi_zero, unresolved, max_boxes_used, negatives, neg_excluded, neg_near,
      negatives - neg_excluded - neg_near, ratios.size(), ratios.empty() ? 0.0 : ratios.front(),
      ratios.empty() ? 0.0 : ratios[ratios.size() / 2], ratios.empty() ? 0.0 : ratios.back(), mean_us, 1e6 * worst_s,
      worst_name.c_str());
  RecordProperty("false_negatives", static_cast<int>(false_neg));
  RecordProperty("past_toi", static_cast<int>(past_toi));
  RecordProperty("false_positives", static_cast<int>(false_pos));
  EXPECT_EQ(positives + negatives, set.queries.size());
  EXPECT_EQ(false_neg, 0u);
  EXPECT_EQ(past_toi, 0u);
  EXPECT_EQ(past_toi_ccd_motion, 0u);
  EXPECT_EQ(reference_misses, 0u);
}

}  // namespace
