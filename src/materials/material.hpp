#pragma once
// Per-body material description and run-time dispatch to the constitutive
// models. MaterialParams is trivially copyable so it can live in a Kokkos View.
#include "core/types.hpp"
#include "materials/lame.hpp"
#include "materials/linear_elastic.hpp"
#include "materials/neo_hookean.hpp"
#include "materials/neo_hookean_psd.hpp"
#include "materials/psd_projection.hpp"

namespace bfemp {

enum class MaterialModel { NeoHookean, LinearElastic };

struct MaterialParams {
  MaterialModel model = MaterialModel::NeoHookean;
  LameParameters lame;
  double density = 0.0;  // rest mass density
};

// "neo_hookean" / "linear_elastic".
KOKKOS_INLINE_FUNCTION const char* material_model_name(MaterialModel m) {
  switch (m) {
    case MaterialModel::NeoHookean: return "neo_hookean";
    case MaterialModel::LinearElastic: return "linear_elastic";
  }
  return "unknown";
}

// Strain energy density psi(F) (per unit rest volume). +infinity for an
// inverted F (J <= 0) with the neo-Hookean model.
template <int dim>
KOKKOS_INLINE_FUNCTION double material_energy(const MaterialParams& m, const Mat<dim>& F) {
  if (m.model == MaterialModel::LinearElastic) return LinearElastic::energy<dim>(F, m.lame);
  return NeoHookean::energy<dim>(F, m.lame);
}

// First Piola-Kirchhoff stress P = dpsi/dF.
template <int dim>
KOKKOS_INLINE_FUNCTION Mat<dim> material_first_piola(const MaterialParams& m, const Mat<dim>& F) {
  if (m.model == MaterialModel::LinearElastic) return LinearElastic::first_piola<dim>(F, m.lame);
  return NeoHookean::first_piola<dim>(F, m.lame);
}

// Exact dP/dF (not projected).
template <int dim>
KOKKOS_INLINE_FUNCTION StressDerivative<dim> material_stress_derivative(const MaterialParams& m,
                                                                        const Mat<dim>& F) {
  if (m.model == MaterialModel::LinearElastic)
    return LinearElastic::stress_derivative<dim>(F, m.lame);
  return NeoHookean::stress_derivative<dim>(F, m.lame);
}

// dP/dF projected onto the PSD cone (for a convex Newton model). The linear
// elastic tangent has eigenvalues 2 mu, 0 and 2 mu + dim lambda; it is
// returned as is when those are >= 0 (the projection would not change it).
// Neo-Hookean: the analytic projection from the singular values of F
// (materials/neo_hookean_psd.hpp); otherwise the eigensolver.
template <int dim>
KOKKOS_INLINE_FUNCTION StressDerivative<dim> material_stress_derivative_psd(const MaterialParams& m,
                                                                            const Mat<dim>& F) {
  if (m.model == MaterialModel::NeoHookean) return neo_hookean_stress_derivative_psd<dim>(F, m.lame);
  StressDerivative<dim> dPdF = material_stress_derivative<dim>(m, F);
  const bool known_psd = m.model == MaterialModel::LinearElastic && m.lame.mu >= 0.0 &&
                         2.0 * m.lame.mu + dim * m.lame.lambda >= 0.0;
  if (!known_psd) project_psd<dim * dim>(dPdF);
  return dPdF;
}

}  // namespace bfemp
