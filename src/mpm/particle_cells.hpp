#pragma once
// Particles binned by the base node of their quadratic B-spline stencil (the
// lowest node of their 3^dim support), rebuilt once per step on the device:
//   cell n   = a grid node that is the base of at least one particle's stencil;
//              all its particles share the same 3^dim nodes;
//   color(n) = sum_d (i_d mod 3) 3^d, i the node's multi-index (9 colors in
//              2D, 27 in 3D). Two cells of one color have bases 3k apart on
//              some axis, so their supports (3 nodes wide) are disjoint: the
//              cells of a color can be assembled in parallel without atomics.
// Within a cell the particles are in increasing index order, so sums over a
// cell do not depend on the thread count.
//
// The sweep (what the MPM elasticity assembly runs): the colors leave no two
// cells that run one after the other with a node in common, so every cell's
// 3^dim x 3^dim node blocks are fetched anew from a matrix far larger than
// the caches. The sweep visits the cells in node order instead (x fastest):
// consecutive cells share two thirds of their nodes. Its layer is a cell's
// index along the last axis; the layers are cut into at most kSlabs slabs
// [b_s, b_s+1) with about equal particle counts (each holds an equal share of
// the particles the slabs before it left), each at least 4 layers thick
// except the last. Phase A runs, slab by slab in parallel, the layers
// [b_s + 2, b_s+1) (slab 0 from b_0), phase B then the two layers [b_s,
// b_s + 2) of slabs s >= 1. A cell spans its layer and the next two, so two
// cells share a node only if their layers differ by at most 2: phase A's
// ranges are 3 layers apart, phase B's at least 3 (the slabs are 4 thick),
// and neither phase needs atomics (every cell's stencil lies inside the grid,
// as bspline_stencil guarantees). The slabs depend on the particles only, so
// every matrix entry sums its cells in the same order at any thread count.
// Limits: at most kSlabs threads work in a phase, and a body thin along the
// last axis gives few slabs; `slabs` (host) counts those with cells, and
// MpmElasticityTerm falls back to the colors when they are too few for the
// threads (then the sums' order depends on the thread count).
//
// The occupied set is compared with the previous step's: `version` changes
// only when it does (the MPM part of the Newton graph depends on nothing
// else).
// No allocation per step unless the grid grows or the particle count changes.
#include <Kokkos_Core.hpp>
#include <array>
#include <cstdint>

#include "kernels/mpm/bspline.hpp"
#include "kernels/mpm/grid.hpp"
#include "kernels/mpm/particles.hpp"

