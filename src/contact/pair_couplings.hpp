#pragma once
// Graph couplings of contact pairs (particle q, primitive j): every grid node
// of the particle's stencil with every vertex of the primitive (both orders),
// the vertices among themselves, and the stencil's own block (the MPM
// elasticity has it too; a contact term declares it itself so that it never
// relies on another term's graph entries).
//
// Declared per run of consecutive pairs whose particles have the same
// stencil nodes (pairs sorted by particle; particles sorted by grid cell
// share a stencil): the stencil's block once per run, and the stencil with
// each distinct vertex of the run's primitives once (the run's vertices
// sorted and merged per run, as the node graph merges its rows). Per pair
// these were 27 x 3 x 2 products in 3D, most of them repeats: on the paper
// twist (76e3 pairs on about 5e3 particles and 350 stencils per rank) the
// barrier's declarations and the node graph's sort took most of a graph
// build. The vertices among themselves stay per pair (nv^2 each).
//
// n pairs; pair k is (q_of(k), j_of(k)). pn: the particles' stencil nodes
// (n_particles x ns); vn, vc: the primitives' vertices and vertex counts
// (vc >= 1). Allocates its scratch (run starts, the runs' vertices) per call:
// a graph build, not a Newton iteration.
#include <KokkosKernels_SparseUtils.hpp>

#include "core/types.hpp"
#include "kernels/node_graph.hpp"

namespace bfemp {

template <class QOf, class JOf, class StencilNodes, class PrimNodes, class PrimCount>
void add_pair_couplings(NodeGraphBuilder& graph, long n, QOf q_of, JOf j_of, const StencilNodes& pn,
                        const PrimNodes& vn, const PrimCount& vc) {
  if (n <= 0) return;
  const int ns = static_cast<int>(pn.extent(1));
  const int nv = static_cast<int>(vn.extent(1));
  using RowMap = NodeGraphBuilder::RowMap;
  using Entries = NodeGraphBuilder::Entries;
  // Runs: pair k starts one unless its particle's stencil equals pair k-1's.
  RowMap start_of(Kokkos::ViewAllocateWithoutInitializing("pair_couplings_run_of"), static_cast<std::size_t>(n));
  long runs = 0;
  Kokkos::parallel_scan(
      "pair_couplings_runs", Kokkos::RangePolicy<ExecSpace>(0, n),
      KOKKOS_LAMBDA(const long k, long& acc, const bool final) {
        bool same = k > 0;
        if (same) {
          const LO q = q_of(k), r = q_of(k - 1);
          for (int a = 0; a < ns && same; ++a) same = pn(q, a) == pn(r, a);
        }
        if (!same) {
          if (final) start_of(acc) = static_cast<std::size_t>(k);
          ++acc;
        }
      },
      runs);
  // Each run's vertices (nv slots per pair; a triangle's third slot on a
  // segment repeats its first vertex), then sorted and merged per run.
  RowMap rows(Kokkos::ViewAllocateWithoutInitializing("pair_couplings_rows"), static_cast<std::size_t>(runs) + 1);
  Entries verts(Kokkos::ViewAllocateWithoutInitializing("pair_couplings_vertices"),
                static_cast<std::size_t>(n) * nv);
  Kokkos::parallel_for(
      "pair_couplings_run_vertices", Kokkos::RangePolicy<ExecSpace>(0, runs + 1), KOKKOS_LAMBDA(const long r) {
        const std::size_t k0 = r < runs ? start_of(r) : static_cast<std::size_t>(n);
        rows(r) = k0 * nv;
        if (r == runs) return;
        const std::size_t k1 = r + 1 < runs ? start_of(r + 1) : static_cast<std::size_t>(n);
        for (std::size_t k = k0; k < k1; ++k) {
          const LO j = j_of(static_cast<long>(k));
          for (int b = 0; b < nv; ++b) verts(k * nv + b) = vn(j, b < vc(j) ? b : 0);
        }
      });
  RowMap run_rows;
  Entries run_verts;
  KokkosKernels::Impl::sort_and_merge_graph<ExecSpace, RowMap, Entries>(rows, verts, run_rows, run_verts);
  const long items = static_cast<long>(run_verts.extent(0));
  Entries run_of_item(Kokkos::ViewAllocateWithoutInitializing("pair_couplings_item_run"),
                      static_cast<std::size_t>(items));
  Kokkos::parallel_for(
      "pair_couplings_item_runs", Kokkos::RangePolicy<ExecSpace>(0, runs), KOKKOS_LAMBDA(const long r) {
        for (std::size_t s = run_rows(r); s < run_rows(r + 1); ++s) run_of_item(s) = static_cast<LO>(r);
      });
  const auto stencil = KOKKOS_LAMBDA(const long r, const int a) { return pn(q_of(static_cast<long>(start_of(r))), a); };
  graph.add_cliques(runs, ns, stencil);
  // the stencil with each of its run's vertices, both ways
  graph.add_products(
      items, ns, 1, KOKKOS_LAMBDA(const long s, const int a) { return stencil(run_of_item(s), a); },
      KOKKOS_LAMBDA(const long s, const int) { return run_verts(s); }, true);
  // the vertices among themselves
  graph.add_cliques(n, nv, KOKKOS_LAMBDA(const long k, const int b) {
    const LO j = j_of(k);
    return b < vc(j) ? vn(j, b) : LO(-1);
  });
}

}  // namespace bfemp
