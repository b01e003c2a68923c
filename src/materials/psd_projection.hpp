#pragma once
// Projection of a small symmetric matrix onto the positive semi-definite cone
// (nearest PSD matrix in the Frobenius norm): symmetrize, eigen-decompose,
// clamp negative eigenvalues to zero, recompose. Meant for the d^2 x d^2
// stress derivative (4x4 / 9x9) and small contact stencils only.
#include <Eigen/Eigenvalues>

#include "core/types.hpp"

namespace bfemp {

// Replaces A by the PSD projection of (A + A^T)/2. If that symmetric part is
// already PSD (smallest eigenvalue >= 0), A is left bitwise unchanged (so a
// non-symmetric PSD input is not symmetrized either).
//
// keep in [0, 1): the fraction of each negative eigenvalue kept (lambda ->
// keep lambda): 0 is the projection; larger values keep more of the exact
// (indefinite) curvature, so A(keep) = S - (1 - keep) S^- moves from the PSD
// projection (keep 0) towards S (keep 1) and is monotone in keep.
template <int n>
KOKKOS_INLINE_FUNCTION void project_psd(SquareMat<n>& A, double keep = 0.0) {
  const SquareMat<n> S = 0.5 * (A + A.transpose());
  Eigen::SelfAdjointEigenSolver<SquareMat<n>> es(S);
  Eigen::Matrix<double, n, 1> lam = es.eigenvalues();  // ascending
  if (lam(0) >= 0.0) return;
  for (int i = 0; i < n; ++i) lam(i) = lam(i) > 0.0 ? lam(i) : (keep > 0.0 ? keep * lam(i) : 0.0);
  const SquareMat<n>& V = es.eigenvectors();
  A.noalias() = V * lam.asDiagonal() * V.transpose();
  // Exact symmetry of the result (the product above is symmetric only up to
  // rounding).
  A = (0.5 * (A + A.transpose())).eval();
}

}  // namespace bfemp
