#pragma once
// Hyperelastic material of paper 001 Eq. 18 (bulk modulus K, shear modulus G, Pa):
//   W(F) = G/2 (I1 / J^(2/3) - 3) + K/2 ( (J^2 - 1)/2 - ln J ),
// J = det F, I1 = tr(F F^T), per unit rest volume (J/m^3).
// 2D is plane strain: F is the in-plane block of a 3x3 F with F_zz = 1, so
// I1 = tr(F F^T) + 1 and J = det F of the 2x2 block (the formulas below keep
// the 3D exponents 2/3 and 5/3).
//   P = dW/dF   = G J^(-2/3) (F - I1/3 F^-T) + K/2 (J^2 - 1) F^-T,
//   sigma = P F^T / J = G J^(-5/3) (B - I1/3 I) + K/2 (J - 1/J) I,  B = F F^T,
// (in 2D the in-plane block of the 3D Cauchy stress; sigma_zz is not needed).
// Small-strain limit: sigma = K tr(eps) I + 2 G dev(eps) (3D deviator).
// Dilatational wave speed at rest: c = sqrt((K + 4G/3) / rho0).
// Preconditions: J > 0 (NaN / inf otherwise).
#include <cmath>

#include "core/types.hpp"

namespace bfemp {

struct HyperelasticKG {
  double K = 0.0;  // Pa
  double G = 0.0;  // Pa

  template <int dim>
  KOKKOS_INLINE_FUNCTION static double first_invariant(const Mat<dim>& F) {
    return F.squaredNorm() + (dim == 2 ? 1.0 : 0.0);
  }

  template <int dim>
  KOKKOS_INLINE_FUNCTION double energy(const Mat<dim>& F) const {
    const double J = F.determinant();
    const double I1 = first_invariant<dim>(F);
    return 0.5 * G * (I1 / std::cbrt(J * J) - 3.0) + 0.5 * K * (0.5 * (J * J - 1.0) - std::log(J));
  }

  template <int dim>
  KOKKOS_INLINE_FUNCTION Mat<dim> first_piola(const Mat<dim>& F) const {
    const double J = F.determinant();
    const double I1 = first_invariant<dim>(F);
    const Mat<dim> FinvT = F.inverse().transpose();
    return (G / std::cbrt(J * J)) * (F - (I1 / 3.0) * FinvT) + (0.5 * K * (J * J - 1.0)) * FinvT;
  }

  template <int dim>
  KOKKOS_INLINE_FUNCTION Mat<dim> cauchy(const Mat<dim>& F) const {
    const double J = F.determinant();
    const double I1 = first_invariant<dim>(F);
    const Mat<dim> B = F * F.transpose();
    return (G / (J * std::cbrt(J * J))) * (B - (I1 / 3.0) * Mat<dim>::Identity()) +
           (0.5 * K * (J - 1.0 / J)) * Mat<dim>::Identity();
  }
};

}  // namespace bfemp
