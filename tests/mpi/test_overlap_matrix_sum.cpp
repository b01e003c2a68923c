// OverlapMatrixSum (solver/overlap_matrix_sum.hpp) on 1, 2 and 3 ranks,
// against Tpetra's own path: the owned graph it builds holds the entries the
// graph an Export of the overlap graph with INSERT holds after fillComplete
// (by global row and column), its column map has the owned DOFs first in row
// order and the others sorted by (owning rank, id), and sum() equals a
// matrix Export with ADD, entry by entry, also when repeated. The DOFs are owned round-robin
// (gid mod ranks), so every rank's ghosts come from every other rank, a
// ghost row's columns may be owned by a third rank, and a column of a
// received row may be absent from the receiving rank's overlap map; the
// last rank's first owned row holds only its diagonal there (its other
// entries, if any, come from other ranks' ghost copies).
#include <gtest/gtest.h>

#include <Teuchos_CommHelpers.hpp>
#include <Tpetra_Core.hpp>
#include <Tpetra_CrsGraph.hpp>
#include <Tpetra_CrsMatrix.hpp>
#include <Tpetra_Export.hpp>
#include <Tpetra_Vector.hpp>
#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <set>
#include <vector>

#include "solver/overlap_matrix_sum.hpp"

using namespace bfemp;

namespace {

constexpr GO kPerRank = 37;

struct Overlap {
  Teuchos::RCP<const Map> owned, overlap;
  Teuchos::RCP<const Graph> G_ov;
};

// Rank p owns the gids g with g mod R == p; its overlap map adds the gids
// g + 1 and g + 5 (mod N) of its owned g. Each overlap row couples to itself
// and to a random set of the other overlap DOFs.
Overlap make(unsigned seed) {
  auto comm = Tpetra::getDefaultComm();
  const int R = comm->getSize(), me = comm->getRank();
  const GO N = kPerRank * R;
  std::vector<GO> own, ov;
  for (GO g = me; g < N; g += R) own.push_back(g);
  std::set<GO> ghosts;
  for (GO g : own)
    for (GO d : {1, 5}) {
      const GO h = (g + d) % N;
      if (h % R != me) ghosts.insert(h);
    }
  ov = own;
  ov.insert(ov.end(), ghosts.begin(), ghosts.end());
  const auto inv = Teuchos::OrdinalTraits<Tpetra::global_size_t>::invalid();
  Overlap s;
  s.owned = Teuchos::rcp(new Map(inv, Teuchos::ArrayView<const GO>(own), 0, comm));
  s.overlap = Teuchos::rcp(new Map(inv, Teuchos::ArrayView<const GO>(ov), 0, comm));
  std::mt19937 rng(seed + 17u * static_cast<unsigned>(me));
  const LO n = static_cast<LO>(ov.size());
  std::uniform_int_distribution<LO> col(0, n - 1);
  Kokkos::View<std::size_t*, Node::device_type> rowptr("rowptr", n + 1);
  std::vector<LO> cols;
  for (LO i = 0; i < n; ++i) {
    std::set<LO> row{i};
    // the last rank's first owned row: no entries beyond its diagonal here
    const int extra = me == R - 1 && i == 0 ? 0 : 1 + static_cast<int>(col(rng) % 6);
    for (int k = 0; k < extra; ++k) row.insert(col(rng));
    cols.insert(cols.end(), row.begin(), row.end());
    rowptr(i + 1) = cols.size();
  }
  Kokkos::View<LO*, Node::device_type> colind("colind", cols.size());
  for (std::size_t k = 0; k < cols.size(); ++k) colind(k) = cols[k];
  auto G = Teuchos::rcp(new Graph(s.overlap, s.overlap, rowptr, colind));
  G->fillComplete(s.owned, s.owned);
  s.G_ov = G;
  return s;
}

// Tpetra's path: row lengths summed by an Export, then the graph exported with INSERT.
Teuchos::RCP<const Graph> exported_graph(const Overlap& s, const Tpetra::Export<LO, GO, Node>& ex) {
  Vector len_ov(s.overlap), len(s.owned);
  {
    auto v = len_ov.getLocalViewHost(Tpetra::Access::OverwriteAll);
    for (LO i = 0; i < static_cast<LO>(v.extent(0)); ++i) v(i, 0) = static_cast<double>(s.G_ov->getNumEntriesInLocalRow(i));
  }
  len.doExport(len_ov, ex, Tpetra::ADD);
  std::vector<std::size_t> cap(s.owned->getNodeNumElements());
  {
    auto v = len.getLocalViewHost(Tpetra::Access::ReadOnly);
    for (std::size_t i = 0; i < cap.size(); ++i) cap[i] = static_cast<std::size_t>(v(i, 0) + 0.5);
  }
  auto G = Teuchos::rcp(new Graph(s.owned, Teuchos::ArrayView<const std::size_t>(cap)));
  G->doExport(*s.G_ov, ex, Tpetra::INSERT);
  G->fillComplete(s.owned, s.owned);
  return G;
}

// Per owned row: its (global row, global column) entries.
std::set<std::pair<GO, GO>> entries(const Graph& G) {
  std::set<std::pair<GO, GO>> out;
  const auto lg = G.getLocalGraphHost();
  for (LO r = 0; r + 1 < static_cast<LO>(lg.row_map.extent(0)); ++r)
    for (auto k = lg.row_map(r); k < lg.row_map(r + 1); ++k)
      out.emplace(G.getRowMap()->getGlobalElement(r), G.getColMap()->getGlobalElement(lg.entries(k)));
  return out;
}

std::map<std::pair<GO, GO>, double> values(const Matrix& A) {
  std::map<std::pair<GO, GO>, double> out;
  const auto lcl = A.getLocalMatrixHost();
  for (LO r = 0; r < static_cast<LO>(lcl.numRows()); ++r)
    for (auto k = lcl.graph.row_map(r); k < lcl.graph.row_map(r + 1); ++k)
      out[{A.getRowMap()->getGlobalElement(r), A.getColMap()->getGlobalElement(lcl.graph.entries(k))}] = lcl.values(k);
  return out;
}

}  // namespace

