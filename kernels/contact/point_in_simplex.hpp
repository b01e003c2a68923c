#pragma once
// Point-in-simplex test (triangle in 2D, tetrahedron in 3D) by barycentric
// coordinates, used to refuse scenes where an MPM particle starts inside an FEM
// element. `tol` is a distance: p counts as inside when its signed distance to
// every face plane, lambda_i / |grad lambda_i|, is >= -tol (inside, on the
// boundary, or outside by at most tol). Either vertex orientation works.
// A degenerate simplex (|det| <= 1e-14 * longest edge^dim) contains nothing.
#include <Kokkos_Core.hpp>
#include <cmath>

#include "core/types.hpp"

namespace bfemp {

template <int dim>
KOKKOS_INLINE_FUNCTION bool point_in_simplex(const Vec<dim>& p, const Vec<dim>* v, double tol) {
  Mat<dim> T;  // columns v_i - v_0
  double edge2 = 0;
  for (int i = 0; i < dim; ++i) T.col(i) = v[i + 1] - v[0];
  for (int i = 0; i <= dim; ++i)
    for (int j = i + 1; j <= dim; ++j) {
      const double e = (v[j] - v[i]).squaredNorm();
      edge2 = e > edge2 ? e : edge2;
    }
  const double det = T.determinant();
  if (!(std::abs(det) > 1e-14 * std::pow(edge2, 0.5 * dim))) return false;
  const Mat<dim> G = T.inverse();  // row i = grad lambda_{i+1}
  const Vec<dim> lam = G * (p - v[0]);
  Vec<dim> g0 = Vec<dim>::Zero();  // grad lambda_0 = -sum of the rows
  double lam0 = 1;
  for (int i = 0; i < dim; ++i) {
    if (lam(i) < -tol * G.row(i).norm()) return false;
    g0 -= G.row(i).transpose();
    lam0 -= lam(i);
  }
  return lam0 >= -tol * g0.norm();
}

}  // namespace bfemp
