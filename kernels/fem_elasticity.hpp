#pragma once
// Kokkos kernels of the FEM elastic energy Psi(x) = sum_e V_e psi(F_e(x)) over
// linear simplices: value, gradient, PSD-projected Hessian assembled into a
// local CRS matrix, and the largest step keeping every det F_e > 0.
// Positions x, directions p and gradients are node-interleaved (node*dim + c).
#include <Kokkos_Core.hpp>
#include <cmath>

#include "core/types.hpp"
#include "fem/det_root.hpp"
#include "fem/fem_mesh.hpp"
#include "materials/material.hpp"

namespace bfemp {

// Edge matrix T(x) = [x_1 - x_0, ..., x_d - x_0] of element e.
template <int dim, class CellView, class XView>
KOKKOS_INLINE_FUNCTION Mat<dim> edge_matrix(const CellView& cells, const XView& x, LO e) {
  Mat<dim> T;
  for (int a = 1; a <= dim; ++a)
    for (int c = 0; c < dim; ++c)
      T(c, a - 1) = x(cells(e, a) * dim + c) - x(cells(e, 0) * dim + c);
  return T;
}

template <int dim, class DmView>
KOKKOS_INLINE_FUNCTION Mat<dim> load_Dm_inv(const DmView& Dm_inv, LO e) {
  Mat<dim> M;
  for (int i = 0; i < dim; ++i)
    for (int j = 0; j < dim; ++j) M(i, j) = Dm_inv(e, i, j);
  return M;
}

// Shape-function gradients in the rest configuration: row a = grad N_a.
template <int dim>
KOKKOS_INLINE_FUNCTION Eigen::Matrix<double, dim + 1, dim> shape_gradients(const Mat<dim>& Dm_inv) {
  Eigen::Matrix<double, dim + 1, dim> g;
  g.template bottomRows<dim>() = Dm_inv;
  g.row(0) = -Dm_inv.colwise().sum();
  return g;
}

template <int dim>
double fem_elastic_energy(const FemMesh<dim>& m, Kokkos::View<const double*, MemSpace> x) {
  auto cells = m.cells;
  auto Dm_inv = m.Dm_inv;
  auto vol = m.rest_volume;
  auto mat = m.material;
  auto mats = m.materials;
  double total = 0;
  Kokkos::parallel_reduce(
      "fem_elastic_energy", Kokkos::RangePolicy<ExecSpace>(0, m.num_cells()),
      KOKKOS_LAMBDA(const LO e, double& acc) {
        const Mat<dim> F = edge_matrix<dim>(cells, x, e) * load_Dm_inv<dim>(Dm_inv, e);
        acc += vol(e) * material_energy<dim>(mats(mat(e)), F);
      },
      total);
  return total;
}

// Per-element J = det F, for output and diagnostics.
template <int dim>
void fem_element_J(const FemMesh<dim>& m, Kokkos::View<const double*, MemSpace> x,
                   Kokkos::View<double*, MemSpace> J) {
  auto cells = m.cells;
  auto Dm_inv = m.Dm_inv;
  Kokkos::parallel_for(
      "fem_element_J", Kokkos::RangePolicy<ExecSpace>(0, m.num_cells()), KOKKOS_LAMBDA(const LO e) {
        J(e) = (edge_matrix<dim>(cells, x, e) * load_Dm_inv<dim>(Dm_inv, e)).determinant();
      });
}

// Largest alpha in (0, inf] such that det F_e(x + t p) > 0 for all t < alpha.
template <int dim>
double fem_max_feasible_step(const FemMesh<dim>& m, Kokkos::View<const double*, MemSpace> x,
                             Kokkos::View<const double*, MemSpace> p) {
  auto cells = m.cells;
  double amin = 0;
  Kokkos::parallel_reduce(
      "fem_max_feasible_step", Kokkos::RangePolicy<ExecSpace>(0, m.num_cells()),
      KOKKOS_LAMBDA(const LO e, double& acc) {
        const double a =
            smallest_positive_det_root<dim>(edge_matrix<dim>(cells, x, e), edge_matrix<dim>(cells, p, e));
        if (a < acc) acc = a;
      },
      Kokkos::Min<double>(amin));
  return amin;
}

// grad += scale * dPsi/dx; local Hessian blocks scale * V B^T (dP/dF)_+ B summed
// into the rows of free DOFs of `A` (columns local == DOF ids). Couplings to
// prescribed DOFs (prescribed(dof) != 0) move to the right-hand side:
// rhs(free) -= H(free, prescribed) * dx_prescribed(prescribed).
template <int dim, class LocalMatrix>
void fem_elastic_assemble(const FemMesh<dim>& m, Kokkos::View<const double*, MemSpace> x, double scale,
                          Kokkos::View<double*, MemSpace> grad, const LocalMatrix& A,
                          Kokkos::View<const int*, MemSpace> prescribed,
                          Kokkos::View<const double*, MemSpace> dx_prescribed,
                          Kokkos::View<double*, MemSpace> rhs) {
  constexpr int nv = dim + 1;
  constexpr int nd = nv * dim;
  constexpr int dd = dim * dim;
  auto cells = m.cells;
  auto Dm_inv = m.Dm_inv;
  auto vol = m.rest_volume;
  auto mat = m.material;
  auto mats = m.materials;
  Kokkos::parallel_for(
      "fem_elastic_assemble", Kokkos::RangePolicy<ExecSpace>(0, m.num_cells()),
      KOKKOS_LAMBDA(const LO e) {
        const Mat<dim> Dinv = load_Dm_inv<dim>(Dm_inv, e);
        const auto gN = shape_gradients<dim>(Dinv);
        const Mat<dim> F = edge_matrix<dim>(cells, x, e) * Dinv;
        const MaterialParams& mp = mats(mat(e));
        const double w = scale * vol(e);
        const Mat<dim> P = material_first_piola<dim>(mp, F);
        const StressDerivative<dim> D = material_stress_derivative_psd<dim>(mp, F);
        LO dof[nd];
        for (int a = 0; a < nv; ++a)
          for (int k = 0; k < dim; ++k) dof[a * dim + k] = cells(e, a) * dim + k;
        // gradient: w * P grad N_a
        for (int a = 0; a < nv; ++a) {
          const Vec<dim> ga = w * (P * gN.row(a).transpose());
          for (int k = 0; k < dim; ++k) Kokkos::atomic_add(&grad(dof[a * dim + k]), ga(k));
        }
        // DB(:, b*dim + l) = sum_m D(:, l + dim m) gN(b, m)
        Eigen::Matrix<double, dd, nd> DB;
        for (int b = 0; b < nv; ++b)
          for (int l = 0; l < dim; ++l) {
            Eigen::Matrix<double, dd, 1> col = Eigen::Matrix<double, dd, 1>::Zero();
            for (int mm = 0; mm < dim; ++mm) col += D.col(l + dim * mm) * gN(b, mm);
            DB.col(b * dim + l) = col;
          }
        for (int a = 0; a < nv; ++a)
          for (int k = 0; k < dim; ++k) {
            const int r = a * dim + k;
            if (prescribed(dof[r])) continue;
            LO cols[nd];
            double vals[nd];
            int nc = 0;
            double rhs_r = 0;
            for (int c = 0; c < nd; ++c) {
              double h = 0;
              for (int j = 0; j < dim; ++j) h += DB(k + dim * j, c) * gN(a, j);
              h *= w;
              if (prescribed(dof[c])) {
                rhs_r -= h * dx_prescribed(dof[c]);
              } else {
                cols[nc] = dof[c];
                vals[nc] = h;
                ++nc;
              }
            }
            A.sumIntoValues(dof[r], cols, nc, vals, false, true);
            if (rhs_r != 0) Kokkos::atomic_add(&rhs(dof[r]), rhs_r);
          }
      });
}

}  // namespace bfemp