namespace bfemp {

template <int dim>
struct ParticleCells {
  static constexpr int n_colors = dim == 2 ? 9 : 27;
  Kokkos::View<LO*, MemSpace> count;        // per grid node: particles with that base
  Kokkos::View<LO*, MemSpace> start;        // per grid node: first slot in `order`
  Kokkos::View<LO*, MemSpace> order;        // particle ids, grouped by cell
  Kokkos::View<LO*, MemSpace> cells;        // occupied base nodes, grouped by color
  Kokkos::View<LO*, MemSpace> occupied_prev;  // last step's count > 0 flags
  Kokkos::View<LO[n_colors + 1], MemSpace> color_start_dev;
  Kokkos::View<LO[n_colors], MemSpace> color_cursor;
  Kokkos::View<LO[n_colors + 1], Kokkos::HostSpace> color_start;  // host copy (28 ints)
  LO n_cells = 0;
  std::uint64_t version = 0;
  // The sweep: sweep(i) = k (an index into `cells`), the occupied cells in node
  // order; slab s runs sweep[phase(4 s), phase(4 s + 1)) in phase A and
  // sweep[phase(4 s + 2), phase(4 s + 3)) in phase B (device view, set per step).
  static constexpr int kSlabs = 8;
  static constexpr int kSlabLayers = 4;
  Kokkos::View<LO*, MemSpace> sweep;
  Kokkos::View<LO*, MemSpace> node_rank;  // per grid node: occupied cells before it in node order
  Kokkos::View<LO[4 * kSlabs], MemSpace> phase;
  Kokkos::View<LO, MemSpace> slabs_dev;
  LO slabs = 0;  // slabs with cells (host copy)
};

template <int dim>
KOKKOS_INLINE_FUNCTION int cell_color(const GridSpec<dim>& grid, LO node) {
  const GridIndex<dim> i = grid.node_multi_index(node);
  int c = 0, m = 1;
  for (int d = 0; d < dim; ++d) {
    c += (i[d] % 3) * m;
    m *= 3;
  }
  return c;
}

// The sweep's slabs and phase ranges (see above), from the particles before
// each layer (start of its first node) and the occupied cells before it
// (node_rank); one device task, a loop over the layers.
template <int dim>
void set_sweep_slabs(const GridSpec<dim>& grid, LO np, ParticleCells<dim>& pc) {
  constexpr int S = ParticleCells<dim>::kSlabs;
  constexpr int thick = ParticleCells<dim>::kSlabLayers;
  const LO layers = grid.nodes_along(dim - 1);
  const LO layer_nodes = grid.num_nodes() / layers;
  const auto start = pc.start;
  const auto rank = pc.node_rank;
  const auto count = pc.count;
  const auto phase = pc.phase;
  const auto slabs = pc.slabs_dev;
  const LO n_nodes = grid.num_nodes();
  Kokkos::parallel_for(
      "mpm_sweep_slabs", Kokkos::RangePolicy<ExecSpace>(0, 1), KOKKOS_LAMBDA(const int) {
        // Each slab ends at the first layer (at least `thick` on) where it holds
        // an equal share of the particles not in the slabs before it.
        LO b[S + 1];
        b[0] = 0;
        int s = 1;
        long long before = 0;  // particles in the slabs before slab s - 1
        for (LO L = 1; L < layers && s < S; ++L) {
          const long long upto = start(L * layer_nodes);
          if ((upto - before) * (S - s + 1) >= static_cast<long long>(np) - before && L - b[s - 1] >= thick) {
            b[s++] = L;
            before = upto;
          }
        }
        for (; s <= S; ++s) b[s] = layers;
        const LO total = rank(n_nodes - 1) + (count(n_nodes - 1) > 0 ? 1 : 0);
        auto pos = [&](LO L) { return L >= layers ? total : rank(L * layer_nodes); };
        for (int t = 0; t < S; ++t) {
          const LO mid = t == 0 ? b[0] : (b[t] + 2 < b[t + 1] ? b[t] + 2 : b[t + 1]);
          phase(4 * t) = pos(mid);
          phase(4 * t + 1) = pos(b[t + 1]);
          phase(4 * t + 2) = pos(b[t]);
          phase(4 * t + 3) = pos(mid);
        }
        LO used = 0;
        for (int t = 0; t < S; ++t) used += pos(b[t + 1]) > pos(b[t]) ? 1 : 0;
        slabs() = used;
      });
  Kokkos::deep_copy(pc.slabs, pc.slabs_dev);
}

// key (optional, one per particle, distinct): the order within a cell is by
// increasing key instead of increasing index (the periodic sort passes the
// particles' global ids, so that the sorted order depends on the positions
// and ids alone, not on the order the particles had before).
template <int dim>
void bin_particles(const GridSpec<dim>& grid, const Particles<dim>& p, ParticleCells<dim>& pc,
                   Kokkos::View<const long long*, MemSpace> key = {}) {
  constexpr int nc = ParticleCells<dim>::n_colors;
  const LO n_nodes = grid.num_nodes();
  const LO np = static_cast<LO>(p.size());
  bool reshaped = false;
  if (static_cast<LO>(pc.count.extent(0)) != n_nodes) {
    pc.count = Kokkos::View<LO*, MemSpace>("mpm_cell_count", n_nodes);
    pc.start = Kokkos::View<LO*, MemSpace>("mpm_cell_start", n_nodes);
    pc.occupied_prev = Kokkos::View<LO*, MemSpace>("mpm_cell_occupied_prev", n_nodes);
    pc.cells = Kokkos::View<LO*, MemSpace>("mpm_cells", n_nodes);
    pc.sweep = Kokkos::View<LO*, MemSpace>("mpm_cell_sweep", n_nodes);
    pc.node_rank = Kokkos::View<LO*, MemSpace>("mpm_cell_node_rank", n_nodes);
    reshaped = true;
  }
  if (static_cast<LO>(pc.order.extent(0)) != np) pc.order = Kokkos::View<LO*, MemSpace>("mpm_cell_order", np);
  if (pc.color_start_dev.data() == nullptr) {
    pc.phase = decltype(pc.phase)("mpm_sweep_phase");
    pc.slabs_dev = decltype(pc.slabs_dev)("mpm_sweep_slabs");
    pc.color_start_dev = decltype(pc.color_start_dev)("mpm_color_start");
    pc.color_start = decltype(pc.color_start)("mpm_color_start_host");
    pc.color_cursor = decltype(pc.color_cursor)("mpm_color_cursor");
  }
  auto count = pc.count;
  auto start = pc.start;
  auto order = pc.order;
  auto cells = pc.cells;
  auto prev = pc.occupied_prev;
  auto cs = pc.color_start_dev;
  Kokkos::deep_copy(count, 0);
  Kokkos::deep_copy(cs, 0);
  auto base_of = KOKKOS_LAMBDA(const LO q) {
    const auto st = bspline_stencil(grid, particle_position(p, q));
    return node_index(grid, st, 0);
  };
  Kokkos::parallel_for(
      "mpm_cell_count", Kokkos::RangePolicy<ExecSpace>(0, np),
      KOKKOS_LAMBDA(const LO q) { Kokkos::atomic_increment(&count(base_of(q))); });
  // Slots per cell; occupied cells per color; changes against the last step.
  LO changed = 0;
  Kokkos::parallel_reduce(
      "mpm_cell_colors", Kokkos::RangePolicy<ExecSpace>(0, n_nodes),
      KOKKOS_LAMBDA(const LO n, LO& acc) {
        const LO occ = count(n) > 0 ? 1 : 0;
        if (occ) Kokkos::atomic_increment(&cs(cell_color(grid, n) + 1));
        if (occ != prev(n)) ++acc;
        prev(n) = occ;
      },
      changed);
  Kokkos::parallel_scan(
      "mpm_cell_start", Kokkos::RangePolicy<ExecSpace>(0, n_nodes),
      KOKKOS_LAMBDA(const LO n, LO& offset, const bool final) {
        if (final) start(n) = offset;
        offset += count(n);
      });
  auto rank = pc.node_rank;
  Kokkos::parallel_scan(
      "mpm_cell_node_rank", Kokkos::RangePolicy<ExecSpace>(0, n_nodes),
      KOKKOS_LAMBDA(const LO n, LO& offset, const bool final) {
        if (final) rank(n) = offset;
        offset += count(n) > 0 ? 1 : 0;
      });
  set_sweep_slabs(grid, np, pc);
  Kokkos::deep_copy(pc.color_start, cs);
  for (int c = 0; c < nc; ++c) pc.color_start(c + 1) += pc.color_start(c);
  Kokkos::deep_copy(cs, pc.color_start);
  pc.n_cells = pc.color_start(nc);
  // Fill: `count` is reused as the cursor (restored to the counts after).
  Kokkos::deep_copy(count, 0);
  Kokkos::parallel_for(
      "mpm_cell_fill", Kokkos::RangePolicy<ExecSpace>(0, np), KOKKOS_LAMBDA(const LO q) {
        const LO b = base_of(q);
        order(start(b) + Kokkos::atomic_fetch_add(&count(b), 1)) = q;
      });
  auto cursor = pc.color_cursor;
  auto sweep = pc.sweep;
  Kokkos::deep_copy(cursor, 0);
  Kokkos::parallel_for(
      "mpm_cell_sort", Kokkos::RangePolicy<ExecSpace>(0, n_nodes), KOKKOS_LAMBDA(const LO n) {
        const LO k = count(n);
        if (k == 0) return;
        // Increasing particle index (or key) within the cell (insertion sort; a few particles).
        const bool keyed = key.extent(0) > 0;
        for (LO i = start(n) + 1; i < start(n) + k; ++i) {
          const LO v = order(i);
          const long long kv = keyed ? key(v) : v;
          LO j = i - 1;
          while (j >= start(n) && (keyed ? key(order(j)) : order(j)) > kv) {
            order(j + 1) = order(j);
            --j;
          }
          order(j + 1) = v;
        }
        const int c = cell_color(grid, n);
        const LO slot = cs(c) + Kokkos::atomic_fetch_add(&cursor(c), 1);
        cells(slot) = n;
        sweep(rank(n)) = slot;
      });
  if (changed > 0 || reshaped) ++pc.version;
}

}  // namespace bfemp
