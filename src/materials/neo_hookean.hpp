#pragma once
// Compressible neo-Hookean hyperelasticity (paper Eq. 7):
//   psi(F) = mu/2 (tr(F^T F) - d) - mu log J + lambda/2 (log J)^2,  J = det F.
// P = dpsi/dF = mu (F - F^{-T}) + lambda log J F^{-T}.
// dP_ij/dF_kl = mu d_ik d_jl + (mu - lambda log J) Finv_li Finv_jk
//               + lambda Finv_ji Finv_lk                (Finv = F^{-1}).
// first_piola / stress_derivative require J > 0 (they are NaN otherwise);
// energy returns +infinity for J <= 0.
#include <cmath>
#include <limits>

#include "core/types.hpp"
#include "materials/lame.hpp"

namespace bfemp {

struct NeoHookean {
  template <int dim>
  KOKKOS_INLINE_FUNCTION static double energy(const Mat<dim>& F, const LameParameters& p) {
    const double J = F.determinant();
    if (!(J > 0.0)) return std::numeric_limits<double>::infinity();
    const double logJ = std::log(J);
    return 0.5 * p.mu * (F.squaredNorm() - dim) - p.mu * logJ + 0.5 * p.lambda * logJ * logJ;
  }

  template <int dim>
  KOKKOS_INLINE_FUNCTION static Mat<dim> first_piola(const Mat<dim>& F, const LameParameters& p) {
    const double logJ = std::log(F.determinant());
    const Mat<dim> FinvT = F.inverse().transpose();
    return p.mu * (F - FinvT) + (p.lambda * logJ) * FinvT;
  }

  template <int dim>
  KOKKOS_INLINE_FUNCTION static StressDerivative<dim> stress_derivative(const Mat<dim>& F,
                                                                        const LameParameters& p) {
    const double logJ = std::log(F.determinant());
    const Mat<dim> Finv = F.inverse();
    const double a = p.mu - p.lambda * logJ;
    StressDerivative<dim> dPdF;
    for (int j = 0; j < dim; ++j)
      for (int i = 0; i < dim; ++i)
        for (int l = 0; l < dim; ++l)
          for (int k = 0; k < dim; ++k) {
            // Products grouped so that entry (ij, kl) and (kl, ij) round
            // identically: the matrix is exactly symmetric.
            double v = a * (Finv(l, i) * Finv(j, k)) + p.lambda * (Finv(j, i) * Finv(l, k));
            if (i == k && j == l) v += p.mu;
            dPdF(i + dim * j, k + dim * l) = v;
          }
    return dPdF;
  }
};

}  // namespace bfemp
