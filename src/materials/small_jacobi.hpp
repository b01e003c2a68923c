#pragma once
// Fixed-size Jacobi methods for d x d matrices (d = 2, 3), without the
// tridiagonal QR iteration of Eigen's solvers (which costs most of a projected
// neo-Hookean tangent).
//
// One-sided Jacobi SVD (Hestenes): plane rotations J(p, q, theta) applied on
// the right of F until its columns are mutually orthogonal,
//   F V = [f_1 .. f_d],  f_p . f_q = 0 (p != q),
// so F = U diag(s) V^T with s_i = |f_i| and u_i = f_i / s_i. A pair (p, q)
// with a = |f_p|^2, b = |f_q|^2, g = f_p . f_q is rotated by
//   zeta = (b - a) / (2 g),  t = sign(zeta) / (|zeta| + sqrt(1 + zeta^2)),
//   c = 1 / sqrt(1 + t^2),   s = c t,
//   f_p <- c f_p - s f_q,     f_q <- s f_p + c f_q,
// which zeroes their inner product; it is skipped once |g| <= tol sqrt(a b).
// No F^T F is formed, so the method is backward stable: each singular value
// carries an error of a few eps s_max (an eigensolve of F^T F: eps s_max^2 /
// s_min), and a near-inverted F needs no other path. V is a product of
// rotations, det V = +1; with det F > 0, det U = +1 too.
// Precondition: F has full rank (s_i > 0); the order of s is unspecified.
//
// Two-sided (cyclic) Jacobi for a symmetric A: rotations J^T A J zero one
// off-diagonal entry each, with the same t as above from
// zeta = (a_qq - a_pp) / (2 a_pq); A = W diag(lambda) W^T at the end.
// Converges quadratically; a 3x3 needs 3-5 sweeps of 3 rotations.
#include <Kokkos_Core.hpp>
#include <cmath>

#include "core/types.hpp"

