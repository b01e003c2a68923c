#pragma once
// Where the terms of the incremental potential put their local derivatives.
//
// A stencil (an FEM element, an MPM particle or cell, a contact pair) has
// nodes n_0 .. n_{k-1} and emits a local gradient g (k*dim) and a local
// Hessian H (k*dim square). The sink adds, with s = scale,
//   grad(n_a dim + i)                += s g(a dim + i)                      every row
//   A(n_a dim + i, n_b dim + j)      += s H(a dim + i, b dim + j)           free row, free column
//   rhs(n_a dim + i)                 -= s H(a dim + i, b dim + j) dxp(n_b dim + j)
//                                                                          free row, prescribed column
// and nothing into a prescribed row: its equation (p = dxp) is written once by
// the DOF space, which owns the constraints. This is the only place where
// prescribed DOFs are eliminated.
//
// Precondition on A's graph (the DofSpace builds it so): node-interleaved rows
// and whole node blocks, every row of one node holding the same sorted columns
// m dim + 0 .. dim-1 for each coupled node m. A node block (a, b) then has one
// position p (of column b dim in row a dim), found by bisection over the
// row's node blocks, and entry (i, j) lies at row_map(a dim) + i len(a) + p + j:
// no search per entry. A block the graph lacks is dropped (the DOF space's
// graph holds every coupling the terms declare; the derivative tests see a
// missing one as a wrong entry), and counted in `dropped`: the Newton solver
// then rebuilds the graph from the terms' couplings and assembles again.
//
// `atomic` = false is for colored assembly, where no two stencils running at
// once share a node. Units: whatever the term's energy has (J, or J/m in 2D).
#include <Kokkos_Core.hpp>
#include <cstddef>

namespace bfemp {

template <int dim, class LocalMatrix>
struct DofSink {
  using ordinal = typename LocalMatrix::ordinal_type;
  using size_type = typename LocalMatrix::size_type;

  LocalMatrix A;                                   // no values: gradient only
  Kokkos::View<double*, typename LocalMatrix::memory_space> grad, rhs;
  Kokkos::View<const int*, typename LocalMatrix::memory_space> prescribed;
  Kokkos::View<const double*, typename LocalMatrix::memory_space> dx_prescribed;
  double scale = 1.0;
  bool atomic = true;
  // false: the terms hand over their exact local Hessians, not the PSD
  // projections (the Newton solver's exact-if-definite iterations; the
  // factorisation then decides whether the sum is positive definite).
  bool project = true;
  // With project: the fraction of the negative curvature of each contact
  // pair's local Hessian that its projection keeps (project_psd's keep; 0:
  // the PSD projection). After an indefinite exact Hessian the Newton solver
  // sets it to each of Newton/fallback keep in turn, then 0, so as to add no
  // more stiffness than the linear solve needs. Like the exact Hessian, a
  // partial one solved by CG on the previous Cholmod factor is checked for
  // definiteness only through CG's curvature test, not by a factorisation.
  double contact_keep = 0.0;
  // Counts blocks the graph lacks (when allocated): the DOF space rebuilds
  // the graph and reassembles instead of dropping them.
  Kokkos::View<int, typename LocalMatrix::memory_space> dropped;

  KOKKOS_INLINE_FUNCTION bool has_matrix() const { return A.values.extent(0) > 0; }

  KOKKOS_INLINE_FUNCTION void add(double& target, double v) const {
    if (atomic) Kokkos::atomic_add(&target, v);
    else target += v;
  }

  // grad(node dim + i) += scale v
  KOKKOS_INLINE_FUNCTION void add_gradient(ordinal node, int i, double v) const {
    add(grad(node * dim + i), scale * v);
  }

  // Position of node block b in the rows of node a (-1: not in the graph).
  KOKKOS_INLINE_FUNCTION long block_position(ordinal a, ordinal b) const {
    const size_type r0 = A.graph.row_map(a * dim);
    const long nblocks = static_cast<long>(A.graph.row_map(a * dim + 1) - r0) / dim;
    const ordinal want = b * dim;
    long lo = 0, hi = nblocks - 1;
    while (lo <= hi) {
      const long mid = (lo + hi) / 2;
      const ordinal c = A.graph.entries(r0 + mid * dim);
      if (c == want) return mid * dim;
      if (c < want) lo = mid + 1;
      else hi = mid - 1;
    }
    return -1;
  }

  // Hessian block of nodes (a, b): h(i, j) for i, j < dim, before scaling.
  // hint: a guess at b's block position in a's rows (checked, then searched
  // if wrong), e.g. the previous block's + dim when a stencil's nodes run
  // consecutively. Returns the position used (-1: none was needed or found).
  template <class H>
  KOKKOS_INLINE_FUNCTION long add_block(ordinal a, ordinal b, const H& h, long hint = -1) const {
    const size_type r0 = A.graph.row_map(a * dim);
    const size_type len = A.graph.row_map(a * dim + 1) - r0;
    long pos = -2;  // found lazily: a block of prescribed rows needs no position
    auto find = [&]() {
      if (hint >= 0 && static_cast<size_type>(hint) < len && A.graph.entries(r0 + hint) == b * dim) return hint;
      return block_position(a, b);
    };
    for (int i = 0; i < dim; ++i) {
      const ordinal row = a * dim + i;
      if (prescribed(row)) continue;
      double r = 0;
      for (int j = 0; j < dim; ++j) {
        const ordinal col = b * dim + j;
        const double v = scale * h(i, j);
        if (prescribed(col)) {
          r -= v * dx_prescribed(col);
        } else {
          if (pos == -2) {
            pos = find();
            if (pos < 0 && dropped.data()) Kokkos::atomic_increment(&dropped());
          }
          if (pos >= 0) add(A.values(r0 + i * len + pos + j), v);
        }
      }
      if (r != 0) add(rhs(row), r);
    }
    return pos >= 0 ? pos : -1;
  }

  // A whole stencil of k nodes: g(r), r < k dim; H(r, c), r, c < k dim.
  template <class G, class H>
  KOKKOS_INLINE_FUNCTION void add_stencil(const ordinal* nodes, int k, const G& g, const H* Hm) const {
    for (int a = 0; a < k; ++a)
      for (int i = 0; i < dim; ++i) add_gradient(nodes[a], i, g(a * dim + i));
    if (!Hm || !has_matrix()) return;
    for (int a = 0; a < k; ++a)
      for (int b = 0; b < k; ++b)
        add_block(nodes[a], nodes[b], [&](int i, int j) { return (*Hm)(a * dim + i, b * dim + j); });
  }
};

}  // namespace bfemp
