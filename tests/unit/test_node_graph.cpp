// The device graph builder (kernels/node_graph.hpp) and the DOF graph built
// from it (solver/dof_graph.hpp):
//  - random products (cliques, symmetric and one-sided products, nodes < 0
//    skipped) give exactly the node pairs a host set of the same
//    declarations holds, plus every diagonal, each row sorted, no repeats;
//  - the filling pass may see the declarations in another order;
//  - the DOF graph holds, in DOF row (i, c), node i's columns in order, each
//    as dim consecutive DOFs;
//  - no nodes, or no items, are legal;
//  - a filling pass that declares fewer or more couplings than the counting
//    pass, or a node id >= n_nodes, is refused (std::logic_error) before a
//    graph comes out.
#include <gtest/gtest.h>

#include <Tpetra_Core.hpp>
#include <Tpetra_CrsGraph.hpp>
#include <random>
#include <set>
#include <utility>
#include <vector>

#include "kernels/node_graph.hpp"
#include "solver/dof_graph.hpp"

using namespace bfemp;

namespace {

static_assert(Kokkos::SpaceAccessibility<Kokkos::HostSpace, MemSpace>::accessible,
              "the test reads the builder's views on the host");

using Pairs = std::set<std::pair<LO, LO>>;

struct Declaration {
  int wr, wc;
  bool symmetric, clique;
  Kokkos::View<LO**, MemSpace> rows, cols;  // n x wr, n x wc (clique: cols = rows)
};

Declaration random_declaration(std::mt19937& rng, LO n_nodes, long n, int wr, int wc, bool symmetric, bool clique) {
  Declaration d{wr, clique ? wr : wc, symmetric, clique, Kokkos::View<LO**, MemSpace>("rows", n, wr),
                Kokkos::View<LO**, MemSpace>("cols", n, clique ? wr : wc)};
  std::uniform_int_distribution<LO> node(-3, n_nodes - 1);  // about 1 in n_nodes/3 skipped
  for (long s = 0; s < n; ++s) {
    for (int a = 0; a < wr; ++a) d.rows(s, a) = node(rng);
    for (int b = 0; b < d.wc; ++b) d.cols(s, b) = clique ? d.rows(s, b) : node(rng);
  }
  return d;
}

void declare(NodeGraphBuilder& g, const Declaration& d) {
  const auto rows = d.rows, cols = d.cols;
  const auto row_of = KOKKOS_LAMBDA(const long s, const int a) { return rows(s, a) < 0 ? LO(-1) : rows(s, a); };
  const auto col_of = KOKKOS_LAMBDA(const long s, const int b) { return cols(s, b) < 0 ? LO(-1) : cols(s, b); };
  if (d.clique) g.add_cliques(static_cast<long>(rows.extent(0)), d.wr, row_of);
  else g.add_products(static_cast<long>(rows.extent(0)), d.wr, d.wc, row_of, col_of, d.symmetric);
}

void reference(Pairs& pairs, const Declaration& d) {
  for (std::size_t s = 0; s < d.rows.extent(0); ++s)
    for (int a = 0; a < d.wr; ++a)
      for (int b = 0; b < d.wc; ++b) {
        const LO r = d.rows(s, a), c = d.cols(s, b);
        if (r < 0 || c < 0) continue;
        pairs.insert({r, c});
        if (d.symmetric) pairs.insert({c, r});
      }
}

void expect_graph(const NodeGraphBuilder::RowMap& rows, const NodeGraphBuilder::Entries& cols, LO n_nodes,
                  const Pairs& expected) {
  ASSERT_EQ(rows.extent(0), static_cast<std::size_t>(n_nodes) + 1);
  ASSERT_EQ(rows(0), 0u);
  Pairs got;
  for (LO i = 0; i < n_nodes; ++i) {
    for (std::size_t k = rows(i); k < rows(i + 1); ++k) {
      if (k > rows(i)) {
        EXPECT_LT(cols(k - 1), cols(k)) << "row " << i << " not sorted or repeats";
      }
      got.insert({i, cols(k)});
    }
  }
  EXPECT_EQ(rows(n_nodes), cols.extent(0));
  EXPECT_EQ(got.size(), cols.extent(0));
  EXPECT_EQ(got, expected);
}

}  // namespace

TEST(NodeGraph, RandomProductsGiveTheDeclaredPairs) {
  const LO n_nodes = 60;
  std::mt19937 rng(5);
  std::vector<Declaration> decls;
  decls.push_back(random_declaration(rng, n_nodes, 40, 4, 4, false, true));    // cliques
  decls.push_back(random_declaration(rng, n_nodes, 30, 5, 3, true, false));    // symmetric products
  decls.push_back(random_declaration(rng, n_nodes, 25, 2, 6, false, false));   // one-sided products
  decls.push_back(random_declaration(rng, n_nodes, 0, 3, 3, true, false));     // no items
  Pairs expected;
  for (LO i = 0; i < n_nodes; ++i) expected.insert({i, i});
  for (const auto& d : decls) reference(expected, d);

  for (bool reversed_fill : {false, true}) {
    NodeGraphBuilder g(n_nodes);
    EXPECT_TRUE(g.counting());
    for (const auto& d : decls) declare(g, d);
    g.start_fill();
    EXPECT_FALSE(g.counting());
    if (reversed_fill)
      for (auto it = decls.rbegin(); it != decls.rend(); ++it) declare(g, *it);
    else
      for (const auto& d : decls) declare(g, d);
    NodeGraphBuilder::RowMap rows;
    NodeGraphBuilder::Entries cols;
    g.finish(rows, cols);
    expect_graph(rows, cols, n_nodes, expected);
    // a missing pair in the reference would be an extra one in the graph: the
    // pairs of the one-sided declaration must not come back transposed
    bool one_sided_only = false;
    for (std::size_t s = 0; s < decls[2].rows.extent(0) && !one_sided_only; ++s)
      for (int a = 0; a < decls[2].wr; ++a)
        for (int b = 0; b < decls[2].wc; ++b) {
          const LO r = decls[2].rows(s, a), c = decls[2].cols(s, b);
          if (r >= 0 && c >= 0 && expected.count({c, r}) == 0) one_sided_only = true;
        }
    EXPECT_TRUE(one_sided_only) << "the random one-sided products should hold a pair without its transpose";
  }
}