namespace bfemp {

// Cap on sweeps (never reached in the tests: at most 6).
constexpr int max_jacobi_sweeps = 20;

// tan of the Jacobi angle for zeta (see above), overflow-safe for huge zeta.
KOKKOS_INLINE_FUNCTION double jacobi_tangent(double zeta) {
  const double az = std::fabs(zeta);
  const double t = az > 1e150 ? 0.5 / az : 1.0 / (az + std::sqrt(1.0 + az * az));
  return zeta >= 0.0 ? t : -t;
}

// F = U diag(s) V^T, det U = det V = 1 when det F > 0 (see above).
// Returns the sweeps made (the last one finds nothing to rotate; 3-5 in 3D).
template <int dim>
KOKKOS_INLINE_FUNCTION int jacobi_svd(const Mat<dim>& F, Mat<dim>& U, Vec<dim>& s, Mat<dim>& V) {
  constexpr double tol = 1e-15;
  // Work on F / max|F_ij| (the squares below neither overflow nor underflow).
  double fmax = 0;
  for (int j = 0; j < dim; ++j)
    for (int i = 0; i < dim; ++i) fmax = std::fmax(fmax, std::fabs(F(i, j)));
  U = F / fmax;  // its columns become the f_i
  V.setIdentity();
  // a and b are recomputed for every pair: tracking them as a - t g, b + t g
  // loses s_min^2 to cancellation once s_min / s_max nears 1e-8.
  int sweep = 0;
  while (sweep < max_jacobi_sweeps) {
    ++sweep;
    bool rotated = false;
    for (int p = 0; p < dim - 1; ++p)
      for (int q = p + 1; q < dim; ++q) {
        double a = 0, b = 0, g = 0;
        for (int r = 0; r < dim; ++r) {
          a += U(r, p) * U(r, p);
          b += U(r, q) * U(r, q);
          g += U(r, p) * U(r, q);
        }
        if (!(g * g > tol * tol * (a * b))) continue;
        rotated = true;
        // t = sign(zeta) / (|zeta| + sqrt(1 + zeta^2)) with zeta = (b - a) / (2 g),
        // multiplied through by 2 |g| (one division, no overflow).
        const double d = b - a, ag = 2.0 * std::fabs(g);
        const double tm = ag / (std::fabs(d) + std::sqrt(d * d + ag * ag));
        const double t = (d >= 0.0) == (g >= 0.0) ? tm : -tm;
        const double c = 1.0 / std::sqrt(1.0 + t * t), sn = c * t;
        for (int r = 0; r < dim; ++r) {
          const double up = U(r, p), uq = U(r, q);
          U(r, p) = c * up - sn * uq;
          U(r, q) = sn * up + c * uq;
          const double vp = V(r, p), vq = V(r, q);
          V(r, p) = c * vp - sn * vq;
          V(r, q) = sn * vp + c * vq;
        }
      }
    if (!rotated) break;
  }
  for (int i = 0; i < dim; ++i) {
    const double ni = U.col(i).norm();
    U.col(i) /= ni;
    s(i) = ni * fmax;
  }
  return sweep;
}

// Symmetric A = W diag(lambda) W^T by cyclic Jacobi (precondition: A
// exactly symmetric; both triangles are read). Returns the sweeps made.
template <int dim>
KOKKOS_INLINE_FUNCTION int jacobi_symmetric_eigen(const Mat<dim>& A_in, Vec<dim>& lambda, Mat<dim>& W) {
  Mat<dim> A = A_in;
  W.setIdentity();
  const double scale = A.norm();
  int sweep = 0;
  while (sweep < max_jacobi_sweeps) {
    ++sweep;
    bool rotated = false;
    for (int p = 0; p < dim - 1; ++p)
      for (int q = p + 1; q < dim; ++q) {
        const double apq = A(p, q);
        if (!(std::fabs(apq) > 1e-17 * scale)) continue;
        rotated = true;
        const double t = jacobi_tangent((A(q, q) - A(p, p)) / (2.0 * apq));
        const double c = 1.0 / std::sqrt(1.0 + t * t), sn = c * t;
        // A <- J^T A J, J the rotation in the (p, q) plane (columns as above).
        for (int r = 0; r < dim; ++r) {
          const double arp = A(r, p), arq = A(r, q);
          A(r, p) = c * arp - sn * arq;
          A(r, q) = sn * arp + c * arq;
        }
        for (int r = 0; r < dim; ++r) {
          const double apr = A(p, r), aqr = A(q, r);
          A(p, r) = c * apr - sn * aqr;
          A(q, r) = sn * apr + c * aqr;
        }
        A(p, q) = A(q, p) = 0.0;
        for (int r = 0; r < dim; ++r) {
          const double wp = W(r, p), wq = W(r, q);
          W(r, p) = c * wp - sn * wq;
          W(r, q) = sn * wp + c * wq;
        }
      }
    if (!rotated) break;
  }
  for (int i = 0; i < dim; ++i) lambda(i) = A(i, i);
  return sweep;
}

// True when the symmetric d x d A is positive definite: every pivot of its
// Cholesky factorisation > 0 (a singular PSD A is not).
template <int dim>
KOKKOS_INLINE_FUNCTION bool cholesky_positive_definite(const Mat<dim>& A) {
  Mat<dim> L = Mat<dim>::Zero();
  for (int j = 0; j < dim; ++j) {
    double d = A(j, j);
    for (int k = 0; k < j; ++k) d -= L(j, k) * L(j, k);
    if (!(d > 0.0)) return false;
    L(j, j) = std::sqrt(d);
    for (int i = j + 1; i < dim; ++i) {
      double v = A(i, j);
      for (int k = 0; k < j; ++k) v -= L(i, k) * L(j, k);
      L(i, j) = v / L(j, j);
    }
  }
  return true;
}

}  // namespace bfemp
