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
// Precondition: det F > 0 (NaN otherwise, as stress_derivative).
#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <cmath>

#include "materials/neo_hookean.hpp"

namespace bfemp {

template <int dim>
KOKKOS_INLINE_FUNCTION StressDerivative<dim> neo_hookean_stress_derivative_psd(const Mat<dim>& F,
                                                                               const LameParameters& p) {
  constexpr int n = dim * dim;
  // SVD through the symmetric eigenproblem of F^T F = V diag(s^2) V^T
  // (cheaper than JacobiSVD): s_min then carries a relative error of about
  // eps (s_max / s_min)^2, so below s_min / s_max = 0.05 the one-sided Jacobi
  // SVD is used instead. det V = 1 by a column flip; U = F V diag(1/s) then
  // has det U = det F / (det V prod s) = 1.
  const Eigen::SelfAdjointEigenSolver<Mat<dim>> ev(F.transpose() * F);
  Mat<dim> U, V = ev.eigenvectors();
  Vec<dim> s;
  for (int i = 0; i < dim; ++i) s(i) = std::sqrt(std::max(ev.eigenvalues()(i), 0.0));
  if (s(0) >= 0.05 * s(dim - 1)) {  // eigenvalues ascending
    if (V.determinant() < 0) V.col(0) *= -1.0;
    U = F * V * s.cwiseInverse().asDiagonal();
  } else {
    const Eigen::JacobiSVD<Mat<dim>> svd(F, Eigen::ComputeFullU | Eigen::ComputeFullV);
    U = svd.matrixU();
    V = svd.matrixV();
    s = svd.singularValues();
    if (U.determinant() < 0) {  // J > 0: det U and det V share their sign
      U.col(dim - 1) *= -1.0;
      V.col(dim - 1) *= -1.0;
    }
  }
  const double logJ = std::log(F.determinant());
  const double c = p.mu - p.lambda * logJ;
  Mat<dim> A;
  for (int i = 0; i < dim; ++i)
    for (int j = 0; j < dim; ++j)
      A(i, j) = i == j ? p.mu + (c + p.lambda) / (s(i) * s(i)) : p.lambda / (s(i) * s(j));
  // The iterative solver: the closed-form computeDirect loses eigenvector
  // accuracy (1e-9) when singular values repeat.
  const Eigen::SelfAdjointEigenSolver<Mat<dim>> es(A);
  constexpr int npairs = dim * (dim - 1) / 2;
  double flip[npairs], twist[npairs];
  bool all_nonnegative = es.eigenvalues().minCoeff() >= 0.0;
  {
    int k = 0;
    for (int i = 0; i < dim; ++i)
      for (int j = i + 1; j < dim; ++j, ++k) {
        const double r = c / (s(i) * s(j));
        flip[k] = p.mu + r;
        twist[k] = p.mu - r;
        all_nonnegative = all_nonnegative && flip[k] >= 0.0 && twist[k] >= 0.0;
      }
  }
  if (all_nonnegative) return NeoHookean::stress_derivative<dim>(F, p);

  StressDerivative<dim> H = StressDerivative<dim>::Zero();
  auto add_mode = [&](const Mat<dim>& Dhat, double lam) {  // Q = U Dhat V^T
    if (!(lam > 0.0)) return;
    const Mat<dim> Q = U * Dhat * V.transpose();
    const Eigen::Map<const Eigen::Matrix<double, n, 1>> q(Q.data());
    H.noalias() += lam * (q * q.transpose());
  };
  for (int k = 0; k < dim; ++k) add_mode(es.eigenvectors().col(k).asDiagonal().toDenseMatrix(), es.eigenvalues()(k));
  const double h = 1.0 / std::sqrt(2.0);
  int k = 0;
  for (int i = 0; i < dim; ++i)
    for (int j = i + 1; j < dim; ++j, ++k) {
      Mat<dim> Df = Mat<dim>::Zero(), Dt = Mat<dim>::Zero();
      Df(i, j) = Df(j, i) = h;
      Dt(i, j) = h;
      Dt(j, i) = -h;
      add_mode(Df, flip[k]);
      add_mode(Dt, twist[k]);
    }
  return (0.5 * (H + H.transpose())).eval();
}

}  // namespace bfemp
