#pragma once
// Line-search inversion bound: the first step alpha > 0 at which a simplex
// with edge matrix T(alpha) = T + alpha dT degenerates, i.e. the smallest
// positive root of the polynomial det(T + alpha dT) (quadratic in 2D, cubic
// in 3D).
//
// Method. Inputs are first scaled by exact powers of two. The coefficients
// c_k (c_0 = det T, c_dim = det dT, mixed determinants in between) are built
// exactly from column-mixed determinants; a coefficient below its own rounding
// bound (8u times the matching mixed permanent of |T|, |dT|) is set to zero,
// which lowers the degree for rank-deficient dT. The positive roots of p'
// (stable quadratic formula) split (0, inf) into intervals on which p is
// monotone; they are visited in order, and the first one whose right end has
// det <= 0 is refined by safeguarded Newton/bisection down to a few ulps. The
// sign tests evaluate det(T + alpha dT) directly (not the coefficients), which
// keeps structured cases (dT = -s T, diagonal matrices) exact. A local minimum
// whose value lies within the running rounding bound of that evaluation is a
// tangency: the refinement then stops where det drops into that bound.
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

  // det(T + a dT) evaluated directly; `err` receives a bound on its rounding
  // error (entry rounding through the cofactors, cofactor/sum rounding through
  // the permanent, plus second-order terms).
  KOKKOS_INLINE_FUNCTION double eval(double a, double& err) const {
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
    const double u = kRoundoff;
    err = 8.0 * u * (abs_permanent<dim>(M) + W.cwiseProduct(C.cwiseAbs()).sum()) +
          64.0 * u * u * abs_permanent<dim>(W);
    return d;
  }

  KOKKOS_INLINE_FUNCTION double slope(double a) const {
    return c[1] + a * (2.0 * c[2] + a * 3.0 * c[3]);
  }

  // Positive roots of p' in ascending order; returns how many (0..2).
  KOKKOS_INLINE_FUNCTION int critical_points(double x[2]) const {
    const double A = 3.0 * c[3], B = 2.0 * c[2], C = c[1];
    double r[2];
    int m = 0;
    if (A == 0.0) {
      if (B != 0.0) r[m++] = -C / B;
    } else {
      const double disc = B * B - 4.0 * A * C;
      if (disc >= 0.0) {
        const double q = -0.5 * (B + std::copysign(std::sqrt(disc), B));
        r[m++] = q / A;
        r[m++] = q != 0.0 ? C / q : 0.0;
      }
    }
    int n = 0;
    for (int i = 0; i < m; ++i)
      if (r[i] > 0.0 && std::isfinite(r[i])) x[n++] = r[i];
    if (n == 2 && x[1] < x[0]) { const double t = x[0]; x[0] = x[1]; x[1] = t; }
    return n;
  }

  KOKKOS_INLINE_FUNCTION static double middle(double lo, double hi) {
    return (lo > 0.0 && hi > 8.0 * lo) ? std::sqrt(lo) * std::sqrt(hi) : 0.5 * (lo + hi);
  }

  // h(a) = det(T + a dT) (minus its rounding bound if `shifted`) with
  // h(lo) > 0 >= h(hi): safeguarded Newton/bisection; returns the final lo,
  // where h is still positive.
  KOKKOS_INLINE_FUNCTION double refine(double lo, double hi, bool shifted) const {
    double x = middle(lo, hi), width_before = hi - lo;
    for (int it = 0; it < 2000; ++it) {
      double err;
      double h = eval(x, err);
      if (shifted) h -= err;
      if (h > 0.0) lo = x; else hi = x;
      const double width = hi - lo;
      if (width <= 4.0 * kRoundoff * hi) break;
      double xn = x - h / slope(x);
      const double tiny = 2.0 * kRoundoff * hi;
      if (std::abs(xn - x) < tiny) xn = h > 0.0 ? x + tiny : x - tiny;  // straddle the root
      if (!(xn > lo && xn < hi) || width > 0.5 * width_before) xn = middle(lo, hi);
      width_before = width;
      x = xn;
    }
    return lo;
  }

  KOKKOS_INLINE_FUNCTION double smallest_positive_root() const {
    constexpr double inf = std::numeric_limits<double>::infinity();
    double err;
    if (!(eval(0.0, err) > 0.0)) return 0.0;
    int n = dim;
    while (n > 0 && c[n] == 0.0) --n;
    if (n == 0) return inf;
    double x[2];
    const int nx = critical_points(x);
    double prev = 0.0;
    for (int i = 0; i < nx; ++i) {
      const double fx = eval(x[i], err);
      if (fx <= 0.0) return refine(prev, x[i], false);
      if (fx <= err) {  // touches zero within rounding: tangency
        double err_prev;
        const double fp = eval(prev, err_prev);
        return fp > err_prev ? refine(prev, x[i], true) : prev;
      }
      prev = x[i];
    }
    // Monotone on (prev, inf): a root exists iff p -> -inf.
    if (c[n] > 0.0) return inf;
    double bound = 0.0;  // Fujiwara: every root has |a| <= bound
    for (int k = 0; k < n; ++k)
      bound = std::fmax(bound, 2.0 * std::pow(std::abs(c[k] / c[n]), 1.0 / (n - k)));
    double hi = 2.0 * std::fmax(bound, prev);
    for (int it = 0; it < 64 && std::isfinite(hi); ++it, hi *= 4.0)
      if (eval(hi, err) <= 0.0) return refine(prev, hi, false);
    return inf;
  }
};

}  // namespace det_root_detail

// Smallest alpha > 0 with det(T + alpha dT) = 0, for T = (x1-x0, x2-x0, ...)
// the edge matrix of a simplex and dT the same built from the search
// direction. Requires det T > 0.
// Returns:
//   +infinity  if det(T + alpha dT) > 0 for every alpha > 0 (never inverts);
//   0          if det T <= 0, T or dT are not finite, or det T itself is zero
//              within rounding and the polynomial touches zero later;
//   otherwise a value alpha* with det(T + a dT) > 0 on [0, alpha*] up to
//   rounding, at most a few ulps below the computed crossing (never above it);
//   at a tangency (double root) the answer is the start of the interval where
//   det is zero within rounding, i.e. slightly conservative.
template <int dim>
KOKKOS_INLINE_FUNCTION double smallest_positive_det_root(const Mat<dim>& T, const Mat<dim>& dT) {
  if (!T.allFinite() || !dT.allFinite()) return 0.0;
  const double t_max = T.cwiseAbs().maxCoeff(), d_max = dT.cwiseAbs().maxCoeff();
  if (t_max == 0.0) return 0.0;
  if (d_max == 0.0)
    return det_root_detail::determinant<dim>(T) > 0.0 ? std::numeric_limits<double>::infinity()
                                                      : 0.0;
  int et = 0, ed = 0;
  std::frexp(t_max, &et);
  std::frexp(d_max, &ed);
  const det_root_detail::DetPolynomial<dim> poly(std::ldexp(1.0, -et) * T, std::ldexp(1.0, -ed) * dT);
  // det(T + a dT) = 2^(dim et) det(Ts + (a 2^(ed - et)) dTs): a = beta 2^(et - ed).
  return std::ldexp(poly.smallest_positive_root(), et - ed);
}

}  // namespace bfemp