TEST(OverlapMatrixSum, OwnedGraphAndSumEqualTpetrasExport) {
  for (unsigned seed : {1u, 2u}) {
    const Overlap s = make(seed);
    Tpetra::Export<LO, GO, Node> ex(s.overlap, s.owned);
    OverlapMatrixSum sum(*s.G_ov, ex);
    const auto G = sum.graph();
    const auto G_ref = exported_graph(s, ex);
    ASSERT_TRUE(G->isFillComplete());
    // The same global entries per owned row.
    EXPECT_EQ(entries(*G), entries(*G_ref)) << "seed " << seed;
    // The column map: the owned DOFs first, in row order, then the others
    // sorted by (owning rank, id).
    const auto& cm = *G->getColMap();
    const LO n_own = static_cast<LO>(s.owned->getNodeNumElements());
    ASSERT_GE(static_cast<LO>(cm.getNodeNumElements()), n_own);
    for (LO r = 0; r < n_own; ++r) EXPECT_EQ(cm.getGlobalElement(r), s.owned->getGlobalElement(r));
    std::vector<GO> remote;
    for (std::size_t k = n_own; k < cm.getNodeNumElements(); ++k) remote.push_back(cm.getGlobalElement(k));
    std::vector<int> pid(remote.size());
    s.owned->getRemoteIndexList(Teuchos::ArrayView<const GO>(remote), Teuchos::ArrayView<int>(pid));
    for (std::size_t k = 1; k < remote.size(); ++k)
      EXPECT_TRUE(std::make_pair(pid[k - 1], remote[k - 1]) < std::make_pair(pid[k], remote[k]))
          << "column " << n_own + k;

    // Values: each rank's overlap entry (R, C) holds a distinct function of (R, C, rank).
    const int me = s.owned->getComm()->getRank();
    Matrix A_ov(s.G_ov);
    A_ov.fillComplete(s.owned, s.owned);
    {
      A_ov.resumeFill();
      auto lcl = A_ov.getLocalMatrixHost();
      for (LO i = 0; i < static_cast<LO>(lcl.numRows()); ++i)
        for (auto k = lcl.graph.row_map(i); k < lcl.graph.row_map(i + 1); ++k) {
          const double R = static_cast<double>(s.overlap->getGlobalElement(i));
          const double C = static_cast<double>(s.overlap->getGlobalElement(lcl.graph.entries(k)));
          lcl.values(k) = 1.0 + R + 0.01 * C + 1e-4 * (me + 1) * std::sqrt(1.0 + R * C);
        }
      A_ov.fillComplete(s.owned, s.owned);
    }
    Matrix A(G), A_ref(G_ref);
    A.fillComplete(s.owned, s.owned);
    A_ref.fillComplete(s.owned, s.owned);
    A.resumeFill();
    sum.sum(A_ov, A);
    A.fillComplete(s.owned, s.owned);
    A_ref.resumeFill();
    A_ref.setAllToScalar(0.0);
    A_ref.doExport(A_ov, ex, Tpetra::ADD);
    A_ref.fillComplete(s.owned, s.owned);
    const auto va = values(A), vb = values(A_ref);
    ASSERT_EQ(va.size(), vb.size());
    double worst = 0;
    for (const auto& [key, v] : vb) {
      ASSERT_EQ(va.count(key), 1u) << "entry (" << key.first << ", " << key.second << ")";
      worst = std::max(worst, std::abs(va.at(key) - v) / std::max(1.0, std::abs(v)));
    }
    EXPECT_LT(worst, 1e-14) << "seed " << seed;
    // Summed twice (the plan reused): the same values.
    A.resumeFill();
    sum.sum(A_ov, A);
    A.fillComplete(s.owned, s.owned);
    EXPECT_EQ(values(A), va);
  }
}
