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
  // Evaluated in H = F - I without cancellation, so that psi keeps its
  // relative accuracy at tiny strains (E = 4e12 at strains ~1e-12: the direct
  // form loses mu * 1e-16 absolute, far above the strain energy itself):
  //   tr(F^T F) - d = 2 tr H + |H|^2,   J - 1 = j = tr H + m2(H) + det H
  //   (m2: sum of principal 2x2 minors),  log J = log1p(j),
  //   psi = mu (-(m2 + det H) + (j - log1p(j))) + mu/2 |H|^2 + lambda/2 log1p(j)^2,
  // with j - log1p(j) by its series for small |j|.
  template <int dim>
  KOKKOS_INLINE_FUNCTION static double energy(const Mat<dim>& F, const LameParameters& p) {
    const Mat<dim> H = F - Mat<dim>::Identity();
    double m2 = 0, detH;
    if constexpr (dim == 2) {
      detH = H.determinant();
    } else {
      m2 = H(0, 0) * H(1, 1) - H(0, 1) * H(1, 0) + H(0, 0) * H(2, 2) - H(0, 2) * H(2, 0) + H(1, 1) * H(2, 2) -
           H(1, 2) * H(2, 1);
      detH = H.determinant();
    }
    const double extra = m2 + detH;  // 2D: m2 is det H itself, counted once
    const double j = H.trace() + extra;
    if (!(j > -1.0)) return std::numeric_limits<double>::infinity();
    const double logJ = std::log1p(j);
    return p.mu * (j_minus_log1p(j) - extra) + 0.5 * p.mu * H.squaredNorm() + 0.5 * p.lambda * logJ * logJ;
  }

  // j - log1p(j), accurate for small |j| (series to j^12 below 1e-2).
  KOKKOS_INLINE_FUNCTION static double j_minus_log1p(double j) {
    if (std::abs(j) >= 1e-2) return j - std::log1p(j);
    double term = j * j, sum = 0;
    for (int k = 2; k <= 12; ++k) {
      sum += (k % 2 == 0 ? term : -term) / k;
      term *= j;
    }
    return sum;
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
