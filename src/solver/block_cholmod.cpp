#include "solver/block_cholmod.hpp"

#include <Teuchos_CommHelpers.hpp>
#include <Tpetra_CrsMatrix.hpp>
#include <Tpetra_Import.hpp>
#include <Tpetra_MultiVector.hpp>
#include <algorithm>
#include <stdexcept>
#include <cholmod.h>
#include <string>
#include <utility>
#include <vector>

#include "solver/cholmod_common.hpp"
#include "solver/cholmod_views.hpp"
#include "solver/single_factor.hpp"
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
  bool want_single = false;
  SingleFactor single;  // the factor in float (want_single), copied by prepare_solve() once worth it
  int applies = 0;      // apply() calls since the factorisation
  double fl = 0, lnz = 0;  // CHOLMOD's analysis: factorisation flops, nonzeros of L
  double local_s = 0;      // compute()'s local work on this rank, summed (no ghost import, no reduction)
  // Overlap >= 1 (n_ghost > 0): the ghost rows (imported from their owners into
  // a matrix on ghost_map with a fixed graph), the block's entries from them
  // (after the owned rows' n_from_A entries), and the vectors of apply().
  LO n_own = 0, n_ghost = 0;
  std::size_t n_from_A = 0;
  Teuchos::RCP<const Map> ghost_map;
  Teuchos::RCP<const Tpetra::Import<LO, GO, Node>> ghost_import;  // owned rows -> ghosts
  Teuchos::RCP<Matrix> ghost_rows;
  Kokkos::View<std::size_t*, MemSpace> ghost_source;  // per ghost-row entry: its index in ghost_rows' values
  mutable Teuchos::RCP<MultiVec> xg, sg, yadd;         // apply(): ghost residual, ghost solution, their sum
  Kokkos::View<double*, MemSpace> rhs;                 // apply(): [owned; ghosts], contiguous for CHOLMOD

  Impl() {
    start_cholmod(c);  // LL' factors, relaxed supernodes (solver/cholmod_common.hpp)
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
// block coordinates (owned rows by local id, then the ghosts), sorted per row.
BlockCholmod::BlockCholmod(const Teuchos::RCP<const Matrix>& A, int overlap, bool single) : impl_(new Impl) {
  if (overlap < 0 || overlap > kMaxOverlap)
    throw std::invalid_argument("BlockCholmod: overlap " + std::to_string(overlap) + "; expected 0 to " +
                                std::to_string(kMaxOverlap));
  auto& m = *impl_;
  m.A = A;
  m.want_single = single;
  const auto& rows = *A->getRowMap();
  const auto& cols = *A->getColMap();
  const auto lcl = A->getLocalMatrixHost();
  const LO invalid = Teuchos::OrdinalTraits<LO>::invalid();
  m.n_own = static_cast<LO>(rows.getNodeNumElements());
  // Overlap level 1: the ghosts are A's columns this rank does not own; level
  // l adds the columns of the level-(l-1) ghosts' rows (imported from their
  // owners) that are neither owned nor ghosts yet, as Ifpack2's overlapping
  // row matrix does. Every rank runs the same levels (the imports are collective).
  const bool any_overlap = overlap > 0 && A->getComm()->getSize() > 1;
  const auto make_map = [&](const std::vector<GO>& g) {
    return Teuchos::rcp(new Map(Teuchos::OrdinalTraits<Tpetra::global_size_t>::invalid(),
                                Teuchos::ArrayView<const GO>(g), 0, A->getComm()));
  };
  std::vector<GO> ghosts;
  if (any_overlap) {
    for (std::size_t k = 0; k < cols.getNodeNumElements(); ++k)
      if (rows.getLocalElement(cols.getGlobalElement(k)) == invalid) ghosts.push_back(cols.getGlobalElement(k));
    std::size_t level_begin = 0;  // the last level's ghosts: ghosts[level_begin..]
    for (int level = 2; level <= overlap; ++level) {
      const std::vector<GO> last(ghosts.begin() + static_cast<std::ptrdiff_t>(level_begin), ghosts.end());
      const auto last_map = make_map(last);
      Teuchos::RCP<Matrix> outer;
      A->importAndFillComplete(outer, Tpetra::Import<LO, GO, Node>(A->getRowMap(), last_map), A->getDomainMap(),
                               A->getRangeMap());
      std::vector<GO> known(ghosts);
      std::sort(known.begin(), known.end());
      std::vector<GO> added;
      const auto& ocols = *outer->getColMap();
      for (std::size_t k = 0; k < ocols.getNodeNumElements(); ++k) {
        const GO g = ocols.getGlobalElement(k);
        if (rows.getLocalElement(g) == invalid && !std::binary_search(known.begin(), known.end(), g))
          added.push_back(g);
      }
      std::sort(added.begin(), added.end());
      level_begin = ghosts.size();
      ghosts.insert(ghosts.end(), added.begin(), added.end());
    }
  }
  m.ghost_map = make_map(ghosts);
  m.n_ghost = static_cast<LO>(ghosts.size());
  // Block index of a global DOF (owned: its row id; ghost: n_own + ghost id), or -1.
  auto block_index = [&](GO g) -> LO {
    const LO r = rows.getLocalElement(g);
    if (r != invalid) return r;
    const LO k = m.n_ghost > 0 ? m.ghost_map->getLocalElement(g) : invalid;
    return k == invalid ? -1 : m.n_own + k;
  };
  // The block index of each of A's local columns, looked up once (not per entry).
  std::vector<LO> col_block(cols.getNodeNumElements());
  for (std::size_t k = 0; k < col_block.size(); ++k) col_block[k] = block_index(cols.getGlobalElement(k));
  const std::size_t n = static_cast<std::size_t>(m.n_own + m.n_ghost);
  m.p.assign(n + 1, 0);
  std::vector<std::pair<LO, std::size_t>> row;  // (block column, index in the source's values)
  std::vector<std::size_t> src;
  for (LO r = 0; r < m.n_own; ++r) {
    row.clear();
    for (auto k = lcl.graph.row_map(r); k < lcl.graph.row_map(r + 1); ++k) {
      const LO c = col_block[lcl.graph.entries(k)];
      if (c >= 0) row.emplace_back(c, k);
    }
    std::sort(row.begin(), row.end());
    for (const auto& [c, k] : row) {
      m.i.push_back(c);
      src.push_back(k);
    }
    m.p[r + 1] = static_cast<SuiteSparse_long>(m.i.size());
  }
  m.n_from_A = src.size();
  std::vector<std::size_t> gsrc;
  if (any_overlap) {
    m.ghost_import = Teuchos::rcp(new Tpetra::Import<LO, GO, Node>(A->getRowMap(), m.ghost_map));
    Teuchos::RCP<Matrix> imported;
    A->importAndFillComplete(imported, *m.ghost_import, A->getDomainMap(), A->getRangeMap());
    m.ghost_rows = Teuchos::rcp(new Matrix(imported->getCrsGraph()));  // fixed graph: values re-imported
    m.ghost_rows->fillComplete(A->getDomainMap(), A->getRangeMap());
    const auto gl = imported->getLocalMatrixHost();
    const auto& gcols = *imported->getColMap();
    const auto& grows = *imported->getRowMap();
    std::vector<LO> gcol_block(gcols.getNodeNumElements());
    for (std::size_t k = 0; k < gcol_block.size(); ++k) gcol_block[k] = block_index(gcols.getGlobalElement(k));
    for (LO k = 0; k < m.n_ghost; ++k) {
      const LO r = grows.getLocalElement(m.ghost_map->getGlobalElement(k));
      row.clear();
      for (auto e = gl.graph.row_map(r); e < gl.graph.row_map(r + 1); ++e) {
        const LO c = gcol_block[gl.graph.entries(e)];
        if (c >= 0) row.emplace_back(c, e);
      }
      std::sort(row.begin(), row.end());
      for (const auto& [c, e] : row) {
        m.i.push_back(c);
        gsrc.push_back(e);
      }
      m.p[m.n_own + k + 1] = static_cast<SuiteSparse_long>(m.i.size());
    }
    m.xg = Teuchos::rcp(new MultiVec(m.ghost_map, 1));
    m.sg = Teuchos::rcp(new MultiVec(m.ghost_map, 1));
    m.yadd = Teuchos::rcp(new MultiVec(A->getRowMap(), 1));
  }
  m.source = Kokkos::View<std::size_t*, MemSpace>("block_cholmod_source", src.size());
  auto hs = Kokkos::create_mirror_view(m.source);
  for (std::size_t k = 0; k < src.size(); ++k) hs(k) = src[k];
  Kokkos::deep_copy(m.source, hs);
  m.ghost_source = Kokkos::View<std::size_t*, MemSpace>("block_cholmod_ghost_source", gsrc.size());
  auto hg = Kokkos::create_mirror_view(m.ghost_source);
  for (std::size_t k = 0; k < gsrc.size(); ++k) hg(k) = gsrc[k];
  Kokkos::deep_copy(m.ghost_source, hg);
  m.values = Kokkos::View<double*, MemSpace>("block_cholmod_values", m.i.size());
  m.rhs = Kokkos::View<double*, MemSpace>("block_cholmod_rhs", n);
}

BlockCholmod::~BlockCholmod() = default;

void BlockCholmod::compute() {
  auto& m = *impl_;
  const auto all = m.A->getLocalMatrixDevice().values;
  const auto src = m.source;
  const auto vals = m.values;
  Kokkos::parallel_for(
      "block_cholmod_gather", Kokkos::RangePolicy<ExecSpace>(0, src.extent(0)),
      KOKKOS_LAMBDA(const std::size_t k) { vals(k) = all(src(k)); });
  if (!m.ghost_rows.is_null()) {  // the ghost rows' current values from their owners
    m.ghost_rows->resumeFill();
    m.ghost_rows->doImport(*m.A, *m.ghost_import, Tpetra::REPLACE);
    m.ghost_rows->fillComplete(m.A->getDomainMap(), m.A->getRangeMap());
    const auto gv = m.ghost_rows->getLocalMatrixDevice().values;
    const auto gsrc = m.ghost_source;
    const std::size_t off = m.n_from_A;
    Kokkos::parallel_for(
        "block_cholmod_gather_ghosts", Kokkos::RangePolicy<ExecSpace>(0, gsrc.extent(0)),
        KOKKOS_LAMBDA(const std::size_t k) { vals(off + k) = gv(gsrc(k)); });
  }
  Kokkos::fence();
  cholmod_sparse S = m.view();
  int status = CHOLMOD_OK;
  m.factored = false;
  m.single.forget();
  {
    Kokkos::Timer local;
    CholmodSerialScope serial;
    if (!m.analysed && S.nrow > 0) {
      m.L = cholmod_l_analyze(&S, &m.c);
      status = m.L ? m.c.status : CHOLMOD_INVALID;
      m.analysed = m.L != nullptr;
      m.fl = m.c.fl;
      m.lnz = m.c.lnz;
    }
    if (status >= CHOLMOD_OK && S.nrow > 0) {
      if (!cholmod_l_factorize(&S, m.L, &m.c)) status = m.c.status == CHOLMOD_OK ? CHOLMOD_INVALID : m.c.status;
      else status = m.c.status;
    }
    m.local_s += local.seconds();
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
  m.applies = 0;
  m.factored = true;
}

void BlockCholmod::apply(const MultiVec& Xin, MultiVec& Yout, Teuchos::ETransp, double alpha, double beta) const {
  auto& m = *impl_;
  if (!m.factored) throw std::logic_error("BlockCholmod::apply before a successful compute()");
  const std::size_t n_own = static_cast<std::size_t>(m.n_own), n = m.p.size() - 1;
  const bool ov = !m.ghost_import.is_null();
  for (std::size_t col = 0; col < Xin.getNumVectors(); ++col) {
    // The right-hand side on the block: owned entries, then (overlap) the ghosts' from their owners.
    const auto rhs = m.rhs;
    {
      const auto xv = Xin.getLocalViewDevice(Tpetra::Access::ReadOnly);
      Kokkos::parallel_for(
          "block_cholmod_rhs", Kokkos::RangePolicy<ExecSpace>(0, n_own),
          KOKKOS_LAMBDA(const std::size_t k) { rhs(k) = xv(k, col); });
    }
    if (ov) {
      m.xg->doImport(*Xin.getVector(col), *m.ghost_import, Tpetra::INSERT);
      const auto gv = m.xg->getLocalViewDevice(Tpetra::Access::ReadOnly);
      Kokkos::parallel_for(
          "block_cholmod_rhs_ghosts", Kokkos::RangePolicy<ExecSpace>(0, n - n_own),
          KOKKOS_LAMBDA(const std::size_t k) { rhs(n_own + k) = gv(k, 0); });
    }
    Kokkos::fence();
    const double* s = nullptr;
    ++m.applies;
    if (n > 0 && m.single.ready()) {
      m.single.solve(rhs.data(), rhs.data());
      s = rhs.data();
    } else if (n > 0) {
      cholmod_dense B = dense_column_view(rhs.data(), n);
      CholmodSerialScope serial;
      if (!cholmod_l_solve2(CHOLMOD_A, m.L, &B, nullptr, &m.X, nullptr, &m.Y, &m.E, &m.c) || m.c.status != CHOLMOD_OK)
        throw SolverError("block Cholesky preconditioner (BLOCK_CHOLMOD): CHOLMOD solve status " +
                          std::to_string(m.c.status));
      s = static_cast<const double*>(m.X->x);
    }
    if (ov) {  // the ghosts' parts of the local solution, added into their owners
      {
        auto sv = m.sg->getLocalViewDevice(Tpetra::Access::OverwriteAll);
        Kokkos::parallel_for(
            "block_cholmod_ghost_solution", Kokkos::RangePolicy<ExecSpace>(0, n - n_own),
            KOKKOS_LAMBDA(const std::size_t k) { sv(k, 0) = s[n_own + k]; });
      }
      m.yadd->putScalar(0.0);
      m.yadd->doExport(*m.sg, *m.ghost_import, Tpetra::ADD);
    }
    auto yv = Yout.getLocalViewDevice(Tpetra::Access::ReadWrite);
    if (ov) {
      const auto av = m.yadd->getLocalViewDevice(Tpetra::Access::ReadOnly);
      Kokkos::parallel_for(
          "block_cholmod_apply", Kokkos::RangePolicy<ExecSpace>(0, n_own), KOKKOS_LAMBDA(const std::size_t k) {
            const double z = s[k] + av(k, 0);
            yv(k, col) = beta == 0.0 ? alpha * z : alpha * z + beta * yv(k, col);
          });
    } else {
      Kokkos::parallel_for(
          "block_cholmod_apply", Kokkos::RangePolicy<ExecSpace>(0, n_own), KOKKOS_LAMBDA(const std::size_t k) {
            yv(k, col) = beta == 0.0 ? alpha * s[k] : alpha * s[k] + beta * yv(k, col);
          });
    }
    Kokkos::fence();
  }
}

Teuchos::RCP<const Map> BlockCholmod::getDomainMap() const { return impl_->A->getDomainMap(); }
Teuchos::RCP<const Map> BlockCholmod::getRangeMap() const { return impl_->A->getRangeMap(); }
double BlockCholmod::factor_flops() const { return impl_->fl; }
double BlockCholmod::local_factor_seconds() const { return impl_->local_s; }
double BlockCholmod::iteration_flops() const {
  return 4.0 * impl_->lnz + 2.0 * static_cast<double>(impl_->A->getNodeNumEntries());
}
std::size_t BlockCholmod::block_rows() const { return impl_->p.size() - 1; }
std::size_t BlockCholmod::block_entries() const { return impl_->i.size(); }
bool BlockCholmod::applies_single() const { return impl_->single.ready(); }
bool BlockCholmod::supernodal() const {
  const auto& m = *impl_;
  return m.p.size() <= 1 || (m.L != nullptr && m.L->is_super);
}

void BlockCholmod::new_step() { impl_->single.new_step(); }

void BlockCholmod::prepare_solve() {
  auto& m = *impl_;
  if (m.want_single && m.factored && m.p.size() > 1) m.single.copy_if_worth(*m.L, m.applies);
}

}  // namespace bfemp
