#pragma once
// Line-search inversion bound: the first step alpha > 0 at which a simplex
// with edge matrix T + alpha dT degenerates, i.e. the smallest positive root
// of det(T + alpha dT) (quadratic in 2D, cubic in 3D).
//
// Method. T and dT are scaled by exact powers of two. The coefficients c_k
// (c_0 = det T, c_dim = det dT, mixed determinants between) are built from
// column-mixed determinants; one below its rounding bound (8u times the
// matching mixed permanent) is set to zero, lowering the degree for
// rank-deficient dT. The positive roots of p' (stable quadratic formula)
// split (0, inf) into intervals where p is monotone. Sign tests evaluate
// det(T + alpha dT) directly (exact in structured cases such as dT = -s T)
// minus a running bound on its rounding error, so "positive" is certified.
// The first interval end not certified positive brackets the answer, which
// Newton / bisection refines to a few ulps, starting from the closed-form
// root when the degree is <= 2. A tangency (double root) is caught alike.
#include <cmath>
#include <limits>

#include "core/types.hpp"

namespace bfemp {
namespace det_root_detail {

constexpr double kRoundoff = 0.5 * std::numeric_limits<double>::epsilon();  // u

// Cofactor matrix: det M = sum_i M(i, j) C(i, j) for every column j.
template <int dim>
KOKKOS_INLINE_FUNCTION Mat<dim> cofactors(const Mat<dim>& M) {
  Mat<dim> C;
  if constexpr (dim == 2) {
    C(0, 0) = M(1, 1);  C(1, 0) = -M(0, 1);
    C(0, 1) = -M(1, 0); C(1, 1) = M(0, 0);
  } else {
    for (int j = 0; j < 3; ++j) {
      const int a = (j + 1) % 3, b = (j + 2) % 3;  // C.col(j) = M.col(a) x M.col(b)
      C(0, j) = M(1, a) * M(2, b) - M(2, a) * M(1, b);
      C(1, j) = M(2, a) * M(0, b) - M(0, a) * M(2, b);
      C(2, j) = M(0, a) * M(1, b) - M(1, a) * M(0, b);
    }
  }
  return C;
}

template <int dim>
KOKKOS_INLINE_FUNCTION double determinant(const Mat<dim>& M) {
  const Mat<dim> C = cofactors<dim>(M);
  double d = 0.0;
  for (int i = 0; i < dim; ++i) d += M(i, 0) * C(i, 0);
  return d;
}

// Permanent of |M| (bounds the rounding error of the determinant).
template <int dim>
KOKKOS_INLINE_FUNCTION double abs_permanent(const Mat<dim>& M) {
  const Mat<dim> A = M.cwiseAbs();
  if constexpr (dim == 2) {
    return A(0, 0) * A(1, 1) + A(0, 1) * A(1, 0);
  } else {
    return A(0, 0) * (A(1, 1) * A(2, 2) + A(1, 2) * A(2, 1)) +
           A(0, 1) * (A(1, 0) * A(2, 2) + A(1, 2) * A(2, 0)) +
           A(0, 2) * (A(1, 0) * A(2, 1) + A(1, 1) * A(2, 0));
  }
}

// A sufficient test, much cheaper than the polynomial below, that
// det(T + a dT) > 0 for every a in [0, cap]: det(T + a dT) = det T det(I +
// a M) with M = T^-1 dT = adj(T) dT / det T, and I + a M is invertible while
// a ||M|| < 1 in an induced norm, so det(T + a dT) keeps det T's sign. True
// when det T exceeds 16 u perm|T| (so the computed det T is within a third
// of the true one) and cap ||adj(T) dT||_inf <= det T / 2, the norm taken
// with each cofactor's rounding bound (a (dim-1)-determinant: 6 u
// max|T|^(dim-1); 2D's are exact) and the products' added to the
// magnitudes; the factor 2 leaves room for the rest.
// Any finite T, dT, unscaled (scaling them by powers of two would triple
// the cost of a cleared 2D stencil):
// - overflow: a row that overflows is infinite or NaN and answers false (a
//   NaN row at once: a later row must not hide it); det T must be finite
//   (in 3D a cofactor's product may overflow while the permanent, grouped
//   differently, does not: det T = +inf would pass any test against it);
// - underflow makes the rounding bounds absolute: 2^-1075 a product, and in
//   3D a cofactor's is multiplied by T(i, 0), so det T must also exceed
//   2^-1070 max|T| (a five-fold margin); a permanent below 2^-900 is refused,
//   so det T > 2^-949 and, with cap <= 2^64, the products of the norm lose
//   less than 2^-1000, far inside the factor 2.
// (Counterexamples to the versions without the finite-det and the 3D
// absolute term are in the test.) False says nothing (the caller computes
// the root).
template <int dim>
KOKKOS_INLINE_FUNCTION bool positive_up_to(const Mat<dim>& T, const Mat<dim>& dT, double cap) {
  const Mat<dim> C = cofactors<dim>(T);
  double det = 0.0;
  for (int i = 0; i < dim; ++i) det += T(i, 0) * C(i, 0);
  const double perm = abs_permanent<dim>(T);
  const double tmax = T.cwiseAbs().maxCoeff();
  // 3D: a cofactor's underflow (2^-1074), amplified by T(i, 0). Below max|T|
  // = 2^100 it is under 2^-972, inside the margin of 16 u perm > 2^-949;
  // and 2^-1070 max|T| is subnormal there, which would cost 20 ns a call.
  const double lost = dim == 3 && tmax > 0x1p100 ? 0x1p-1070 * tmax : 0.0;
  if (!(perm > 0x1p-900) || !(det > 16.0 * kRoundoff * perm + lost) || !(det < 0x1p1023)) return false;
  const double e = 6.0 * kRoundoff * (dim == 2 ? tmax : tmax * tmax);
  double norm = 0.0;  // ||adj(T) dT||_inf, adj(T)(i, k) = C(k, i)
  for (int i = 0; i < dim; ++i) {
    double row = 0.0;
    for (int j = 0; j < dim; ++j) {
      double v = 0.0, err = 0.0;
      for (int k = 0; k < dim; ++k) {
        v += C(k, i) * dT(k, j);
        err += (e + 4.0 * kRoundoff * std::abs(C(k, i))) * std::abs(dT(k, j));
      }
      row += std::abs(v) + err;
    }
    if (std::isnan(row)) return false;
    norm = row > norm ? row : norm;  // (no NaN here; std::fmax may be a call)
  }
  return cap <= 0x1p64 && cap * norm <= 0.5 * det;  // (false when cap * norm overflows)
}

// det(T + a dT) = sum_k c[k] a^k, with T and dT already scaled to O(1).
template <int dim>
struct DetPolynomial {
  Mat<dim> T, dT;
  double c[4] = {0.0, 0.0, 0.0, 0.0};

