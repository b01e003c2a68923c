#pragma once
// Greedy coloring of stencils (FEM elements) so that no two stencils of one
// color share a node: the stencils of a color can add into the matrix in
// parallel without atomics, and the sums no longer depend on the thread count.
// Each stencil takes the smallest color none of its nodes has seen (at most
// 128 colors; a simplex mesh needs a few tens). Computed once on the host when
// the mesh is built; `order` lists the stencils color by color.
#include <Kokkos_Core.hpp>
#include <cstdint>
#include <stdexcept>
#include <vector>

#include "core/types.hpp"

namespace bfemp {

struct StencilColoring {
  Kokkos::View<LO*, MemSpace> order;  // stencil ids grouped by color
  std::vector<LO> color_start;        // host: colors c -> order[color_start[c], color_start[c+1])
  int colors() const { return color_start.empty() ? 0 : static_cast<int>(color_start.size()) - 1; }
};

template <int nv, class NodesView>
StencilColoring color_stencils(const NodesView& nodes_dev, LO n_nodes) {
  auto nodes = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), nodes_dev);
  const LO n = static_cast<LO>(nodes.extent(0));
  std::vector<std::uint64_t> used(2 * static_cast<std::size_t>(n_nodes), 0);  // 128 color bits per node
  std::vector<int> color(n);
  int n_colors = 0;
  for (LO q = 0; q < n; ++q) {
    std::uint64_t m0 = 0, m1 = 0;
    for (int a = 0; a < nv; ++a) {
      m0 |= used[2 * nodes(q, a)];
      m1 |= used[2 * nodes(q, a) + 1];
    }
    int c = 0;
    while (c < 128 && ((c < 64 ? m0 >> c : m1 >> (c - 64)) & 1)) ++c;
    if (c == 128) throw std::runtime_error("color_stencils: more than 128 colors needed");
    color[q] = c;
    n_colors = std::max(n_colors, c + 1);
    for (int a = 0; a < nv; ++a) used[2 * nodes(q, a) + (c / 64)] |= std::uint64_t(1) << (c % 64);
  }
  StencilColoring out;
  out.color_start.assign(n_colors + 1, 0);
  for (LO q = 0; q < n; ++q) ++out.color_start[color[q] + 1];
  for (int c = 0; c < n_colors; ++c) out.color_start[c + 1] += out.color_start[c];
  std::vector<LO> cursor(out.color_start.begin(), out.color_start.end() - 1);
  out.order = Kokkos::View<LO*, MemSpace>("fem_color_order", n);
  auto h = Kokkos::create_mirror_view(out.order);
  for (LO q = 0; q < n; ++q) h(cursor[color[q]]++) = q;
  Kokkos::deep_copy(out.order, h);
  return out;
}

}  // namespace bfemp
