#pragma once
// Graph couplings of contact pairs (particle q, primitive j): every grid node
// of the particle's stencil with every vertex of the primitive (both orders),
// the vertices among themselves, and the stencil's own block (the MPM
// elasticity has it too; a contact term declares it itself so that it never
// relies on another term's graph entries), declared once per run of pairs of
// the same particle (pairs sorted by particle declare it once per particle).
//
// n pairs; pair k is (q_of(k), j_of(k)). pn: the particles' stencil nodes
// (n_particles x ns); vn, vc: the primitives' vertices and vertex counts.
#include "core/types.hpp"
#include "kernels/node_graph.hpp"

namespace bfemp {

template <class QOf, class JOf, class StencilNodes, class PrimNodes, class PrimCount>
void add_pair_couplings(NodeGraphBuilder& graph, long n, QOf q_of, JOf j_of, const StencilNodes& pn,
                        const PrimNodes& vn, const PrimCount& vc) {
  const int ns = static_cast<int>(pn.extent(1));
  const int nv = static_cast<int>(vn.extent(1));
  graph.add_cliques(n, ns, KOKKOS_LAMBDA(const long k, const int a) {
    const LO q = q_of(k);
    return k > 0 && q_of(k - 1) == q ? LO(-1) : pn(q, a);
  });
  const auto vertex = KOKKOS_LAMBDA(const long k, const int b) {
    const LO j = j_of(k);
    return b < vc(j) ? vn(j, b) : LO(-1);
  };
  // the stencil with the vertices, both ways; the vertices among themselves
  graph.add_products(
      n, ns, nv, KOKKOS_LAMBDA(const long k, const int a) { return pn(q_of(k), a); }, vertex, true);
  graph.add_cliques(n, nv, vertex);
}

}  // namespace bfemp