  KOKKOS_INLINE_FUNCTION DetPolynomial(const Mat<dim>& T_, const Mat<dim>& dT_) : T(T_), dT(dT_) {
    double bound[4] = {0.0, 0.0, 0.0, 0.0};
    for (int mask = 0; mask < (1 << dim); ++mask) {  // column j from dT iff bit j
      Mat<dim> M;
      int k = 0;
      for (int j = 0; j < dim; ++j) {
        const bool from_dT = (mask >> j) & 1;
        M.col(j) = from_dT ? dT.col(j) : T.col(j);
        k += from_dT;
      }
      c[k] += determinant<dim>(M);
      bound[k] += abs_permanent<dim>(M);
    }
    for (int k = 1; k <= dim; ++k)
      if (std::abs(c[k]) <= 8.0 * kRoundoff * bound[k]) c[k] = 0.0;
  }

  // det(T + a dT) evaluated directly, minus a bound on the rounding error of
  // that evaluation (cofactor and sum rounding through the permanent of |M|,
  // entry rounding through the cofactors and higher-order terms): a positive
  // value certifies det(T + a dT) > 0.
  KOKKOS_INLINE_FUNCTION double certified(double a) const {
    Mat<dim> M, W;
    for (int j = 0; j < dim; ++j)
      for (int i = 0; i < dim; ++i) {
        const double s = a * dT(i, j);
        M(i, j) = T(i, j) + s;
        W(i, j) = std::abs(T(i, j)) + std::abs(s);
      }
    const Mat<dim> C = cofactors<dim>(M);
    double d = 0.0;
    for (int i = 0; i < dim; ++i) d += M(i, 0) * C(i, 0);
    // Entry errors |E| <= 2u W: det M - det(M - E) has first-order terms
    // sum |E||C|, then terms with two columns of E (and one of M), det E.
    const double u = kRoundoff;
    double higher = 16.0 * u * u * abs_permanent<dim>(W);
    if constexpr (dim == 3) {
      double mixed = 0.0;
      for (int l = 0; l < 3; ++l) {
        Mat<dim> Wl = W;
        Wl.col(l) = M.col(l);
        mixed += abs_permanent<dim>(Wl);
      }
      higher = 16.0 * u * u * mixed + 128.0 * u * u * u * abs_permanent<dim>(W);
    }
    return d - (8.0 * u * (abs_permanent<dim>(M) + W.cwiseProduct(C.cwiseAbs()).sum()) + higher);
  }