namespace bfemp {

// grad += scale * dPsi/dx (gradient only; used for a^0 and checks).
template <int dim>
void fem_elastic_gradient(const FemMesh<dim>& m, Kokkos::View<const double*, MemSpace> x, double scale,
                          Kokkos::View<double*, MemSpace> grad) {
  constexpr int nv = dim + 1;
  auto cells = m.cells;
  auto Dm_inv = m.Dm_inv;
  auto vol = m.rest_volume;
  auto mat = m.material;
  auto mats = m.materials;
  Kokkos::parallel_for(
      "fem_elastic_gradient", Kokkos::RangePolicy<ExecSpace>(0, m.num_cells()),
      KOKKOS_LAMBDA(const LO e) {
        const Mat<dim> Dinv = load_Dm_inv<dim>(Dm_inv, e);
        const auto gN = shape_gradients<dim>(Dinv);
        const Mat<dim> P = material_first_piola<dim>(mats(mat(e)), edge_matrix<dim>(cells, x, e) * Dinv);
        for (int a = 0; a < nv; ++a) {
          const Vec<dim> ga = scale * vol(e) * (P * gN.row(a).transpose());
          for (int k = 0; k < dim; ++k) Kokkos::atomic_add(&grad(cells(e, a) * dim + k), ga(k));
        }
      });
}

// Von Mises stress of the Cauchy stress sigma = P F^T / J (2D: in-plane
// components, sqrt(sxx^2 - sxx syy + syy^2 + 3 sxy^2)).
template <int dim>
void fem_element_von_mises(const FemMesh<dim>& m, Kokkos::View<const double*, MemSpace> x,
                           Kokkos::View<double*, MemSpace> out) {
  auto cells = m.cells;
  auto Dm_inv = m.Dm_inv;
  auto mat = m.material;
  auto mats = m.materials;
  Kokkos::parallel_for(
      "fem_element_von_mises", Kokkos::RangePolicy<ExecSpace>(0, m.num_cells()),
      KOKKOS_LAMBDA(const LO e) {
        const Mat<dim> F = edge_matrix<dim>(cells, x, e) * load_Dm_inv<dim>(Dm_inv, e);
        const Mat<dim> s = material_first_piola<dim>(mats(mat(e)), F) * F.transpose() / F.determinant();
        if constexpr (dim == 2) {
          out(e) = std::sqrt(s(0, 0) * s(0, 0) - s(0, 0) * s(1, 1) + s(1, 1) * s(1, 1) +
                                3 * s(0, 1) * s(0, 1));
        } else {
          const Mat<dim> dev = s - s.trace() / 3.0 * Mat<dim>::Identity();
          out(e) = std::sqrt(1.5 * dev.squaredNorm());
        }
      });
}

}  // namespace bfemp
