#pragma once
// A small MPM grid for kernel tests: 8 cells per axis of dx = 0.1 from an
// origin that is not a multiple of dx (node positions carry rounding).
#include "kernels/mpm/grid.hpp"

namespace bfemp::fixtures {

template <int dim>
GridSpec<dim> small_grid() {
  GridSpec<dim> g;
  const double o[3] = {-0.3, 0.7, 0.1};
  for (int d = 0; d < dim; ++d) {
    g.origin[d] = o[d];
    g.n_cells[d] = 8;
  }
  g.dx = 0.1;
  return g;
}

}  // namespace bfemp::fixtures