TEST(NodeGraph, NoNodesAndNoCouplings) {
  {
    NodeGraphBuilder g(0);
    g.start_fill();
    NodeGraphBuilder::RowMap rows;
    NodeGraphBuilder::Entries cols;
    g.finish(rows, cols);
    ASSERT_EQ(rows.extent(0), 1u);
    EXPECT_EQ(rows(0), 0u);
    EXPECT_EQ(cols.extent(0), 0u);
  }
  NodeGraphBuilder g(7);
  g.start_fill();
  NodeGraphBuilder::RowMap rows;
  NodeGraphBuilder::Entries cols;
  g.finish(rows, cols);
  Pairs diagonal;
  for (LO i = 0; i < 7; ++i) diagonal.insert({i, i});
  expect_graph(rows, cols, 7, diagonal);
  EXPECT_THROW(g.start_fill(), std::logic_error);
}

TEST(NodeGraph, DeclarationsThatDifferBetweenPassesAreRefused) {
  const LO n_nodes = 40;
  std::mt19937 rng(23);
  const auto d = random_declaration(rng, n_nodes, 20, 3, 3, true, false);
  const auto fewer = random_declaration(rng, n_nodes, 0, 3, 3, true, false);
  const auto extra = random_declaration(rng, n_nodes, 5, 3, 3, true, false);
  NodeGraphBuilder::RowMap rows;
  NodeGraphBuilder::Entries cols;
  {  // the fill declares nothing: rows left unfilled
    NodeGraphBuilder g(n_nodes);
    declare(g, d);
    g.start_fill();
    declare(g, fewer);
    EXPECT_THROW(g.finish(rows, cols), std::logic_error);
  }
  {  // the fill declares more: rows overfilled (refused before writing past them)
    NodeGraphBuilder g(n_nodes);
    declare(g, d);
    g.start_fill();
    declare(g, d);
    declare(g, extra);
    EXPECT_THROW(g.finish(rows, cols), std::logic_error);
  }
  {  // the same declarations: a graph, and finish() only once
    NodeGraphBuilder g(n_nodes);
    declare(g, d);
    g.start_fill();
    declare(g, d);
    EXPECT_NO_THROW(g.finish(rows, cols));
    EXPECT_THROW(g.finish(rows, cols), std::logic_error);
    EXPECT_THROW(declare(g, d), std::logic_error);
  }
  {  // a node id past the last node
    NodeGraphBuilder g(n_nodes);
    Kokkos::View<LO**, MemSpace> nodes("nodes", 1, 2);
    nodes(0, 0) = 3;
    nodes(0, 1) = n_nodes;
    g.add_cliques(1, 2, KOKKOS_LAMBDA(const long s, const int a) { return nodes(s, a); });
    EXPECT_THROW(g.start_fill(), std::logic_error);
  }
}

template <int dim>
void dof_layout() {
  const LO n_nodes = 30;
  std::mt19937 rng(11 + dim);
  const auto d = random_declaration(rng, n_nodes, 20, 3, 3, false, true);
  NodeGraphBuilder g(n_nodes);
  declare(g, d);
  g.start_fill();
  declare(g, d);
  NodeGraphBuilder::RowMap rows;
  NodeGraphBuilder::Entries cols;
  g.finish(rows, cols);
  auto map = Teuchos::rcp(new Map(static_cast<Tpetra::global_size_t>(n_nodes) * dim, 0, Tpetra::getDefaultComm()));
  const auto graph = build_dof_graph<dim>(rows, cols, map);
  ASSERT_EQ(graph->getNodeNumRows(), static_cast<std::size_t>(n_nodes) * dim);
  EXPECT_EQ(graph->getNodeNumEntries(), cols.extent(0) * dim * dim);
  const auto lcl = graph->getLocalGraphHost();
  for (LO i = 0; i < n_nodes; ++i)
    for (int c = 0; c < dim; ++c) {
      const LO row = i * dim + c;
      std::vector<LO> expected;
      for (std::size_t k = rows(i); k < rows(i + 1); ++k)
        for (int e = 0; e < dim; ++e) expected.push_back(cols(k) * dim + e);
      std::vector<LO> got(lcl.entries.data() + lcl.row_map(row), lcl.entries.data() + lcl.row_map(row + 1));
      EXPECT_EQ(got, expected) << "DOF row " << row;
    }
}

TEST(NodeGraph, DofGraphExpandsNodeRows2D) { dof_layout<2>(); }
TEST(NodeGraph, DofGraphExpandsNodeRows3D) { dof_layout<3>(); }