  KOKKOS_INLINE_FUNCTION double slope(double a) const {
    return c[1] + a * (2.0 * c[2] + a * 3.0 * c[3]);
  }

  // Positive roots of p' in ascending order; returns how many (0..2).
  KOKKOS_INLINE_FUNCTION int critical_points(double x[2]) const {
    const double A = 3.0 * c[3], B = 2.0 * c[2], C = c[1], disc = B * B - 4.0 * A * C;
    double r[2] = {-1.0, -1.0};
    if (A == 0.0) {
      if (B != 0.0) r[0] = -C / B;
    } else if (disc >= 0.0) {
      const double q = -0.5 * (B + std::copysign(std::sqrt(disc), B));
      r[0] = q / A;
      r[1] = q != 0.0 ? C / q : 0.0;
    }
    if (r[1] < r[0]) { const double t = r[0]; r[0] = r[1]; r[1] = t; }
    int n = 0;
    for (double ri : r)
      if (ri > 0.0 && std::isfinite(ri)) x[n++] = ri;
    return n;
  }

  // Closed-form start when the effective degree is <= 2: smallest positive
  // root of c0 + c1 a + c2 a^2 by the stable quadratic formula, else NaN.
  KOKKOS_INLINE_FUNCTION double quadratic_guess() const {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    if (c[3] != 0.0) return nan;
    if (c[2] == 0.0) return c[1] != 0.0 ? -c[0] / c[1] : nan;
    const double disc = c[1] * c[1] - 4.0 * c[2] * c[0];
    if (disc < 0.0) return nan;
    const double q = -0.5 * (c[1] + std::copysign(std::sqrt(disc), c[1]));
    const double r1 = q / c[2], r2 = q != 0.0 ? c[0] / q : nan;
    return r1 > 0.0 && (!(r2 > 0.0) || r1 < r2) ? r1 : r2;
  }

  KOKKOS_INLINE_FUNCTION static double middle(double lo, double hi) {
    return (lo > 0.0 && hi > 8.0 * lo) ? std::sqrt(lo) * std::sqrt(hi) : 0.5 * (lo + hi);
  }

  // h = certified(), h(lo) > 0 >= h(hi). Newton from the best point while its
  // step is large (bisection if it leaves the bracket or the bracket has not
  // halved in two steps); then aim just across the Newton estimate, doubling
  // the offset while probes land on the same side (h is flat or noisy within
  // a few ulps of the crossing). Returns the final lo, where h is positive.
  KOKKOS_INLINE_FUNCTION double refine(double lo, double h_lo, double hi, double h_hi) const {
    double x = quadratic_guess();
    if (!(x > lo && x < hi)) x = lo + (hi - lo) * (h_lo / (h_lo - h_hi));  // regula falsi
    if (!(x > lo && x < hi)) x = middle(lo, hi);
    double best_x = x, best_h = std::numeric_limits<double>::infinity();
    double width1 = 2.0 * (hi - lo), width2 = width1, probe = 0.0;
    for (int it = 0; it < 400; ++it) {
      const double hx = certified(x);
      if ((hx > 0.0) != (best_h > 0.0)) probe = 0.0;  // landed across
      if (hx > 0.0) lo = x; else hi = x;
      if (std::abs(hx) <= std::abs(best_h)) { best_x = x; best_h = hx; }
      const double tol = 2.0 * kRoundoff * hi, width = hi - lo;
      if (width <= 2.0 * tol) break;
      const double step = best_h / slope(best_x), estimate = best_x - step;
      if (std::abs(step) < 0.25 * width) {
        probe = probe > 0.0 ? 2.0 * probe : tol;
        x = best_h > 0.0 ? std::fmax(estimate, lo) + probe : std::fmin(estimate, hi) - probe;
      } else {
        x = width > 0.5 * width2 ? middle(lo, hi) : estimate;
      }
      if (!(x > lo && x < hi)) x = middle(lo, hi);
      width2 = width1;
      width1 = width;
    }
    return lo;
  }

