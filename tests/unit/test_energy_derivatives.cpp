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
#include "solver/dof_graph.hpp"
#include "solver/energy_term.hpp"

using namespace bfemp;

namespace {

template <int dim, int nv>
void check_term(DeformationTerm<dim, nv>& term, LO n_nodes, Kokkos::View<double*, MemSpace> x, double fd_h,
                double tol) {
  const std::size_t nd = static_cast<std::size_t>(n_nodes) * dim;
  std::vector<long long> keys;
  term.add_couplings(keys, n_nodes);
  term.set_projection(false);  // exact Hessian; the projection is tested in test_psd_projection
  auto map = Teuchos::rcp(new Map(nd, 0, Tpetra::getDefaultComm()));
  auto A = Teuchos::rcp(new Matrix(build_dof_graph<dim>(keys, n_nodes, map)));
  A->fillComplete();
  A->resumeFill();
  A->setAllToScalar(0.0);
  Kokkos::View<double*, MemSpace> grad("grad", nd), rhs("rhs", nd), dxp("dxp", nd);
  Kokkos::View<int*, MemSpace> pres("pres", nd);
  term.assemble(x, 1.0, grad, A->getLocalMatrixDevice(), pres, dxp, rhs);
  A->fillComplete();
  // Gradient vs central differences of the energy.
  auto xh = Kokkos::create_mirror_view(x);
  double gmax = 0, gerr = 0;
  for (std::size_t i = 0; i < nd; ++i) {
    const double x0 = xh(i);
    xh(i) = x0 + fd_h;
    const double ep = term.energy(x);
    xh(i) = x0 - fd_h;
    const double em = term.energy(x);
    xh(i) = x0;
    gerr = std::max(gerr, std::abs((ep - em) / (2 * fd_h) - grad(i)));
    gmax = std::max(gmax, std::abs(grad(i)));
  }
  EXPECT_LT(gerr, tol * gmax) << "gradient";
  // Hessian columns vs central differences of the gradient.
  double herr = 0, hmax = 0;
  Kokkos::View<double*, MemSpace> gp("gp", nd), gm("gm", nd);
  for (std::size_t j = 0; j < nd; ++j) {
    const double x0 = xh(j);
    Kokkos::deep_copy(gp, 0.0);
    Kokkos::deep_copy(gm, 0.0);
    xh(j) = x0 + fd_h;
    term.gradient(x, 1.0, gp);
    xh(j) = x0 - fd_h;
    term.gradient(x, 1.0, gm);
    xh(j) = x0;
    for (std::size_t i = 0; i < nd; ++i) {
      double aij = 0;
      typename Matrix::nonconst_local_inds_host_view_type cols("c", A->getNumEntriesInLocalRow(i));
      typename Matrix::nonconst_values_host_view_type vals("v", A->getNumEntriesInLocalRow(i));
      size_t n = 0;
      A->getLocalRowCopy(i, cols, vals, n);
      for (size_t k = 0; k < n; ++k)
        if (static_cast<std::size_t>(cols(k)) == j) aij = vals(k);
      herr = std::max(herr, std::abs((gp(i) - gm(i)) / (2 * fd_h) - aij));
      hmax = std::max(hmax, std::abs(aij));
    }
  }
  EXPECT_LT(herr, tol * hmax) << "Hessian";
}

template <int dim>
void fem_case() {
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
  DeformationTerm<dim, nv> term("fem", s);
  check_term(term, n_nodes, X, 1e-6, 1e-6);
}

template <int dim>
void mpm_case() {
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
      for (int j = 0; j < dim; ++j) p.F(q, i, j) = (i == j) + pert(rng);  // F^n away from I
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
  check_term(term, n, x, 1e-7, 1e-5);
}

}  // namespace

TEST(EnergyDerivatives, FemTriangles) { fem_case<2>(); }
TEST(EnergyDerivatives, FemTetrahedra) { fem_case<3>(); }
TEST(EnergyDerivatives, MpmParticles2D) { mpm_case<2>(); }
TEST(EnergyDerivatives, MpmParticles3D) { mpm_case<3>(); }
