#pragma once
// The node coupling graph of a Hessian, built on the device from the terms'
// stencils.
//
// A term declares which node blocks (r, c) its Hessian may touch as
// products: for each of n items s, every row node r = row_of(s, a), a < wr,
// with every column node c = col_of(s, b), b < wc; with `symmetric` also
// every (c, r). A node < 0 is skipped (padding, or an item that repeats an
// earlier one). A clique, all pairs of one stencil's nodes, is the product of
// the stencil with itself. Every node couples with itself (the diagonal is
// always there).
//
// Two passes over the same declarations: counting (each row's entries,
// repeats included, atomic adds), then filling (each row's cursor, atomic
// fetch-adds). finish() sorts each row and drops the repeats (KokkosKernels'
// sort_and_merge_graph: a radix sort per row on host execution spaces, a
// team bitonic sort on GPUs; rows in parallel), giving the node graph as CRS
// (row pointers, sorted unique columns). Everything runs on ExecSpace; the
// host reads a few numbers (the entry counts, the checks below).
//
// Memory: the unmerged entries, sum over items of (valid rows x valid
// columns), 4 bytes each (a 3D MPM cell of 27 nodes: 729), as many again for
// the sort's scratch, 4 bytes per merged entry, and three arrays of
// n_nodes + 1 row pointers (8 bytes each).
//
// Preconditions, checked (std::logic_error, before any entry is written out
// of its row): node ids < n_nodes; the same declarations, in any order, in
// both passes (terms are const between them): every row filled exactly.
#include <Kokkos_Core.hpp>
#include <KokkosKernels_SparseUtils.hpp>
#include <cstddef>
#include <stdexcept>
#include <string>

#include "core/types.hpp"

namespace bfemp {

class NodeGraphBuilder {
 public:
  using RowMap = Kokkos::View<std::size_t*, MemSpace>;
  using Entries = Kokkos::View<LO*, MemSpace>;

  explicit NodeGraphBuilder(LO n_nodes)
      : n_nodes_(n_nodes), rows_("node_graph_rows", n_nodes + 1), out_of_range_("node_graph_out_of_range") {
    const auto rows = rows_;
    Kokkos::parallel_for(
        "node_graph_diagonal_count", Kokkos::RangePolicy<ExecSpace>(0, n_nodes),
        KOKKOS_LAMBDA(const LO i) { rows(i) = 1; });
  }
  LO n_nodes() const { return n_nodes_; }
  bool counting() const { return counting_; }

  template <class RowOf, class ColOf>
  void add_products(long n, int wr, int wc, RowOf row_of, ColOf col_of, bool symmetric = false) {
    if (finished_) throw std::logic_error("NodeGraphBuilder: add_products after finish()");
    if (n <= 0) return;
    const bool counting = counting_;
    const LO n_nodes = n_nodes_;
    const auto rows = rows_;
    const auto cursor = cursor_;
    const auto entries = raw_;
    const auto bad = counting ? out_of_range_ : overflow_;
    Kokkos::parallel_for(
        counting ? "node_graph_count" : "node_graph_fill", Kokkos::RangePolicy<ExecSpace>(0, n),
        KOKKOS_LAMBDA(const long s) {
          const std::size_t nc = valid_nodes(col_of, s, wc, n_nodes, bad);
          const std::size_t nr = valid_nodes(row_of, s, wr, n_nodes, bad);
          for (int a = 0; a < wr; ++a)
            add_row(row_of(s, a), nc, col_of, s, wc, n_nodes, counting, rows, cursor, entries, bad);
          if (!symmetric) return;
          for (int b = 0; b < wc; ++b)
            add_row(col_of(s, b), nr, row_of, s, wr, n_nodes, counting, rows, cursor, entries, bad);
        });
  }
  template <class NodeOf>
  void add_cliques(long n, int w, NodeOf node_of) {
    add_products(n, w, w, node_of, node_of, false);
  }

