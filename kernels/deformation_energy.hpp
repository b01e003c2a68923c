#pragma once
// Kokkos kernels of an elastic energy Psi(x) = sum_q V_q psi(F_q(x)) whose
// deformation gradients are linear in nodal positions over a stencil:
//   F_q(x) = sum_a x_{n(q,a)} g_{qa}^T.
// FEM simplices: g_qa = grad N_a (rest shape-function gradients, nv = dim+1).
// MPM particles:  g_qa = F_q^n^T grad w_{aq} (B-spline stencil, nv = 3^dim).
// Value, gradient, PSD-projected Hessian (V B^T (dP/dF)_+ B, never an
// eigen-decomposition of the stencil matrix), det F > 0 step bound, J and von
// Mises. Positions and directions are node-interleaved (node*dim + c).
#include <Kokkos_Core.hpp>
#include <cmath>

#include "core/types.hpp"
#include "kernels/fem/det_root.hpp"
#include "materials/material.hpp"

namespace bfemp {

template <int dim, int nv>
struct DeformationStencils {
  Kokkos::View<LO* [nv], MemSpace> nodes;       // system node ids
  Kokkos::View<double* [nv][dim], MemSpace> g;  // F = sum_a x_a g_a^T
  Kokkos::View<double*, MemSpace> volume;       // rest volume V_q
  Kokkos::View<int*, MemSpace> material;        // index into materials
  Kokkos::View<MaterialParams*, MemSpace> materials;
  LO size() const { return static_cast<LO>(nodes.extent(0)); }
};

template <int dim, int nv, class XView>
KOKKOS_INLINE_FUNCTION Mat<dim> stencil_F(const DeformationStencils<dim, nv>& s, const XView& x, LO q) {
  Mat<dim> F = Mat<dim>::Zero();
  for (int a = 0; a < nv; ++a) {
    const LO n = s.nodes(q, a);
    for (int i = 0; i < dim; ++i)
      for (int j = 0; j < dim; ++j) F(i, j) += x(n * dim + i) * s.g(q, a, j);
  }
  return F;
}

// sum over stencils q in [k0, k1) (k1 < 0: to the end) of V_q psi(F_q).
template <int dim, int nv>
double deformation_energy(const DeformationStencils<dim, nv>& s, Kokkos::View<const double*, MemSpace> x,
                          LO k0 = 0, LO k1 = -1) {
  double total = 0;
  if (k1 < 0) k1 = s.size();
  if (k1 <= k0) return 0.0;
  Kokkos::parallel_reduce(
      "deformation_energy", Kokkos::RangePolicy<ExecSpace>(k0, k1),
      KOKKOS_LAMBDA(const LO q, double& acc) {
        acc += s.volume(q) * material_energy<dim>(s.materials(s.material(q)), stencil_F(s, x, q));
      },
      total);
  return total;
}

// grad += scale * dPsi/dx.
template <int dim, int nv>
void deformation_gradient(const DeformationStencils<dim, nv>& s, Kokkos::View<const double*, MemSpace> x,
                          double scale, Kokkos::View<double*, MemSpace> grad) {
  Kokkos::parallel_for(
      "deformation_gradient", Kokkos::RangePolicy<ExecSpace>(0, s.size()), KOKKOS_LAMBDA(const LO q) {
        const Mat<dim> P = material_first_piola<dim>(s.materials(s.material(q)), stencil_F(s, x, q));
        const double w = scale * s.volume(q);
        for (int a = 0; a < nv; ++a)
          for (int k = 0; k < dim; ++k) {
            double v = 0;
            for (int j = 0; j < dim; ++j) v += P(k, j) * s.g(q, a, j);
            Kokkos::atomic_add(&grad(s.nodes(q, a) * dim + k), w * v);
          }
      });
}

// Local gradient and Hessian of stencil q, added into gl (nv*dim) and Hl
// (nv*dim square), unscaled:
//   gl(a dim + k)            += V sum_j P_kj g_aj
//   Hl(a dim + k, b dim + l) += V sum_{j,m} g_aj (dP/dF)_{kj,lm} g_bm
// with dP/dF projected onto the PSD cone when `project` (the exact tangent
// otherwise, for derivative tests). Only the lower triangle of Hl (row >=
// column, contiguous in Eigen's column-major storage) is written;
// symmetric_from_lower() completes it.
template <int dim, int nv, class XView>
KOKKOS_INLINE_FUNCTION void deformation_local_add(const DeformationStencils<dim, nv>& s, const XView& x, LO q,
                                                  bool project, Eigen::Matrix<double, nv * dim, 1>& gl,
                                                  SquareMat<nv * dim>& Hl) {
  constexpr int nd = nv * dim;
  constexpr int dd = dim * dim;
  const MaterialParams& mp = s.materials(s.material(q));
  const Mat<dim> F = stencil_F(s, x, q);
  const double w = s.volume(q);
  const Mat<dim> P = material_first_piola<dim>(mp, F);
  const StressDerivative<dim> D =
      project ? material_stress_derivative_psd<dim>(mp, F) : material_stress_derivative<dim>(mp, F);
  double gq[nv][dim];
  for (int a = 0; a < nv; ++a)
    for (int j = 0; j < dim; ++j) gq[a][j] = s.g(q, a, j);
  for (int a = 0; a < nv; ++a)
    for (int k = 0; k < dim; ++k) {
      double v = 0;
      for (int j = 0; j < dim; ++j) v += P(k, j) * gq[a][j];
      gl(a * dim + k) += w * v;
    }
  // DB[r][b dim + l] = w sum_m D(r, l + dim m) g_bm, rows contiguous.
  double DB[dd][nd];
  for (int r = 0; r < dd; ++r)
    for (int b = 0; b < nv; ++b)
      for (int l = 0; l < dim; ++l) {
        double v = 0;
        for (int m = 0; m < dim; ++m) v += D(r, l + dim * m) * gq[b][m];
        DB[r][b * dim + l] = w * v;
      }
  // Column c = a dim + k of Hl, rows r >= c: sum_j g_aj DB[k + dim j][r],
  // the dim terms summed before the column is loaded, so each entry of Hl is
  // read and written once per stencil (Hl, 52 KB in 3D, is not in L1).
  for (int a = 0; a < nv; ++a)
    for (int k = 0; k < dim; ++k) {
      const int c = a * dim + k;
      double* col = &Hl(0, c);
      const double g0 = gq[a][0], g1 = gq[a][1];
      const double* r0 = DB[k];
      const double* r1 = DB[k + dim];
      if constexpr (dim == 3) {
        const double g2 = gq[a][2];
        const double* r2 = DB[k + 2 * dim];
        for (int r = c; r < nd; ++r) col[r] += g0 * r0[r] + g1 * r1[r] + g2 * r2[r];
      } else {
        for (int r = c; r < nd; ++r) col[r] += g0 * r0[r] + g1 * r1[r];
      }
    }
}

template <int n>
KOKKOS_INLINE_FUNCTION void symmetric_from_lower(SquareMat<n>& H) {
  for (int c = 1; c < n; ++c)
    for (int r = 0; r < c; ++r) H(r, c) = H(c, r);
}

// scale * (gradient, PSD-projected Hessian) of stencils into the sink, which
// eliminates prescribed DOFs (kernels/dof_sink.hpp; at the positions of its
// scatter table when it holds one for these stencils): stencils order(k), k in
// [k0, k1) (all stencils, in index order, when `order` is empty), in
// parallel; the sink's `atomic` flag says whether they may share nodes.
template <int dim, int nv, class Sink>
void deformation_assemble(const DeformationStencils<dim, nv>& s, Kokkos::View<const double*, MemSpace> x,
                          const Sink& sink, bool project = true, Kokkos::View<const LO*, MemSpace> order = {},
                          LO k0 = 0, LO k1 = -1) {
  constexpr int nd = nv * dim;
  const bool ordered = order.extent(0) > 0;
  const long n_stencils = s.size();  // the sink's scatter table, if it has one, is by stencil index q
  if (k1 < 0) k1 = ordered ? static_cast<LO>(order.extent(0)) : s.size();
  Kokkos::parallel_for(
      "deformation_assemble", Kokkos::RangePolicy<ExecSpace>(k0, k1), KOKKOS_LAMBDA(const LO k) {
        const LO q = ordered ? order(k) : k;
        Eigen::Matrix<double, nd, 1> gl = Eigen::Matrix<double, nd, 1>::Zero();
        SquareMat<nd> Hl = SquareMat<nd>::Zero();
        deformation_local_add<dim, nv>(s, x, q, project, gl, Hl);
        symmetric_from_lower<nd>(Hl);
        LO nodes[nv];
        for (int a = 0; a < nv; ++a) nodes[a] = s.nodes(q, a);
        sink.add_stencil(nodes, nv, gl, &Hl, sink.stencil_positions(q, nv, n_stencils));
      });
}

// Largest alpha in (0, inf] such that det F_q(x + t p) > 0 for all t < alpha;
// inf also when that holds for all t <= cap (a caller that never steps past
// cap: no stencil's root beyond it is refined, see smallest_positive_det_root).
template <int dim, int nv>
double deformation_max_step(const DeformationStencils<dim, nv>& s, Kokkos::View<const double*, MemSpace> x,
                            Kokkos::View<const double*, MemSpace> p,
                            double cap = std::numeric_limits<double>::infinity()) {
  double amin = 0;
  Kokkos::parallel_reduce(
      "deformation_max_step", Kokkos::RangePolicy<ExecSpace>(0, s.size()),
      KOKKOS_LAMBDA(const LO q, double& acc) {
        const double a = smallest_positive_det_root<dim>(stencil_F(s, x, q), stencil_F(s, p, q), cap);
        if (a < acc) acc = a;
      },
      Kokkos::Min<double>(amin));
  return amin;
}

// Von Mises stress of the Cauchy stress of F (2D: in-plane components).
template <int dim>
KOKKOS_INLINE_FUNCTION double von_mises_of(const MaterialParams& mp, const Mat<dim>& F) {
  const Mat<dim> sg = material_first_piola<dim>(mp, F) * F.transpose() / F.determinant();
  if constexpr (dim == 2) {
    return std::sqrt(sg(0, 0) * sg(0, 0) - sg(0, 0) * sg(1, 1) + sg(1, 1) * sg(1, 1) + 3 * sg(0, 1) * sg(0, 1));
  } else {
    const Mat<dim> dev = sg - sg.trace() / 3.0 * Mat<dim>::Identity();
    return std::sqrt(1.5 * dev.squaredNorm());
  }
}

// J = det F_q and the von Mises stress of sigma = P F^T / J (2D: in-plane
// components, sqrt(sxx^2 - sxx syy + syy^2 + 3 sxy^2)).
template <int dim, int nv>
void deformation_J_von_mises(const DeformationStencils<dim, nv>& s, Kokkos::View<const double*, MemSpace> x,
                             Kokkos::View<double*, MemSpace> J, Kokkos::View<double*, MemSpace> von_mises) {
  Kokkos::parallel_for(
      "deformation_J_von_mises", Kokkos::RangePolicy<ExecSpace>(0, s.size()), KOKKOS_LAMBDA(const LO q) {
        const Mat<dim> F = stencil_F(s, x, q);
        J(q) = F.determinant();
        if (von_mises.extent(0) > 0) von_mises(q) = von_mises_of<dim>(s.materials(s.material(q)), F);
      });
}

template <int dim, int nv>
double deformation_min_J(const DeformationStencils<dim, nv>& s, Kokkos::View<const double*, MemSpace> x) {
  double jmin = 0;
  Kokkos::parallel_reduce(
      "deformation_min_J", Kokkos::RangePolicy<ExecSpace>(0, s.size()),
      KOKKOS_LAMBDA(const LO q, double& acc) {
        const double j = stencil_F(s, x, q).determinant();
        if (j < acc) acc = j;
      },
      Kokkos::Min<double>(jmin));
  return jmin;
}

}  // namespace bfemp