  // cap (> 0, or inf): inf as soon as p is certified positive on [0, cap].
  KOKKOS_INLINE_FUNCTION double smallest_positive_root(double cap = std::numeric_limits<double>::infinity()) const {
    constexpr double inf = std::numeric_limits<double>::infinity();
    double prev = 0.0, h_prev = certified(0.0);
    if (!(h_prev > 0.0)) return 0.0;  // det T <= 0 up to rounding
    int n = dim;
    while (n > 0 && c[n] == 0.0) --n;
    if (n == 0) return inf;
    // p is monotone between critical points: the first right end where
    // positivity is no longer certified brackets the root (or a tangency).
    // Once cap lies within a monotone piece whose left end is certified
    // positive, p certified positive at cap too clears [0, cap].
    double x[2];
    const int nx = critical_points(x);
    for (int i = 0; i < nx; ++i) {
      if (x[i] > cap && certified(cap) > 0.0) return inf;
      const double hx = certified(x[i]);
      if (hx <= 0.0) return refine(prev, h_prev, x[i], hx);
      prev = x[i];
      h_prev = hx;
    }
    if (cap > prev && cap < inf && certified(cap) > 0.0) return inf;
    // Monotone on (prev, inf): a root exists iff p -> -inf.
    if (c[n] > 0.0) return inf;
    double bound = 0.0;  // Fujiwara: every root has |a| <= bound
    for (int k = 0; k < n; ++k)
      bound = std::fmax(bound, 2.0 * std::pow(std::abs(c[k] / c[n]), 1.0 / (n - k)));
    double hi = 2.0 * std::fmax(bound, prev);
    for (int it = 0; it < 64 && std::isfinite(hi); ++it, hi *= 4.0) {
      const double h_hi = certified(hi);
      if (h_hi <= 0.0) return refine(prev, h_prev, hi, h_hi);
    }
    return inf;
  }
};

}  // namespace det_root_detail

// Smallest alpha > 0 with det(T + alpha dT) = 0, for T = (x1-x0, x2-x0, ...)
// the edge matrix of a simplex and dT the same built from the search
// direction (det T > 0 expected). Returns:
//   +infinity  if det(T + alpha dT) > 0 for every alpha > 0 (never inverts),
//              or the only roots lie beyond the double range;
//   0          if T or dT are not finite, or det T is not positive beyond
//              rounding (already inverted or degenerate);
//   otherwise  alpha* <= the smallest positive root, where det(T + alpha* dT)
//              is still certified positive: below a simple root by about u
//              times its condition number; at a double/triple root, the start
//              of the band where det is zero within rounding (generic data:
//              up to ~sqrt(u) relative for a double root).
//
// cap (optional, > 0): +infinity also when det(T + alpha dT) is certified
// positive for every alpha in [0, cap], whatever lies beyond (a caller that
// never steps past cap needs no root there; the root's refinement is most of
// the cost). Certified first by det_root_detail::positive_up_to, then by the
// polynomial's sign tests.
template <int dim>
KOKKOS_INLINE_FUNCTION double smallest_positive_det_root(const Mat<dim>& T, const Mat<dim>& dT,
                                                         double cap = std::numeric_limits<double>::infinity()) {
  constexpr double inf = std::numeric_limits<double>::infinity();
  const double t_max = T.cwiseAbs().maxCoeff(), d_max = dT.cwiseAbs().maxCoeff();
  if (!T.allFinite() || !dT.allFinite() || t_max == 0.0) return 0.0;
  if (d_max == 0.0) {  // det T itself, certified on T scaled to O(1) (a rare call: the scaling's cost is no matter)
    int et = 0;
    std::frexp(t_max, &et);
    return det_root_detail::positive_up_to<dim>(std::ldexp(1.0, -et) * T, Mat<dim>::Zero(), 1.0) ? inf : 0.0;
  }
  // Most stencils of a Newton step: dT small against T, cleared to cap
  // without the polynomial (its eight mixed determinants and permanents).
  // Raw T and dT: scaling them first took a cleared 2D stencil from 11 to 32
  // ns, and even a range test before the call cost 5 ns (perf/bench_det_root).
  if (cap < inf && det_root_detail::positive_up_to<dim>(T, dT, cap)) return inf;
  int et = 0, ed = 0;
  std::frexp(t_max, &et), std::frexp(d_max, &ed);
  // det(T + a dT) = 2^(dim et) det(Ts + beta dTs) with beta = a 2^(ed - et).
  const Mat<dim> Ts = std::ldexp(1.0, -et) * T, dTs = std::ldexp(1.0, -ed) * dT;
  const double cap_s = std::ldexp(cap, ed - et);
  const det_root_detail::DetPolynomial<dim> p(Ts, dTs);
  return std::ldexp(p.smallest_positive_root(cap_s), et - ed);
}

}  // namespace bfemp
