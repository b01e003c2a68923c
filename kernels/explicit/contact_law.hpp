#pragma once
// Contact laws of the multimaterial grid contact (paper 001 §2.2, Eqs. 7-10).
// At a node where material alpha (mass m_a, momentum p_a) meets beta (m_b, p_b)
// with unit normal n from alpha to beta, the momentum change of alpha is
// Delta p (beta gets -Delta p, Eq. 7, so the pair's momentum is unchanged):
//   Delta p(0) = m_a (v_cm - v_a) = m_red (v_b - v_a),   m_red = m_a m_b / (m_a + m_b)
//   (the change that moves both with the centre-of-mass velocity, Eq. 8),
//   dn = Delta p(0) . n  (< 0 when approaching; N_c = -dn / (A_c dt) > 0).
// Laws (k of Eq. 10 with S_slide):
//   Stick        : Delta p = Delta p(0), always (a perfect interface: no
//                  approach or separation test).
//   Frictionless : Delta p = dn n.
//   Coulomb (mu) : t = tangential part of Delta p(0), |t| its size;
//                  |t| <= mu |dn| (stick branch): Delta p = Delta p(0);
//                  otherwise (slip): Delta p = dn n + mu |dn| t/|t|
//                  (S_slide A_c dt = mu N_c A_c dt = mu |dn|, Eq. 10: the area cancels).
// A non-stick law acts only when the materials approach, dn < 0 (no tension);
// the caller adds the separation test (d < 0) of the chosen method.
// Units: masses kg (kg/m in 2D), momenta kg m/s; dimensionless mu >= 0.
#include <Kokkos_Core.hpp>
#include <cmath>

#include "core/types.hpp"

namespace bfemp::xmpm {

enum class ContactLaw : int { Frictionless = 0, Coulomb = 1, Stick = 2 };

struct LawParams {
  ContactLaw law = ContactLaw::Coulomb;
  double mu = 0.0;
};

// Delta p(0) = m_red (v_b - v_a) from masses and momenta.
template <int dim>
KOKKOS_INLINE_FUNCTION Vec<dim> center_of_mass_change(double m_a, const Vec<dim>& p_a, double m_b,
                                                      const Vec<dim>& p_b) {
  const double M = m_a + m_b;
  return (m_a / M) * p_b - (m_b / M) * p_a;  // = m_a m_b/(m_a+m_b) (p_b/m_b - p_a/m_a)
}

// Momentum change of alpha for the law; `active` is false when the law does
// nothing (separating, or zero masses). n: unit normal from alpha to beta.
template <int dim>
KOKKOS_INLINE_FUNCTION Vec<dim> contact_momentum_change(const LawParams& law, double m_a, const Vec<dim>& p_a,
                                                        double m_b, const Vec<dim>& p_b, const Vec<dim>& n,
                                                        bool& active) {
  active = false;
  if (!(m_a > 0.0 && m_b > 0.0)) return Vec<dim>::Zero();
  const Vec<dim> dp0 = center_of_mass_change<dim>(m_a, p_a, m_b, p_b);
  if (law.law == ContactLaw::Stick) {
    active = true;
    return dp0;
  }
  const double dn = dp0.dot(n);
  if (!(dn < 0.0)) return Vec<dim>::Zero();
  active = true;
  if (law.law == ContactLaw::Frictionless) return dn * n;
  const Vec<dim> t = dp0 - dn * n;
  const double tn = t.norm();
  const double limit = law.mu * (-dn);
  if (tn <= limit) return dp0;
  return dn * n + (limit / tn) * t;
}

}  // namespace bfemp::xmpm
