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
// Scatter table (optional): for a term whose stencils keep their nodes while
// the graph serves (FEM elements until the next graph build, MPM cells for a
// step), the DOF space stores each block's position once per graph and
// stencil set,
//   table(s k^2 + a k + b) = position of block (n_a, n_b) in n_a's rows
//                            (-1: not in the graph),
// filled by scatter_positions() below; the term then passes the stencil's k^2
// positions to add_stencil and no row is searched during assembly. The sink
// carries the table of the term it is handed to (DofSpace::term_sink) and
// the number of stencils it was built for; a term uses it only when that
// number equals its own stencil count. Each position is checked against the
// graph before it is used (add_block_at), so a wrong table costs a search,
// never a wrong entry. Memory: k^2 ints per stencil (729 per 3D MPM cell).
//
// `atomic` = false is for colored or swept assembly, where no two stencils running at
// once share a node. Units: whatever the term's energy has (J, or J/m in 2D).
#include <Kokkos_Core.hpp>
#include <cstddef>

#include "core/types.hpp"

namespace bfemp {

// Position of node block (a, b) in the rows of node a of a graph laid out as
// above (-1: not in the graph), by bisection over a's node blocks.
template <int dim, class Graph>
KOKKOS_INLINE_FUNCTION long graph_block_position(const Graph& graph, typename Graph::data_type a,
                                                 typename Graph::data_type b) {
  const auto r0 = graph.row_map(a * dim);
  const long nblocks = static_cast<long>(graph.row_map(a * dim + 1) - r0) / dim;
  const auto want = b * dim;
  long lo = 0, hi = nblocks - 1;
  while (lo <= hi) {
    const long mid = (lo + hi) / 2;
    const auto c = graph.entries(r0 + mid * dim);
    if (c == want) return mid * dim;
    if (c < want) lo = mid + 1;
    else hi = mid - 1;
  }
  return -1;
}

// Scatter table of n_stencils stencils of k nodes each, nodes_of(s, a) the
// a-th node of stencil s: table(s k^2 + a k + b) = graph_block_position(
// nodes_of(s, a), nodes_of(s, b)). `table` keeps its allocation when it is
// large enough (it is reallocated only when the stencils outgrow it).
template <int dim, class Graph, class Table, class NodesOf>
void scatter_positions(const Graph& graph, long n_stencils, int k, const NodesOf& nodes_of, Table& table) {
  const std::size_t need = static_cast<std::size_t>(n_stencils) * k * k;
  if (table.extent(0) < need) table = Table(Kokkos::view_alloc(Kokkos::WithoutInitializing, "dof_scatter_table"), need);
  auto t = table;
  Kokkos::parallel_for(
      "dof_scatter_positions", Kokkos::RangePolicy<ExecSpace>(0, n_stencils),
      KOKKOS_LAMBDA(const long s) {
        for (int a = 0; a < k; ++a) {
          const auto na = nodes_of(s, a);
          for (int b = 0; b < k; ++b)
            t(static_cast<std::size_t>(s) * k * k + a * k + b) =
                static_cast<int>(graph_block_position<dim>(graph, na, nodes_of(s, b)));
        }
      });
}

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
  // The scatter table of the term this sink is handed to, and its stencil
  // count (0: none; the blocks are found by bisection).
  Kokkos::View<const int*, typename LocalMatrix::memory_space> table;
  long table_stencils = 0;
  // The k^2 positions of stencil s of k nodes, or null when the sink has no
  // table for n_stencils stencils.
  KOKKOS_INLINE_FUNCTION const int* stencil_positions(long s, int k, long n_stencils) const {
    return table_stencils == n_stencils && table_stencils > 0 ? &table(static_cast<std::size_t>(s) * k * k) : nullptr;
  }

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
    return graph_block_position<dim>(A.graph, a, b);
  }

  // Hessian block of nodes (a, b): h(i, j) for i, j < dim, before scaling.
  // hint: a guess at b's block position in a's rows (checked, then searched
  // if wrong), e.g. the previous block's + dim when a stencil's nodes run
  // consecutively. Returns the position used (-1: none was needed or found).
  template <class H>
  KOKKOS_INLINE_FUNCTION long add_block(ordinal a, ordinal b, const H& h, long hint = -1) const {
    return add_block_found(a, b, h, [&](size_type r0, size_type len) -> long {
      if (hint >= 0 && static_cast<size_type>(hint) < len && A.graph.entries(r0 + hint) == b * dim) return hint;
      return block_position(a, b);
    });
  }
  // The same at a known position (a scatter table's entry; -1: not in the
  // graph). The position is checked (one load: the block's first column must
  // be b's): a table that does not fit this graph falls back to the search,
  // so it can never write into another block.
  template <class H>
  KOKKOS_INLINE_FUNCTION long add_block_at(ordinal a, ordinal b, const H& h, long pos) const {
    return add_block_found(a, b, h, [&](size_type r0, size_type len) -> long {
      if (pos >= 0 && static_cast<size_type>(pos) + dim <= len && A.graph.entries(r0 + pos) == b * dim) return pos;
      return block_position(a, b);
    });
  }

  // find(r0, len): the block's position, asked for only when a free row meets
  // a free column (a block of prescribed rows needs none).
  template <class H, class Find>
  KOKKOS_INLINE_FUNCTION long add_block_found(ordinal a, ordinal b, const H& h, const Find& find) const {
    const size_type r0 = A.graph.row_map(a * dim);
    const size_type len = A.graph.row_map(a * dim + 1) - r0;
    long pos = -2;
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
            pos = find(r0, len);
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
  // positions: the stencil's k^2 scatter-table entries (stencil_positions),
  // or null to search each block.
  template <class G, class H>
  KOKKOS_INLINE_FUNCTION void add_stencil(const ordinal* nodes, int k, const G& g, const H* Hm,
                                          const int* positions = nullptr) const {
    for (int a = 0; a < k; ++a)
      for (int i = 0; i < dim; ++i) add_gradient(nodes[a], i, g(a * dim + i));
    if (!Hm || !has_matrix()) return;
    for (int a = 0; a < k; ++a)
      for (int b = 0; b < k; ++b) {
        auto hab = [&](int i, int j) { return (*Hm)(a * dim + i, b * dim + j); };
        if (positions) add_block_at(nodes[a], nodes[b], hab, positions[a * k + b]);
        else add_block(nodes[a], nodes[b], hab);
      }
  }
};

}  // namespace bfemp
