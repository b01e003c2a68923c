#pragma once
// Graph couplings of a contact pair (particle q, primitive j): every grid node
// of the particle's stencil with every vertex (both orders), and the vertices
// among themselves; with `stencil_block` also the stencil's own block (the
// MPM elasticity has it too; a term asks for it once per particle so that it
// never relies on another term's graph entries).
#include <vector>

#include "core/types.hpp"

namespace bfemp {

template <class StencilNodes, class PrimNodes, class PrimCount>
void add_pair_couplings(const StencilNodes& pn, const PrimNodes& vn, const PrimCount& vc, LO q, LO j, LO n_nodes,
                        bool stencil_block, std::vector<long long>& keys) {
  const long long N = n_nodes;
  if (stencil_block)
    for (std::size_t a = 0; a < pn.extent(1); ++a)
      for (std::size_t b = 0; b < pn.extent(1); ++b) keys.push_back(pn(q, a) * N + pn(q, b));
  for (int i = 0; i < vc(j); ++i) {
    const long long v = vn(j, i);
    for (std::size_t a = 0; a < pn.extent(1); ++a) {
      keys.push_back(pn(q, a) * N + v);
      keys.push_back(v * N + pn(q, a));
    }
    for (int k = 0; k < vc(j); ++k) keys.push_back(v * N + vn(j, k));
  }
}

}  // namespace bfemp
