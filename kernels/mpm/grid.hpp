#pragma once
// Uniform Cartesian background grid of the MPM domain: nodes at
// origin + dx * i for i in [0, n_cells] per axis, numbered linearly with x
// fastest. Plain data (copied into kernels by value); every helper callable
// inside a kernel.
//
// A particle at x is usable on the grid when the whole 3^dim support of its
// quadratic B-spline stencil lies inside the node range: with the cell
// coordinate s = (x - origin) / dx, the lowest stencil node is
// floor(s - 1/2) >= 0 and the highest floor(s - 1/2) + 2 <= n_cells, i.e.
// 1/2 <= s < n_cells - 1/2 on every axis.
#include <Kokkos_Core.hpp>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>

#include "core/types.hpp"

namespace bfemp {

// Multi-index of a grid node (or cell), one entry per axis.
template <int dim>
using GridIndex = std::array<int, dim>;

template <int dim>
struct GridSpec {
  static_assert(dim == 2 || dim == 3, "GridSpec: dim must be 2 or 3");
  Vec<dim> origin = Vec<dim>::Zero();
  double dx = 0.0;
  std::array<int, dim> n_cells{};

  // Nodes along axis d: n_cells[d] + 1.
  KOKKOS_INLINE_FUNCTION int nodes_along(int d) const { return n_cells[d] + 1; }

  KOKKOS_INLINE_FUNCTION LO num_nodes() const {
    LO n = 1;
    for (int d = 0; d < dim; ++d) n *= nodes_along(d);
    return n;
  }

  // Linear index of node i (x fastest): i[0] + N0 * (i[1] + N1 * i[2]).
  KOKKOS_INLINE_FUNCTION LO node_index(const GridIndex<dim>& i) const {
    LO n = i[dim - 1];
    for (int d = dim - 2; d >= 0; --d) n = n * nodes_along(d) + i[d];
    return n;
  }

  // Inverse of node_index.
  KOKKOS_INLINE_FUNCTION GridIndex<dim> node_multi_index(LO n) const {
    GridIndex<dim> i{};
    for (int d = 0; d < dim; ++d) {
      i[d] = n % nodes_along(d);
      n /= nodes_along(d);
    }
    return i;
  }

  KOKKOS_INLINE_FUNCTION Vec<dim> node_position(const GridIndex<dim>& i) const {
    Vec<dim> x;
    for (int d = 0; d < dim; ++d) x[d] = origin[d] + dx * i[d];
    return x;
  }

  KOKKOS_INLINE_FUNCTION Vec<dim> node_position(LO n) const {
    return node_position(node_multi_index(n));
  }

  // Position along axis d in cell units, relative to the origin.
  KOKKOS_INLINE_FUNCTION double cell_coordinate(const Vec<dim>& x, int d) const {
    return (x[d] - origin[d]) / dx;
  }

