#pragma once
// Lagged friction of paper §4.3: the mollified friction magnitude (Eq. 36),
// its integral f0 (the pseudo-potential density of Eq. 37, with f0' = f1) and
// the tangent bases of the contact pairs.
//
// With eh = eps_v * dt (a sliding displacement per step):
//   f1(y) = -y^2 / eh^2 + 2 y / eh          (y < eh),   1           (y >= eh)
//   f0(y) = -y^3 / (3 eh^2) + y^2 / eh + eh / 3   (y < eh),   y     (y >= eh)
// f0 is C1 at eh and f0(0) = eh/3 (a constant, irrelevant to forces).
// For a sliding displacement u in the (dim-1)-dimensional tangent space the
// Hessian of f0(|u|) is (f1/y) I + (f1' - f1/y) u u^T / y^2, which is PSD
// (f1' >= 0 and f1/y >= 0 everywhere), so no projection is needed; at y -> 0
// it tends to (2 / eh) I.
#include <Kokkos_Core.hpp>
#include <cmath>

#include "core/types.hpp"

namespace bfemp {

KOKKOS_INLINE_FUNCTION double friction_f0(double y, double eh) {
  return y >= eh ? y : -y * y * y / (3.0 * eh * eh) + y * y / eh + eh / 3.0;
}

KOKKOS_INLINE_FUNCTION double friction_f1(double y, double eh) {
  return y >= eh ? 1.0 : -y * y / (eh * eh) + 2.0 * y / eh;
}

// f1(y) / y, finite at y = 0.
KOKKOS_INLINE_FUNCTION double friction_f1_over_y(double y, double eh) {
  return y >= eh ? 1.0 / y : -y / (eh * eh) + 2.0 / eh;
}

// f1'(y).
KOKKOS_INLINE_FUNCTION double friction_f1_derivative(double y, double eh) {
  return y >= eh ? 0.0 : -2.0 * y / (eh * eh) + 2.0 / eh;
}

// Hessian of f0(|u|) w.r.t. u (PSD by construction).
template <int m>
KOKKOS_INLINE_FUNCTION SquareMat<m> friction_f0_hessian(const Eigen::Matrix<double, m, 1>& u, double eh) {
  const double y = u.norm();
  const double a = friction_f1_over_y(y, eh);
  SquareMat<m> H = a * SquareMat<m>::Identity();
  if (y > 0) H += (friction_f1_derivative(y, eh) - a) / (y * y) * (u * u.transpose());
  return H;
}

// Orthonormal tangent basis (columns) of the plane orthogonal to the unit
// contact normal n (from the closest point of the facet to the particle):
// dim x (dim - 1). For a point-edge pair in 2D this is the edge tangent, for
// point-triangle the triangle's plane; friction is isotropic, so any
// orthonormal basis of the plane gives the same |u|.
template <int dim>
KOKKOS_INLINE_FUNCTION Eigen::Matrix<double, dim, dim - 1> tangent_basis_of_normal(const Vec<dim>& n) {
  Eigen::Matrix<double, dim, dim - 1> T;
  if constexpr (dim == 2) {
    T(0, 0) = -n(1);
    T(1, 0) = n(0);
  } else {
    // Cross with the axis least aligned with n.
    Vec<3> a = Vec<3>::Zero();
    int k = 0;
    n.cwiseAbs().minCoeff(&k);
    a(k) = 1.0;
    const Vec<3> t1 = n.cross(a).normalized();
    T.col(0) = t1;
    T.col(1) = n.cross(t1);
  }
  return T;
}

}  // namespace bfemp
