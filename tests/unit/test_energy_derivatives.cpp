// Finite-difference checks of the assembled elastic gradient and Hessian
// w.r.t. nodal positions: FEM simplices and MPM particle stencils (F_q(x) =
// sum_i x_i grad w_iq^T F_q^n), 2D and 3D, through the same Tpetra matrix
// assembly the Newton solver uses (with the projection of dP/dF switched off:
// the projected Hessian is checked to be PSD and minimal in the material and
// projection tests).
#include <gtest/gtest.h>

#include <Tpetra_Core.hpp>
#include <Tpetra_CrsMatrix.hpp>
#include <random>

#include "mpm/mpm_bodies.hpp"
#include "common/fd_check.hpp"
#include "solver/energy_term.hpp"

using namespace bfemp;

namespace {

template <int dim, int nv>
void check_term(DeformationTerm<dim, nv>& term, LO n_nodes, Kokkos::View<double*, MemSpace> x, double fd_h,
                double tol) {
  term.set_projection(false);  // exact Hessian; the projection is tested in test_psd_projection
  fixtures::check_energy_term<dim>(term, n_nodes, x, fd_h, tol);
}

// compressed: the nodes squeezed to 55 % along x and sheared after the rest
// shape is set, so that the neo-Hookean tangent is indefinite (its PSD
// projection differs from it) and the sink's exact-Hessian path is checked.
template <int dim>
void fem_case(bool compressed = false) {
  constexpr int nv = dim + 1;
  // Two simplices sharing a facet, perturbed from rest.
  const int n_nodes = dim + 2;
  DeformationStencils<dim, nv> s;
  s.nodes = decltype(s.nodes)("n", 2);
  s.g = decltype(s.g)("g", 2);
  s.volume = decltype(s.volume)("v", 2);
  s.material = decltype(s.material)("m", 2);
  s.materials = decltype(s.materials)("mats", 1);
  MaterialParams mp;
  mp.lame = lame_from_young(1e5, 0.3);
  mp.density = 1000;
  s.materials(0) = mp;
  Kokkos::View<double*, MemSpace> X("X", n_nodes * dim);
  // Rest nodes: origin, unit axes, and a point beyond the facet.
  for (int a = 1; a <= dim; ++a) X((a)*dim + a - 1) = 1.0;
  for (int c = 0; c < dim; ++c) X((dim + 1) * dim + c) = 0.8;
  for (int e = 0; e < 2; ++e) {
    Mat<dim> Dm;
    for (int a = 0; a < nv; ++a) s.nodes(e, a) = e == 0 ? a : (a == 0 ? dim + 1 : a);
    for (int a = 1; a < nv; ++a)
      for (int c = 0; c < dim; ++c) Dm(c, a - 1) = X(s.nodes(e, a) * dim + c) - X(s.nodes(e, 0) * dim + c);
    if (Dm.determinant() < 0) {
      std::swap(s.nodes(e, 1), s.nodes(e, 2));
      Dm.col(0).swap(Dm.col(1));
    }
    const Mat<dim> inv = Dm.inverse();
    for (int j = 0; j < dim; ++j) {
      s.g(e, 0, j) = -inv.col(j).sum();
      for (int a = 1; a < nv; ++a) s.g(e, a, j) = inv(a - 1, j);
    }
    s.volume(e) = std::abs(Dm.determinant());
  }
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.02, 0.02);
  for (std::size_t i = 0; i < X.extent(0); ++i) X(i) += u(rng);
  if (compressed)
    for (int a = 0; a < n_nodes; ++a) X(a * dim) = 0.55 * X(a * dim) + 0.3 * X(a * dim + 1);
  DeformationTerm<dim, nv> term("fem", s);
  check_term(term, n_nodes, X, 1e-6, 1e-6);
  if (compressed) EXPECT_GT(fixtures::check_sink_exact_hessian<dim>(term, n_nodes, X), 0u);
}

// compressed: F^n about 0.5 I (indefinite tangent, as for fem_case).
template <int dim>
void mpm_case(bool compressed = false) {
  constexpr int ns = bspline_stencil_size<dim>;
  GridSpec<dim> grid = grid_covering<dim>(Vec<dim>::Constant(0.0), Vec<dim>::Constant(0.3), 0.1);
  auto p = allocate_particles<dim>(3);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> pos(0.1, 0.2), pert(-0.05, 0.05);
  MaterialParams mp;
  mp.lame = lame_from_young(1e4, 0.25);
  mp.density = 100;
  Kokkos::View<MaterialParams*, MemSpace> mats("mats", 1);
  mats(0) = mp;
  for (int q = 0; q < 3; ++q) {
    for (int d = 0; d < dim; ++d) p.x(q, d) = pos(rng);
    for (int i = 0; i < dim; ++i)
      for (int j = 0; j < dim; ++j) p.F(q, i, j) = (compressed ? 0.5 : 1.0) * (i == j) + pert(rng);  // F^n away from I
    p.volume0(q) = 1e-3;
    p.mass(q) = 0.1;
  }
  Kokkos::View<LO*, MemSpace> system_node("sn", grid.num_nodes());
  Kokkos::View<LO*, MemSpace> grid_node;
  const LO n = activate_grid<dim>(grid, p, 0, system_node, grid_node);
  DeformationStencils<dim, ns> s;
  s.nodes = decltype(s.nodes)("n", 3);
  s.g = decltype(s.g)("g", 3);
  s.volume = decltype(s.volume)("v", 3);
  s.material = decltype(s.material)("m", 3);
  s.materials = mats;
  mpm_stencils<dim>(grid, p, system_node, s);
  // Grid positions x^n, slightly displaced.
  Kokkos::View<double*, MemSpace> x("x", n * dim);
  std::uniform_real_distribution<double> disp(-0.002, 0.002);
  for (LO k = 0; k < n; ++k) {
    const Vec<dim> xi = grid.node_position(grid_node(k));
    for (int c = 0; c < dim; ++c) x(k * dim + c) = xi(c) + disp(rng);
  }
  MpmElasticityTerm<dim> term("mpm", s);
  ParticleCells<dim> cells;  // the per-cell assembly (the sweep)
  bin_particles<dim>(grid, p, cells);
  term.set_cells(cells);
  check_term(term, n, x, 1e-7, 1e-5);
  if (compressed) EXPECT_GT(fixtures::check_sink_exact_hessian<dim>(term, n, x), 0u);
}

}  // namespace

TEST(EnergyDerivatives, FemTriangles) { fem_case<2>(); }
TEST(EnergyDerivatives, FemTetrahedra) { fem_case<3>(); }
TEST(EnergyDerivatives, MpmParticles2D) { mpm_case<2>(); }
TEST(EnergyDerivatives, MpmParticles3D) { mpm_case<3>(); }
TEST(EnergyDerivatives, CompressedFemTrianglesExactThroughTheSink) { fem_case<2>(true); }
TEST(EnergyDerivatives, CompressedFemTetrahedraExactThroughTheSink) { fem_case<3>(true); }
TEST(EnergyDerivatives, CompressedMpmParticles2DExactThroughTheSink) { mpm_case<2>(true); }
TEST(EnergyDerivatives, CompressedMpmParticles3DExactThroughTheSink) { mpm_case<3>(true); }
