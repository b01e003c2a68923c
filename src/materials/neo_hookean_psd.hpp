#pragma once
// Analytic PSD projection of the neo-Hookean tangent dP/dF (paper Eq. 7), from
// the singular values of F (Teran et al. 2005; Smith et al. 2019), replacing
// the iterative d^2 x d^2 eigensolver.
//
// With F = U diag(s) V^T (det U = det V = 1, s_i > 0 since J > 0) the energy
// is psi(s) = mu/2 (sum s_i^2 - d) - mu log J + lambda/2 (log J)^2 and the
// d^2 eigenpairs of dP/dF are, with c = mu - lambda log J:
//   scaling: the d x d Hessian A = d^2 psi / ds ds,
//            A_ii = mu + (c + lambda) / s_i^2,  A_ij = lambda / (s_i s_j),
//            each eigenvector e giving the mode U diag(e) V^T;
//   flip  (i < j): mu + c / (s_i s_j),  mode U (E_ij + E_ji) V^T / sqrt 2;
//   twist (i < j): mu - c / (s_i s_j),  mode U (E_ij - E_ji) V^T / sqrt 2.
// (The flip and twist values are (psi_i -/+ psi_j)/(s_i -/+ s_j) in closed
// form: no division by s_i - s_j, so repeated singular values are exact.)
// The projection keeps the modes with positive eigenvalue:
//   sum_k max(lambda_k, 0) vec(Q_k) vec(Q_k)^T, column-major vec as in
//   StressDerivative. When every eigenvalue is >= 0 the exact tangent
//   (NeoHookean::stress_derivative) is returned unchanged.
// The SVD is one-sided Jacobi, and the scaling block's eigensolve (cyclic
// Jacobi) runs only when A is not positive definite, which with mu > 0 and
// lambda >= 0 needs c < 0 (ln J > mu / lambda): no iterative tridiagonal
// solver on this path.
// Precondition: det F > 0 (the result is meaningless otherwise: NaN or a
// clamped-away tangent, not an error).
#include <cmath>

#include "materials/neo_hookean.hpp"
#include "materials/small_jacobi.hpp"

namespace bfemp {

template <int dim>
KOKKOS_INLINE_FUNCTION StressDerivative<dim> neo_hookean_stress_derivative_psd(const Mat<dim>& F,
                                                                               const LameParameters& p) {
  constexpr int n = dim * dim;
  // One-sided Jacobi SVD (materials/small_jacobi.hpp): det U = det V = 1,
  // backward stable (errors of a few eps s_max, no F^T F), so near-inverted F
  // need no other path.
  Mat<dim> U, V;
  Vec<dim> s;
  jacobi_svd<dim>(F, U, s, V);
  const double logJ = std::log(F.determinant());
  const double c = p.mu - p.lambda * logJ;
  Mat<dim> A;
  for (int i = 0; i < dim; ++i)
    for (int j = 0; j < dim; ++j)
      A(i, j) = i == j ? p.mu + (c + p.lambda) / (s(i) * s(i)) : p.lambda / (s(i) * s(j));
  constexpr int npairs = dim * (dim - 1) / 2;
  double flip[npairs], twist[npairs];
  bool flip_twist_nonnegative = true;
  {
    int k = 0;
    for (int i = 0; i < dim; ++i)
      for (int j = i + 1; j < dim; ++j, ++k) {
        const double r = c / (s(i) * s(j));
        flip[k] = p.mu + r;
        twist[k] = p.mu - r;
        flip_twist_nonnegative = flip_twist_nonnegative && flip[k] >= 0.0 && twist[k] >= 0.0;
      }
  }
  // A_+: A itself when definite (with mu > 0, lambda >= 0: whenever c > 0,
  // i.e. ln J < mu / lambda, any compression included), else clamped from
  // its Jacobi eigenpairs.
  Mat<dim> Ap = A;
  bool scaling_nonnegative = cholesky_positive_definite<dim>(A);
  if (!scaling_nonnegative) {
    Vec<dim> lam;
    Mat<dim> W;
    jacobi_symmetric_eigen<dim>(A, lam, W);
    scaling_nonnegative = lam.minCoeff() >= 0.0;
    Ap = W * lam.cwiseMax(0.0).asDiagonal() * W.transpose();
  }
  if (scaling_nonnegative && flip_twist_nonnegative) return NeoHookean::stress_derivative<dim>(F, p);

  // Scaling modes: S_i = vec(u_i v_i^T), their part of H is S A_+ S^T.
  using Modes = Eigen::Matrix<double, n, dim>;
  Modes S;
  for (int i = 0; i < dim; ++i)
    for (int col = 0; col < dim; ++col)
      for (int row = 0; row < dim; ++row) S(row + dim * col, i) = U(row, i) * V(col, i);
  const Modes SA = S.lazyProduct(Ap);
  StressDerivative<dim> H;
  H.noalias() = SA.lazyProduct(S.transpose());
  // Flip and twist (i < j): with X = vec(u_i v_j^T), Y = vec(u_j v_i^T),
  // f (X+Y)(X+Y)^T / 2 + t (X-Y)(X-Y)^T / 2 for the clamped f, t.
  int k = 0;
  for (int i = 0; i < dim; ++i)
    for (int j = i + 1; j < dim; ++j, ++k) {
      const double f = flip[k] > 0.0 ? 0.5 * flip[k] : 0.0;
      const double t = twist[k] > 0.0 ? 0.5 * twist[k] : 0.0;
      if (f == 0.0 && t == 0.0) continue;
      Eigen::Matrix<double, n, 1> qf, qt;
      for (int col = 0; col < dim; ++col)
        for (int row = 0; row < dim; ++row) {
          const double x = U(row, i) * V(col, j), y = U(row, j) * V(col, i);
          qf(row + dim * col) = x + y;
          qt(row + dim * col) = x - y;
        }
      if (f != 0.0) H.noalias() += f * (qf * qf.transpose());
      if (t != 0.0) H.noalias() += t * (qt * qt.transpose());
    }
  return (0.5 * (H + H.transpose())).eval();
}

}  // namespace bfemp
