#include "solver/block_cholmod.hpp"

#include <Teuchos_CommHelpers.hpp>
#include <Tpetra_CrsMatrix.hpp>
#include <Tpetra_MultiVector.hpp>
#include <algorithm>
#include <cholmod.h>
#include <string>
#include <utility>
#include <vector>

#include "solver/cholmod_views.hpp"
#include "solver/solver_error.hpp"

namespace bfemp {

static_assert(Kokkos::SpaceAccessibility<Kokkos::HostSpace, MemSpace>::accessible,
              "BlockCholmod hands CHOLMOD views of the vectors: they must be host-accessible");

struct BlockCholmod::Impl {
  Teuchos::RCP<const Matrix> A;
  cholmod_common c{};
  cholmod_factor* L = nullptr;
  cholmod_dense* X = nullptr;  // solve workspaces, reused
  cholmod_dense* Y = nullptr;
  cholmod_dense* E = nullptr;
  std::vector<SuiteSparse_long> p, i;             // the block's compressed columns (= rows: symmetric)
  Kokkos::View<std::size_t*, MemSpace> source;    // per block entry: its index in A's values
  Kokkos::View<double*, MemSpace> values;         // the block's values, gathered by compute()
  bool analysed = false;
  bool factored = false;

  Impl() {
    cholmod_l_start(&c);
    c.print = 0;
    c.error_handler = nullptr;  // errors come back as c.status
    c.final_ll = 1;             // simplicial factors as LL': a non-positive pivot is reported
  }
  ~Impl() {
    if (L) cholmod_l_free_factor(&L, &c);
    if (X) cholmod_l_free_dense(&X, &c);
    if (Y) cholmod_l_free_dense(&Y, &c);
    if (E) cholmod_l_free_dense(&E, &c);
    cholmod_l_finish(&c);
  }
  cholmod_sparse view() { return symmetric_csc_view(p, i, values.data()); }
};

// Once per graph (host): which of A's entries lie in this rank's block, in
// block coordinates (row local ids), sorted per row.
BlockCholmod::BlockCholmod(const Teuchos::RCP<const Matrix>& A) : impl_(new Impl) {
  auto& m = *impl_;
  m.A = A;
  const auto& rows = *A->getRowMap();
  const auto& cols = *A->getColMap();
  const auto lcl = A->getLocalMatrixHost();
  const std::size_t n = rows.getNodeNumElements();
  std::vector<LO> col_to_row(cols.getNodeNumElements());
  for (std::size_t k = 0; k < col_to_row.size(); ++k) col_to_row[k] = rows.getLocalElement(cols.getGlobalElement(k));
  m.p.assign(n + 1, 0);
  std::vector<std::pair<LO, std::size_t>> row;  // (block column, index in A's values)
  std::vector<std::size_t> src;
  for (std::size_t r = 0; r < n; ++r) {
    row.clear();
    for (auto k = lcl.graph.row_map(r); k < lcl.graph.row_map(r + 1); ++k) {
      const LO c = col_to_row[lcl.graph.entries(k)];
      if (c != Teuchos::OrdinalTraits<LO>::invalid()) row.emplace_back(c, k);
    }
    std::sort(row.begin(), row.end());
    for (const auto& [c, k] : row) {
      m.i.push_back(c);
      src.push_back(k);
    }
    m.p[r + 1] = static_cast<SuiteSparse_long>(m.i.size());
  }
  m.source = Kokkos::View<std::size_t*, MemSpace>("block_cholmod_source", src.size());
  auto hs = Kokkos::create_mirror_view(m.source);
  for (std::size_t k = 0; k < src.size(); ++k) hs(k) = src[k];
  Kokkos::deep_copy(m.source, hs);
  m.values = Kokkos::View<double*, MemSpace>("block_cholmod_values", src.size());
}

BlockCholmod::~BlockCholmod() = default;

void BlockCholmod::compute() {
  auto& m = *impl_;
  const auto all = m.A->getLocalMatrixDevice().values;
  const auto src = m.source;
  const auto vals = m.values;
  Kokkos::parallel_for(
      "block_cholmod_gather", Kokkos::RangePolicy<ExecSpace>(0, vals.extent(0)),
      KOKKOS_LAMBDA(const std::size_t k) { vals(k) = all(src(k)); });
  Kokkos::fence();
  cholmod_sparse S = m.view();
  int status = CHOLMOD_OK;
  if (!m.analysed && S.nrow > 0) {
    m.L = cholmod_l_analyze(&S, &m.c);
    status = m.L ? m.c.status : CHOLMOD_INVALID;
    m.analysed = m.L != nullptr;
  }
  m.factored = false;
  if (status >= CHOLMOD_OK && S.nrow > 0) {
    if (!cholmod_l_factorize(&S, m.L, &m.c)) status = m.c.status == CHOLMOD_OK ? CHOLMOD_INVALID : m.c.status;
    else status = m.c.status;
  }
  // Every rank learns of a failure on any rank (a CG on the others would wait).
  int worst_local = status == CHOLMOD_OK ? 0 : (status == CHOLMOD_NOT_POSDEF ? 1 : 2);
  int worst = 0;
  Teuchos::reduceAll(*m.A->getComm(), Teuchos::REDUCE_MAX, worst_local, Teuchos::outArg(worst));
  if (worst == 1)
    throw NotPositiveDefinite("block Cholesky preconditioner (BLOCK_CHOLMOD): a rank's diagonal block is not "
                              "positive definite, so the matrix is not");
  if (worst == 2)
    throw SolverError("block Cholesky preconditioner (BLOCK_CHOLMOD): CHOLMOD status " + std::to_string(status) +
                      " on this rank (or a failure on another rank)");
  m.factored = true;
}

void BlockCholmod::apply(const MultiVec& Xin, MultiVec& Yout, Teuchos::ETransp, double alpha, double beta) const {
  auto& m = *impl_;
  if (!m.factored) throw std::logic_error("BlockCholmod::apply before a successful compute()");
  const std::size_t n = m.p.size() - 1;
  const auto xv = Xin.getLocalViewDevice(Tpetra::Access::ReadOnly);
  auto yv = Yout.getLocalViewDevice(Tpetra::Access::ReadWrite);
  for (std::size_t col = 0; col < Xin.getNumVectors(); ++col) {
    if (n == 0) break;
    cholmod_dense B = dense_column_view(const_cast<double*>(&xv(0, col)), n);  // LayoutLeft: contiguous
    if (!cholmod_l_solve2(CHOLMOD_A, m.L, &B, nullptr, &m.X, nullptr, &m.Y, &m.E, &m.c) || m.c.status != CHOLMOD_OK)
      throw SolverError("block Cholesky preconditioner (BLOCK_CHOLMOD): CHOLMOD solve status " +
                        std::to_string(m.c.status));
    const double* s = static_cast<const double*>(m.X->x);
    Kokkos::parallel_for(
        "block_cholmod_apply", Kokkos::RangePolicy<ExecSpace>(0, n), KOKKOS_LAMBDA(const std::size_t k) {
          yv(k, col) = beta == 0.0 ? alpha * s[k] : alpha * s[k] + beta * yv(k, col);
        });
  }
  Kokkos::fence();
}

Teuchos::RCP<const Map> BlockCholmod::getDomainMap() const { return impl_->A->getDomainMap(); }
Teuchos::RCP<const Map> BlockCholmod::getRangeMap() const { return impl_->A->getRangeMap(); }
std::size_t BlockCholmod::block_rows() const { return impl_->p.size() - 1; }
std::size_t BlockCholmod::block_entries() const { return impl_->i.size(); }

}  // namespace bfemp
