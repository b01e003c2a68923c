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
// sort_and_merge_graph: a radix sort per row, rows in parallel), giving the
// node graph as CRS (row pointers, sorted unique columns). Everything runs on
// ExecSpace; the host reads one number, the entry count, to allocate.
//
// Memory: the unmerged entries, sum over items of (valid rows x valid
// columns), 4 bytes each (a 3D MPM cell of 27 nodes: 729), plus as many
// again for the sort's scratch.
//
// Preconditions: node ids in [0, n_nodes); the same declarations, in any
// order, in both passes (terms are const between them).
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

  explicit NodeGraphBuilder(LO n_nodes) : n_nodes_(n_nodes), rows_("node_graph_rows", n_nodes + 1) {
    const auto rows = rows_;
    Kokkos::parallel_for(
        "node_graph_diagonal_count", Kokkos::RangePolicy<ExecSpace>(0, n_nodes),
        KOKKOS_LAMBDA(const LO i) { rows(i) = 1; });
  }
  LO n_nodes() const { return n_nodes_; }
  bool counting() const { return counting_; }

  template <class RowOf, class ColOf>
  void add_products(long n, int wr, int wc, RowOf row_of, ColOf col_of, bool symmetric = false) {
    if (n <= 0) return;
    if (finished_) throw std::logic_error("NodeGraphBuilder: add_products after finish()");
    const auto rows = rows_;
    if (counting_) {
      Kokkos::parallel_for(
          "node_graph_count", Kokkos::RangePolicy<ExecSpace>(0, n), KOKKOS_LAMBDA(const long s) {
            std::size_t nr = 0, nc = 0;
            for (int b = 0; b < wc; ++b) nc += col_of(s, b) >= 0 ? 1 : 0;
            for (int a = 0; a < wr; ++a) {
              const LO r = row_of(s, a);
              if (r < 0) continue;
              ++nr;
              Kokkos::atomic_add(&rows(r), nc);
            }
            if (!symmetric) return;
            for (int b = 0; b < wc; ++b) {
              const LO c = col_of(s, b);
              if (c >= 0) Kokkos::atomic_add(&rows(c), nr);
            }
          });
      return;
    }
    const auto cursor = cursor_;
    const auto entries = raw_;
    Kokkos::parallel_for(
        "node_graph_fill", Kokkos::RangePolicy<ExecSpace>(0, n), KOKKOS_LAMBDA(const long s) {
          std::size_t nr = 0, nc = 0;
          for (int b = 0; b < wc; ++b) nc += col_of(s, b) >= 0 ? 1 : 0;
          for (int a = 0; a < wr; ++a) nr += row_of(s, a) >= 0 ? 1 : 0;
          for (int a = 0; a < wr; ++a) {
            const LO r = row_of(s, a);
            if (r < 0) continue;
            std::size_t p = Kokkos::atomic_fetch_add(&cursor(r), nc);
            for (int b = 0; b < wc; ++b) {
              const LO c = col_of(s, b);
              if (c >= 0) entries(p++) = c;
            }
          }
          if (!symmetric) return;
          for (int b = 0; b < wc; ++b) {
            const LO c = col_of(s, b);
            if (c < 0) continue;
            std::size_t p = Kokkos::atomic_fetch_add(&cursor(c), nr);
            for (int a = 0; a < wr; ++a) {
              const LO r = row_of(s, a);
              if (r >= 0) entries(p++) = r;
            }
          }
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
    const auto cursor = cursor_;
    const auto raw = raw_;
    Kokkos::parallel_for(
        "node_graph_diagonal", Kokkos::RangePolicy<ExecSpace>(0, n), KOKKOS_LAMBDA(const LO i) {
          raw(rows(i)) = i;
          cursor(i) = rows(i) + 1;
        });
  }

  // The node graph: rows sorted, repeats dropped. `rowmap` has n_nodes + 1
  // entries.
  void finish(RowMap& rowmap, Entries& entries) {
    if (counting_) throw std::logic_error("NodeGraphBuilder: finish before start_fill");
    finished_ = true;
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
  LO n_nodes_;
  bool counting_ = true, finished_ = false;
  RowMap rows_;    // counts, then the unmerged row pointers
  RowMap cursor_;  // each row's next free entry while filling
  Entries raw_;    // the unmerged entries
};

}  // namespace bfemp
