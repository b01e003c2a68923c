#pragma once
// Quadratic B-spline kernel of the MPM grid (paper §3.2): the weight of node i
// at a particle x_p is w_ip = prod_d N((x_p,d - x_i,d) / dx) with
//   N(r) = 3/4 - r^2              for |r| < 1/2,
//          1/2 (3/2 - |r|)^2      for 1/2 <= |r| < 3/2,
//          0                      otherwise,
// so each particle touches a 3^dim stencil of nodes. The stencil stores the
// three 1D weights and derivatives per axis; the 3^dim nodal values are their
// tensor products, enumerated by a in [0, 3^dim) with x fastest:
// a = a_0 + 3 a_1 (+ 9 a_2), node multi-index base + (a_0, a_1, a_2).
#include <Kokkos_Core.hpp>
#include <cmath>

#include "core/types.hpp"
#include "kernels/mpm/grid.hpp"

namespace bfemp {

// Number of nodes in a stencil: 3^dim.
template <int dim>
inline constexpr int bspline_stencil_size = dim == 2 ? 9 : 27;

template <int dim>
struct BSplineStencil {
  int base[dim];      // lowest node index of the 3-node support per axis
  double w[dim][3];   // N at the three nodes, per axis
  double dw[dim][3];  // dN/dx_p (physical units, 1/dx) at the three nodes
};

// 1D values at the nodes base, base + 1, base + 2 for a particle at cell
// coordinate base + f (f in [1/2, 3/2) up to rounding; the polynomials below
// are used as they are outside that range too, which keeps partition of unity
// and linear reproduction exact as polynomial identities).
KOKKOS_INLINE_FUNCTION void bspline_weights_1d(double f, double inv_dx, double* w, double* dw) {
  const double a = 1.5 - f;  // distance to node 0 is f, in [1/2, 3/2)
  const double b = f - 1.0;  // signed distance to node 1, in [-1/2, 1/2)
  const double c = f - 0.5;  // 3/2 - distance to node 2
  w[0] = 0.5 * a * a;
  w[1] = 0.75 - b * b;
  w[2] = 0.5 * c * c;
  dw[0] = -a * inv_dx;
  dw[1] = -2.0 * b * inv_dx;
  dw[2] = c * inv_dx;
}

// Stencil of a particle at xp. The result is only meaningful for the grid's
// node range when grid.contains(xp); callers check that first.
template <int dim>
KOKKOS_INLINE_FUNCTION BSplineStencil<dim> bspline_stencil(const GridSpec<dim>& grid, const Vec<dim>& xp) {
  BSplineStencil<dim> s;
  const double inv_dx = 1.0 / grid.dx;
  for (int d = 0; d < dim; ++d) {
    const double r = grid.cell_coordinate(xp, d);
    s.base[d] = static_cast<int>(std::floor(r - 0.5));
    bspline_weights_1d(r - s.base[d], inv_dx, s.w[d], s.dw[d]);
  }
  return s;
}

// Per-axis offset (0, 1 or 2) of stencil node a along axis d.
KOKKOS_INLINE_FUNCTION int stencil_offset(int a, int d) {
  for (int k = 0; k < d; ++k) a /= 3;
  return a % 3;
}

// w_a: weight of the a-th stencil node.
template <int dim>
KOKKOS_INLINE_FUNCTION double weight(const BSplineStencil<dim>& s, int a) {
  double v = 1.0;
  for (int d = 0; d < dim; ++d) v *= s.w[d][stencil_offset(a, d)];
  return v;
}

// grad w_a with respect to the particle position (physical units).
template <int dim>
KOKKOS_INLINE_FUNCTION Vec<dim> weight_gradient(const BSplineStencil<dim>& s, int a) {
  int o[dim];
  for (int d = 0; d < dim; ++d) o[d] = stencil_offset(a, d);
  Vec<dim> g;
  for (int k = 0; k < dim; ++k) {
    double v = s.dw[k][o[k]];
    for (int d = 0; d < dim; ++d)
      if (d != k) v *= s.w[d][o[d]];
    g[k] = v;
  }
  return g;
}

// Grid multi-index of the a-th stencil node.
template <int dim>
KOKKOS_INLINE_FUNCTION GridIndex<dim> stencil_node(const BSplineStencil<dim>& s, int a) {
  GridIndex<dim> i{};
  for (int d = 0; d < dim; ++d) i[d] = s.base[d] + stencil_offset(a, d);
  return i;
}

// Linear grid index of the a-th stencil node (valid when grid.contains(xp)).
template <int dim>
KOKKOS_INLINE_FUNCTION LO node_index(const GridSpec<dim>& grid, const BSplineStencil<dim>& s, int a) {
  return grid.node_index(stencil_node<dim>(s, a));
}

// Visits the 3^dim nodes of the stencil of a particle at xp in the order of
// a (x fastest) and calls f(a, node, w, grad_w, r) with the node's linear
// grid index, w_a, grad w_a (physical units) and r = x_node - xp, from the
// per-axis tables: no divisions, no index decoding (the same values as
// node_index, weight, weight_gradient and grid.node_position(node) - xp, up
// to the rounding of the last).
template <int dim, class F>
KOKKOS_INLINE_FUNCTION void for_each_stencil_node(const GridSpec<dim>& grid, const BSplineStencil<dim>& s,
                                                  const Vec<dim>& xp, F&& f) {
  double r[dim][3];
  for (int d = 0; d < dim; ++d)
    for (int o = 0; o < 3; ++o) r[d][o] = grid.origin[d] + grid.dx * (s.base[d] + o) - xp[d];
  const LO n0 = grid.nodes_along(0), n01 = n0 * grid.nodes_along(1);
  GridIndex<dim> b{};
  for (int d = 0; d < dim; ++d) b[d] = s.base[d];
  const LO base = grid.node_index(b);
  int a = 0;
  for (int o2 = 0; o2 < (dim == 3 ? 3 : 1); ++o2) {
    double wz = 1.0, dwz = 0.0;
    if constexpr (dim == 3) {
      wz = s.w[2][o2];
      dwz = s.dw[2][o2];
    }
    for (int o1 = 0; o1 < 3; ++o1) {
      const double wyz = s.w[1][o1] * wz;
      for (int o0 = 0; o0 < 3; ++o0, ++a) {
        const LO node = base + o0 + n0 * o1 + n01 * o2;
        Vec<dim> g, rel;
        g[0] = s.dw[0][o0] * wyz;
        g[1] = s.w[0][o0] * s.dw[1][o1] * wz;
        rel[0] = r[0][o0];
        rel[1] = r[1][o1];
        if constexpr (dim == 3) {
          g[2] = s.w[0][o0] * s.w[1][o1] * dwz;
          rel[2] = r[2][o2];
        }
        f(a, node, s.w[0][o0] * wyz, g, rel);
      }
    }
  }
}

}  // namespace bfemp
