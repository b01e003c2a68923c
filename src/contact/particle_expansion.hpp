#pragma once
// The particle part of a contact term, expanded through the particle's
// stencil: with stencil weights w_a at grid nodes n_a, the particle's summed
// gradient g_p (over its pairs) and summed particle block H_pp (symmetric)
// reach the system as
//   grad(n_a) += w_a g_p,    A(n_a, n_b) += w_a w_b H_pp   (with `matrix`).
//
// Two ways, the same sums to round-off:
// - expand_particle_sums: one particle at a time, straight into the sink
//   (atomic adds when the sink's are). Stencil nodes in a row of the grid are
//   usually consecutive ids, and then consecutive blocks of n_a's rows: each
//   block hints the next one's position (DofSink::add_block checks the hint).
//   Zero weights add nothing. In 3D that is 729 3x3 blocks per particle.
// - ParticleSums + expand_by_cell: the terms store each particle's (g_p,
//   H_pp); the particles of one MPM cell (mpm/particle_cells.hpp: the same
//   3^dim nodes) are summed in a local stencil matrix,
//     G_a = sum_q w_qa g_q,   H_ab = sum_q w_qa w_qb H_q   (a <= b; H_ba = H_ab: scalar weights),
//   and each cell adds it once, the cells of one color in parallel without
//   atomics, the particles of a cell in increasing index order (the sums do
//   not depend on the thread count). The cost per contact particle is the
//   local sums' ns (ns + 1) / 2 dim^2 multiply-adds; per cell, one scatter.
#include <Kokkos_Core.hpp>

#include "kernels/contact/contact_pair.hpp"
#include "mpm/particle_cells.hpp"

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

// Per-particle (g_p, H_pp) of one assembly, for expand_by_cell. `mark(q)` = 1
// for a particle whose sums are stored; expand_by_cell clears the marks it
// uses, so the buffers serve the next assembly without a reset pass.
// Capacity: one row per MPM particle (the cells' particles), kept while the
// particle count does not change (not per assembly).
template <int dim>
struct ParticleSums {
  static constexpr int width = dim + dim * dim;
  Kokkos::View<double* [width], MemSpace> sum;
  Kokkos::View<int*, MemSpace> mark;

  void reserve(LO n_particles) {
    if (static_cast<LO>(mark.extent(0)) == n_particles) return;
    sum = Kokkos::View<double* [width], MemSpace>(Kokkos::ViewAllocateWithoutInitializing("contact_particle_sums"),
                                                  n_particles);
    mark = Kokkos::View<int*, MemSpace>("contact_particle_marks", n_particles);
  }
  LO capacity() const { return static_cast<LO>(mark.extent(0)); }

  // Particle q's sums (q < capacity(); one writer per particle).
  KOKKOS_INLINE_FUNCTION void store(LO q, const Vec<dim>& gp, const Mat<dim>& Hpp) const {
    for (int c = 0; c < dim; ++c) sum(q, c) = gp(c);
    for (int r = 0; r < dim; ++r)
      for (int c = 0; c < dim; ++c) sum(q, dim + r * dim + c) = Hpp(r, c);
    mark(q) = 1;
  }
};

// Adds the stored sums of the marked particles through their stencils (see
// the top of this file: gradient and matrix) and clears their marks. cells: the binning of the
// particles ps covers (their first cells.order.extent(0) points); the sink's
// atomic flag is ignored (the colors make the adds race-free).
template <int dim, class Sink>
void expand_by_cell(const ParticleCells<dim>& pc, const ParticleStencils<dim>& ps, const ParticleSums<dim>& sums,
                    const Sink& sink_in) {
  constexpr int ns = ParticleStencils<dim>::ns;
  constexpr int nc = ParticleCells<dim>::n_colors;
  Sink sink = sink_in;
  sink.atomic = false;
  const auto cells = pc.cells;
  const auto start = pc.start;
  const auto count = pc.count;
  const auto order = pc.order;
  for (int color = 0; color < nc; ++color) {
    const LO c0 = pc.color_start(color), c1 = pc.color_start(color + 1);
    if (c1 == c0) continue;
    Kokkos::parallel_for(
        "contact_expand_by_cell", Kokkos::RangePolicy<ExecSpace>(c0, c1), KOKKOS_LAMBDA(const LO k) {
          const LO n = cells(k);
          const LO first = start(n), last = first + count(n);
          LO q0 = -1;
          for (LO i = first; i < last && q0 < 0; ++i)
            if (sums.mark(order(i))) q0 = order(i);
          if (q0 < 0) return;
          double G[ns][dim] = {};
          double W[ns] = {};  // sum of the weights: a node no particle weighs adds nothing
          double H[ns * (ns + 1) / 2][dim * dim] = {};  // blocks a <= b, row-major upper triangle
          for (LO i = first; i < last; ++i) {
            const LO q = order(i);
            if (!sums.mark(q)) continue;
            sums.mark(q) = 0;
            double w[ns];
            for (int a = 0; a < ns; ++a) w[a] = ps.w(q, a);
            for (int a = 0; a < ns; ++a) {
              W[a] += w[a];
              for (int c = 0; c < dim; ++c) G[a][c] += w[a] * sums.sum(q, c);
            }
            double h[dim * dim];
            for (int e = 0; e < dim * dim; ++e) h[e] = sums.sum(q, dim + e);
            int ab = 0;
            for (int a = 0; a < ns; ++a) {
              if (w[a] == 0.0) {
                ab += ns - a;
                continue;
              }
              for (int b = a; b < ns; ++b, ++ab) {
                const double wab = w[a] * w[b];
                for (int e = 0; e < dim * dim; ++e) H[ab][e] += wab * h[e];
              }
            }
          }
          LO nodes[ns];
          for (int a = 0; a < ns; ++a) nodes[a] = ps.nodes(q0, a);
          for (int a = 0; a < ns; ++a) {
            if (W[a] == 0.0) continue;
            for (int c = 0; c < dim; ++c) sink.add_gradient(nodes[a], c, G[a][c]);
            long pos = -1;
            LO prev = -1;
            for (int b = 0; b < ns; ++b) {
              if (W[b] == 0.0) continue;
              // block (a, b): H_ab for a <= b, else H_ba (the same sum: the weights are scalars)
              const int lo = a < b ? a : b, hi = a < b ? b : a;
              const double* blk = H[lo * ns - lo * (lo - 1) / 2 + (hi - lo)];
              const long hint = (pos >= 0 && nodes[b] == prev + 1) ? pos + dim : -1;
              pos = sink.add_block(nodes[a], nodes[b], [&](int r, int c) { return blk[r * dim + c]; }, hint);
              prev = nodes[b];
            }
          }
        });
  }
}

}  // namespace bfemp
