#pragma once
// Finite-difference check of an energy term: its gradient against central
// differences of the energy, and the Hessian it assembles into a Tpetra
// matrix (the term's own graph) against central differences of the gradient.
// Both errors are relative to the largest entry. Terms with a projection
// must have it switched off by the caller.
#include <gtest/gtest.h>

#include <Tpetra_Core.hpp>
#include <Tpetra_CrsMatrix.hpp>
#include <algorithm>
#include <cmath>

#include "solver/dof_graph.hpp"
#include "solver/energy_term.hpp"

namespace bfemp::fixtures {

template <int dim>
inline void check_energy_term(const EnergyTerm<dim>& term, LO n_nodes, Kokkos::View<double*, MemSpace> x, double fd_h,
                double tol) {
  const std::size_t nd = static_cast<std::size_t>(n_nodes) * dim;
  std::vector<long long> keys;
  term.add_couplings(keys, n_nodes);
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

}  // namespace bfemp::fixtures
