#pragma once
// Small-strain linear elasticity written as a function of F:
//   eps = (F + F^T)/2 - I,  psi = mu eps:eps + lambda/2 tr(eps)^2,
//   P = 2 mu eps + lambda tr(eps) I,
//   dP_ij/dF_kl = mu (d_ik d_jl + d_il d_jk) + lambda d_ij d_kl (constant).
// Defined for every F (no inversion barrier).
#include "core/types.hpp"
#include "materials/lame.hpp"

namespace bfemp {

struct LinearElastic {
  template <int dim>
  KOKKOS_INLINE_FUNCTION static Mat<dim> small_strain(const Mat<dim>& F) {
    return 0.5 * (F + F.transpose()) - Mat<dim>::Identity();
  }

  template <int dim>
  KOKKOS_INLINE_FUNCTION static double energy(const Mat<dim>& F, const LameParameters& p) {
    const Mat<dim> eps = small_strain<dim>(F);
    const double tr = eps.trace();
    return p.mu * eps.squaredNorm() + 0.5 * p.lambda * tr * tr;
  }

  template <int dim>
  KOKKOS_INLINE_FUNCTION static Mat<dim> first_piola(const Mat<dim>& F, const LameParameters& p) {
    const Mat<dim> eps = small_strain<dim>(F);
    return 2.0 * p.mu * eps + (p.lambda * eps.trace()) * Mat<dim>::Identity();
  }

  template <int dim>
  KOKKOS_INLINE_FUNCTION static StressDerivative<dim> stress_derivative(const Mat<dim>& /*F*/,
                                                                        const LameParameters& p) {
    StressDerivative<dim> dPdF = StressDerivative<dim>::Zero();
    for (int j = 0; j < dim; ++j)
      for (int i = 0; i < dim; ++i) {
        dPdF(i + dim * j, i + dim * j) += p.mu;  // d_ik d_jl
        dPdF(i + dim * j, j + dim * i) += p.mu;  // d_il d_jk
        if (i == j)
          for (int k = 0; k < dim; ++k) dPdF(i + dim * i, k + dim * k) += p.lambda;
      }
    return dPdF;
  }
};

}  // namespace bfemp