  // True when the B-spline stencil of a particle at x lies inside the node
  // range (see the top of this file). NaN coordinates give false.
  KOKKOS_INLINE_FUNCTION bool contains(const Vec<dim>& x) const {
    for (int d = 0; d < dim; ++d) {
      const double r = cell_coordinate(x, d) - 0.5;  // floor(r) is the stencil base
      if (!(r >= 0.0 && r < n_cells[d] - 1.0)) return false;
    }
    return true;
  }
};

// The smallest grid with nodes on the lattice dx * Z^dim (aligned with the
// origin (0,...,0), like the particle sampling) on which every point of the box
// [lo, hi] is usable (contains() is true). Throws std::invalid_argument naming
// the argument for dx <= 0, non-finite or inverted bounds, or more nodes than
// a local ordinal can count.
template <int dim>
GridSpec<dim> grid_covering(const Vec<dim>& lo, const Vec<dim>& hi, double dx) {
  auto fail = [](const std::string& field, double value, const std::string& expected) {
    char v[32];
    std::snprintf(v, sizeof v, "%.10g", value);
    throw std::invalid_argument("grid field '" + field + "' = " + v + ": expected " + expected);
  };
  if (!(dx > 0.0) || !std::isfinite(dx)) fail("dx", dx, "a finite value > 0");
  GridSpec<dim> g;
  g.dx = dx;
  double nodes = 1.0;
  for (int d = 0; d < dim; ++d) {
    const std::string axis = "[" + std::to_string(d) + "]";
    if (!std::isfinite(lo[d])) fail("lo" + axis, lo[d], "a finite coordinate");
    if (!std::isfinite(hi[d])) fail("hi" + axis, hi[d], "a finite coordinate");
    if (hi[d] < lo[d]) fail("hi" + axis, hi[d], ">= lo" + axis);
    double first = std::floor(lo[d] / dx - 0.5);  // lattice index of the origin
    double last = std::floor(hi[d] / dx + 0.5) + 1.0;
    if (!(last - first + 1.0 < 0.5 * std::numeric_limits<LO>::max()))
      fail("dx", dx, "a larger value (axis " + std::to_string(d) + " would have " +
                         std::to_string(last - first) + " cells)");
    // Rounding of (x - origin) / dx may differ from x / dx by an ulp: adjust
    // by whole cells until both ends pass, tightly, the test contains() applies.
    auto usable = [&](double x, double f, double l) {
      const double r = (x - f * dx) / dx - 0.5;
      return r >= 0.0 && r < (l - f) - 1.0;
    };
    while (!usable(lo[d], first, last)) first -= 1.0;
    while (usable(lo[d], first + 1.0, last)) first += 1.0;
    while (!usable(hi[d], first, last)) last += 1.0;
    while (usable(hi[d], first, last - 1.0)) last -= 1.0;
    g.origin[d] = first * dx;
    g.n_cells[d] = static_cast<int>(last - first);
    nodes *= g.n_cells[d] + 1.0;
  }
  if (!(nodes < static_cast<double>(std::numeric_limits<LO>::max())))
    fail("dx", dx, "a larger value (the grid would have " + std::to_string(nodes) + " nodes)");
  return g;
}

// `g` grown by whole cells (same dx; nodes stay on the same lattice, so the
// origin moves by whole cells) until every point of [lo, hi] is usable
// (contains() is true), each side that grows getting `margin` further cells
// (the option 'MPM/when particles leave: extend'). Throws std::invalid_argument
// for non-finite bounds or when the grid would have more nodes than a local
// ordinal can count.
template <int dim>
GridSpec<dim> grid_extended(const GridSpec<dim>& g, const Vec<dim>& lo, const Vec<dim>& hi, int margin) {
  GridSpec<dim> e = g;
  double nodes = 1.0;
  for (int d = 0; d < dim; ++d) {
    if (!std::isfinite(lo[d]) || !std::isfinite(hi[d]))
      throw std::invalid_argument("grid_extended: non-finite bound on axis " + std::to_string(d));
    // Cell offsets relative to g's origin: the new grid spans cells [first, last).
    double first = 0.0, last = g.n_cells[d];
    auto usable = [&](double x, double f, double l) {
      const double r = (x - (g.origin[d] + f * g.dx)) / g.dx - 0.5;
      return r >= 0.0 && r < (l - f) - 1.0;
    };
    const double need_lo = std::floor((lo[d] - g.origin[d]) / g.dx - 0.5);
    const double need_hi = std::floor((hi[d] - g.origin[d]) / g.dx + 0.5) + 1.0;
    if (need_lo < first) first = need_lo - margin;
    if (need_hi > last) last = need_hi + margin;
    while (!usable(lo[d], first, last)) first -= 1.0;  // ulp-level rounding of (x - origin) / dx
    while (!usable(hi[d], first, last)) last += 1.0;
    if (!(last - first < 0.5 * std::numeric_limits<LO>::max()))
      throw std::invalid_argument("grid_extended: axis " + std::to_string(d) + " would have " +
                                  std::to_string(last - first) + " cells");
    e.origin[d] = g.origin[d] + first * g.dx;
    e.n_cells[d] = static_cast<int>(last - first);
    nodes *= e.n_cells[d] + 1.0;
  }
  if (!(nodes < static_cast<double>(std::numeric_limits<LO>::max())))
    throw std::invalid_argument("grid_extended: the grid would have " + std::to_string(nodes) + " nodes");
  return e;
}

}  // namespace bfemp