  // Counting done: row pointers by an exclusive scan, the entries allocated,
  // each row's diagonal written.
  void start_fill() {
    if (!counting_) throw std::logic_error("NodeGraphBuilder: start_fill twice");
    counting_ = false;
    int out_of_range = 0;
    Kokkos::deep_copy(out_of_range, out_of_range_);
    if (out_of_range)
      throw std::logic_error("NodeGraphBuilder: a term declared a node id >= n_nodes = " + std::to_string(n_nodes_));
    const auto rows = rows_;
    const LO n = n_nodes_;
    std::size_t total = 0;
    Kokkos::parallel_scan(
        "node_graph_scan", Kokkos::RangePolicy<ExecSpace>(0, n + 1),
        KOKKOS_LAMBDA(const LO i, std::size_t& acc, const bool final) {
          const std::size_t c = i < n ? rows(i) : 0;
          if (final) rows(i) = acc;
          acc += c;
        },
        total);
    raw_ = Entries(Kokkos::ViewAllocateWithoutInitializing("node_graph_raw"), total);
    cursor_ = RowMap(Kokkos::ViewAllocateWithoutInitializing("node_graph_cursor"), n);
    overflow_ = Kokkos::View<int, MemSpace>("node_graph_overflow");
    const auto cursor = cursor_;
    const auto raw = raw_;
    Kokkos::parallel_for(
        "node_graph_diagonal", Kokkos::RangePolicy<ExecSpace>(0, n), KOKKOS_LAMBDA(const LO i) {
          raw(rows(i)) = i;
          cursor(i) = rows(i) + 1;
        });
  }

  // The node graph: rows sorted, repeats dropped. `rowmap` has n_nodes + 1
  // entries. Throws std::logic_error when the filling pass did not fill
  // every row exactly as counted.
  void finish(RowMap& rowmap, Entries& entries) {
    if (counting_) throw std::logic_error("NodeGraphBuilder: finish before start_fill");
    if (finished_) throw std::logic_error("NodeGraphBuilder: finish twice");
    finished_ = true;
    const auto rows = rows_;
    const auto cursor = cursor_;
    const auto overflow = overflow_;
    LO unfilled = 0;
    Kokkos::parallel_reduce(
        "node_graph_check", Kokkos::RangePolicy<ExecSpace>(0, n_nodes_),
        KOKKOS_LAMBDA(const LO i, LO& acc) { acc += cursor(i) != rows(i + 1) ? 1 : 0; }, unfilled);
    int overflowed = 0;
    Kokkos::deep_copy(overflowed, overflow);
    if (overflowed || unfilled)
      throw std::logic_error("NodeGraphBuilder: the filling pass declared other couplings than the counting pass (" +
                             std::to_string(unfilled) + " rows not filled as counted" +
                             (overflowed ? ", some overfilled)" : ")"));
    if (n_nodes_ == 0) {
      rowmap = RowMap("node_graph_rowmap", 1);
      entries = Entries();
      return;
    }
    KokkosKernels::Impl::sort_and_merge_graph<ExecSpace, RowMap, Entries>(rows_, raw_, rowmap, entries);
    raw_ = Entries();
    cursor_ = RowMap();
  }

 private:
  // The nodes of item s in [0, n_nodes); a node >= n_nodes raises `bad`.
  template <class NodeOf>
  KOKKOS_INLINE_FUNCTION static std::size_t valid_nodes(const NodeOf& node_of, long s, int w, LO n_nodes,
                                                        const Kokkos::View<int, MemSpace>& bad) {
    std::size_t k = 0;
    for (int a = 0; a < w; ++a) {
      const LO v = node_of(s, a);
      if (v >= n_nodes) Kokkos::atomic_assign(&bad(), 1);
      k += v >= 0 && v < n_nodes ? 1 : 0;
    }
    return k;
  }

  // Row r gets the k valid nodes of item s's list: counted (counting), or
  // written at the row's cursor (filling; a row that would get more than
  // counted raises `bad` and gets nothing).
  template <class ListOf>
  KOKKOS_INLINE_FUNCTION static void add_row(LO r, std::size_t k, const ListOf& list_of, long s, int w, LO n_nodes,
                                             bool counting, const RowMap& rows, const RowMap& cursor,
                                             const Entries& entries, const Kokkos::View<int, MemSpace>& bad) {
    if (r < 0 || r >= n_nodes || k == 0) return;
    if (counting) {
      Kokkos::atomic_add(&rows(r), k);
      return;
    }
    std::size_t p = Kokkos::atomic_fetch_add(&cursor(r), k);
    if (p + k > rows(r + 1)) {
      Kokkos::atomic_assign(&bad(), 1);
      return;
    }
    for (int b = 0; b < w; ++b) {
      const LO c = list_of(s, b);
      if (c >= 0 && c < n_nodes) entries(p++) = c;
    }
  }

  LO n_nodes_;
  bool counting_ = true, finished_ = false;
  RowMap rows_;    // counts, then the unmerged row pointers
  RowMap cursor_;  // each row's next free entry while filling
  Entries raw_;    // the unmerged entries
  Kokkos::View<int, MemSpace> out_of_range_;  // counting: a node id >= n_nodes seen
  Kokkos::View<int, MemSpace> overflow_;      // filling: a row got more than counted
};

}  // namespace bfemp
