#pragma once
// PSD projection of a contact pair's local Hessian in the pair's own range.
//
// A pair's barrier (or any f(d2)) has the local Hessian
//   H = a grad grad^T + b hess,   grad = 2 c (x) w,
//   hess = 2 (c c^T (x) I) - 2 N G^-1 N^T            (kernels/contact/distance.hpp)
// with a, b scalars. Every term maps into the subspace
//   U = span{ c (x) e_k : k < dim } + span{ columns of N }   (r = dim + nb <= dim + 2),
// so with Q (n x r) an orthonormal basis of U,  H = Q M Q^T,  M = Q^T H Q.
// H's eigenvectors with non-zero eigenvalues lie in U, the others are zero,
// so the projection onto the PSD cone (negative eigenvalues lambda set to
// keep lambda, keep in [0, 1)) is  Q proj(M) Q^T:  an r x r eigenproblem
// (2x2 to 5x5) instead of n x n (4x4 to 12x12), with the same result to
// round-off. As project_psd (materials/psd_projection.hpp): when M has no
// negative eigenvalue, H is left bitwise unchanged.
//
// Basis: the dim columns c (x) e_k / |c| are orthonormal by construction;
// each column of N is orthogonalised against the basis so far (Gram-Schmidt
// twice, so that a column nearly inside the span still gives an orthogonal
// direction) and dropped when nothing of it is left (below 1e-13 of its
// norm: its part of H is then at round-off level).
#include <Eigen/Eigenvalues>
#include <Kokkos_Core.hpp>
#include <cmath>

#include "kernels/contact/distance.hpp"

namespace bfemp {

namespace contact_detail {

// H <- Q proj(Q^T H Q) Q^T with Q's first r columns (fixed r).
template <int n, int r, int rmax>
KOKKOS_INLINE_FUNCTION void project_in_basis(const Eigen::Matrix<double, n, rmax>& Qfull, SquareMat<n>& H,
                                             double keep) {
  const Eigen::Matrix<double, n, r> Q = Qfull.template leftCols<r>();
  const Eigen::Matrix<double, n, r> HQ = H * Q;
  SquareMat<r> M = Q.transpose() * HQ;
  M = (0.5 * (M + M.transpose())).eval();
  Eigen::SelfAdjointEigenSolver<SquareMat<r>> es(M);
  Eigen::Matrix<double, r, 1> lam = es.eigenvalues();  // ascending
  if (lam(0) >= 0.0) return;
  for (int i = 0; i < r; ++i) lam(i) = lam(i) > 0.0 ? lam(i) : (keep > 0.0 ? keep * lam(i) : 0.0);
  const Eigen::Matrix<double, n, r> QV = Q * es.eigenvectors();
  H.noalias() = QV * lam.asDiagonal() * QV.transpose();
  H = (0.5 * (H + H.transpose())).eval();
}

}  // namespace contact_detail

// Projects H (the local Hessian of a function of s.d2, see above) in place.
template <int dim, int n>
KOKKOS_INLINE_FUNCTION void project_pair_hessian(const Distance2<n>& s, SquareMat<n>& H, double keep = 0.0) {
  static_assert(n % dim == 0, "n = nv dim");
  constexpr int nv = n / dim;
  constexpr int rmax = dim + 2;
  Eigen::Matrix<double, n, rmax> Q = Eigen::Matrix<double, n, rmax>::Zero();
  double cc = 0;
  for (int i = 0; i < nv; ++i) cc += s.c[i] * s.c[i];
  const double inv = 1.0 / std::sqrt(cc);  // c_0 = 1: |c| >= 1
  for (int k = 0; k < dim; ++k)
    for (int i = 0; i < nv; ++i) Q(i * dim + k, k) = s.c[i] * inv;
  int r = dim;
  for (int l = 0; l < s.nb; ++l) {
    Eigen::Matrix<double, n, 1> v = s.N.col(l);
    const double vn0 = v.norm();
    for (int pass = 0; pass < 2; ++pass)
      for (int m = 0; m < r; ++m) v -= Q.col(m).dot(v) * Q.col(m);
    const double vn = v.norm();
    if (!(vn > 1e-13 * vn0)) continue;
    Q.col(r++) = v / vn;
  }
  if (r == dim) contact_detail::project_in_basis<n, dim, rmax>(Q, H, keep);
  else if (r == dim + 1) contact_detail::project_in_basis<n, dim + 1, rmax>(Q, H, keep);
  else contact_detail::project_in_basis<n, dim + 2, rmax>(Q, H, keep);
}

}  // namespace bfemp
