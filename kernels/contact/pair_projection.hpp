#pragma once
// PSD projection of a contact pair's local Hessian in the pair's own range.
//
// A pair's barrier (or any f(d2)) has the local Hessian
//   H = a grad grad^T + b hess,   grad = 2 c (x) w,
//   hess = 2 (c c^T (x) I) - 2 N G^-1 N^T,  N_k = dc_k (x) w + c (x) u_k
// (kernels/contact/distance.hpp) with a, b scalars. Every term maps into
//   U = span{ c (x) e_k : k < dim } + span{ dc_k (x) w : k < nb }   (r = dim + nb <= dim + 2),
// so with Q (n x r) an orthonormal basis of U,  H = Q M Q^T,  M = Q^T H Q.
// H's eigenvectors with non-zero eigenvalues lie in U, the others are zero,
// so the projection onto the PSD cone (negative eigenvalues lambda set to
// keep lambda, keep in [0, 1)) is  Q proj(M) Q^T:  an r x r eigenproblem
// (2x2 to 5x5) instead of n x n (4x4 to 12x12), equal to round-off
// (tests/unit/test_pair_projection.cpp). As project_psd
// (materials/psd_projection.hpp): when M has no negative eigenvalue, H is
// left bitwise unchanged.
//
// Basis, built in the nv stencil coefficients (no cancellation in the
// positions): the dim columns c (x) e_k / |c|, then b_l (x) w / |w| with b_l
// the dc_k orthogonalised against c and each other (Gram-Schmidt twice), so
// that (c (x) e_k).(b_l (x) w) = (c.b_l)(e_k.w) = 0. The dc_k are constant
// (entries 0, +-1) with dc_k[0] = 0 while c[0] = 1, so they are independent
// of c; a column with nothing left (only for degenerate input) is dropped.
// Preconditions: c[0] = 1 and w != 0 (d > 0), as every Distance2 that the
// stencil functions return.
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
  const double inv = 1.0 / std::sqrt(cc);  // c[0] = 1: |c| >= 1
  for (int k = 0; k < dim; ++k)
    for (int i = 0; i < nv; ++i) Q(i * dim + k, k) = s.c[i] * inv;
  int r = dim;
  // w's direction: grad's first block is 2 c[0] w = 2 w.
  Vec<dim> wdir = s.grad.template head<dim>();
  const double wn = wdir.norm();
  if (wn > 0) {
    wdir /= wn;
    double basis[2][4];  // orthonormal b_l, orthogonal to c, in the nv coefficients
    int nl = 0;
    for (int k = 0; k < s.nb; ++k) {
      double v[4];
      double v0 = 0;
      for (int i = 0; i < nv; ++i) v0 += (v[i] = s.dc[k][i]) * s.dc[k][i];
      for (int pass = 0; pass < 2; ++pass) {
        double dot = 0;
        for (int i = 0; i < nv; ++i) dot += v[i] * s.c[i];
        for (int i = 0; i < nv; ++i) v[i] -= dot / cc * s.c[i];
        for (int l = 0; l < nl; ++l) {
          double dl = 0;
          for (int i = 0; i < nv; ++i) dl += v[i] * basis[l][i];
          for (int i = 0; i < nv; ++i) v[i] -= dl * basis[l][i];
        }
      }
      double vn = 0;
      for (int i = 0; i < nv; ++i) vn += v[i] * v[i];
      if (!(vn > 1e-24 * v0)) continue;  // nothing left of dc_k (degenerate input only)
      vn = std::sqrt(vn);
      for (int i = 0; i < nv; ++i) basis[nl][i] = v[i] / vn;
      for (int i = 0; i < nv; ++i)
        for (int a = 0; a < dim; ++a) Q(i * dim + a, r) = basis[nl][i] * wdir(a);
      ++nl;
      ++r;
    }
  }
  if (r == dim) contact_detail::project_in_basis<n, dim, rmax>(Q, H, keep);
  else if (r == dim + 1) contact_detail::project_in_basis<n, dim + 1, rmax>(Q, H, keep);
  else contact_detail::project_in_basis<n, dim + 2, rmax>(Q, H, keep);
}

}  // namespace bfemp
