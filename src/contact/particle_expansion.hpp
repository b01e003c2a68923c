#pragma once
// The particle part of a contact term, expanded once per particle: with
// stencil weights w_a at grid nodes n_a, the particle's summed gradient g_p
// (over its pairs) and summed particle block H_pp reach the system as
//   grad(n_a) += w_a g_p,    A(n_a, n_b) += w_a w_b H_pp   (with `matrix`).
// Stencil nodes in a row of the grid are usually consecutive ids, and then
// consecutive blocks of n_a's rows: each block hints the next one's position
// (DofSink::add_block checks the hint). Zero weights add nothing.
#include <Kokkos_Core.hpp>

#include "kernels/contact/contact_pair.hpp"

namespace bfemp {

template <int dim, class Sink>
KOKKOS_INLINE_FUNCTION void expand_particle_sums(const ParticleStencils<dim>& ps, LO q, const Vec<dim>& gp,
                                                 const Mat<dim>& Hpp, bool matrix, const Sink& sink) {
  constexpr int ns = ParticleStencils<dim>::ns;
  for (int a = 0; a < ns; ++a) {
    const double wa = ps.w(q, a);
    if (wa == 0.0) continue;
    const LO na = ps.nodes(q, a);
    for (int c = 0; c < dim; ++c) sink.add_gradient(na, c, wa * gp(c));
    if (!matrix) continue;
    long pos = -1;
    LO prev = -1;
    for (int b = 0; b < ns; ++b) {
      const double wab = wa * ps.w(q, b);
      if (wab == 0.0) continue;
      const LO nb = ps.nodes(q, b);
      const long hint = (pos >= 0 && nb == prev + 1) ? pos + dim : -1;
      pos = sink.add_block(na, nb, [&](int r, int c) { return wab * Hpp(r, c); }, hint);
      prev = nb;
    }
  }
}

}  // namespace bfemp
