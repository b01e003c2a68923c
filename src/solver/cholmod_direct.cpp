#include "solver/cholmod_direct.hpp"

#include <Tpetra_CrsMatrix.hpp>
#include <Tpetra_Vector.hpp>
#include <cholmod.h>
#include <cstring>
#include <string>
#include <vector>

#include "solver/solver_error.hpp"

namespace bfemp {

static_assert(Kokkos::SpaceAccessibility<Kokkos::HostSpace, MemSpace>::accessible,
              "CholmodDirect hands CHOLMOD the matrix's own arrays: they must be host-accessible");

namespace {
std::string status_name(int s) {
  switch (s) {
    case CHOLMOD_OK: return "CHOLMOD_OK";
    case CHOLMOD_NOT_POSDEF: return "CHOLMOD_NOT_POSDEF (matrix not positive definite)";
    case CHOLMOD_OUT_OF_MEMORY: return "CHOLMOD_OUT_OF_MEMORY";
    case CHOLMOD_TOO_LARGE: return "CHOLMOD_TOO_LARGE";
    case CHOLMOD_INVALID: return "CHOLMOD_INVALID";
    case CHOLMOD_DSMALL: return "CHOLMOD_DSMALL (tiny diagonal)";
    default: return "CHOLMOD status " + std::to_string(s);
  }
}
}  // namespace

struct CholmodDirect::Impl {
  cholmod_common c{};
  cholmod_factor* L = nullptr;
  cholmod_dense* X = nullptr;  // solution workspace, reused
  cholmod_dense* Y = nullptr;
  cholmod_dense* E = nullptr;
  Teuchos::RCP<const Matrix> A;
  std::vector<SuiteSparse_long> p, i;  // CHOLMOD's index type; built once per graph
  bool analysed = false;

  Impl() {
    cholmod_l_start(&c);
    c.print = 0;
    c.error_handler = nullptr;  // errors come back as c.status
  }
  ~Impl() {
    if (L) cholmod_l_free_factor(&L, &c);
    if (X) cholmod_l_free_dense(&X, &c);
    if (Y) cholmod_l_free_dense(&Y, &c);
    if (E) cholmod_l_free_dense(&E, &c);
    cholmod_l_finish(&c);
  }

  cholmod_sparse view() {
    auto lcl = A->getLocalMatrixDevice();
    cholmod_sparse S{};
    S.nrow = S.ncol = static_cast<std::size_t>(lcl.numRows());
    S.nzmax = i.size();
    S.p = p.data();
    S.i = i.data();
    S.x = lcl.values.data();  // the matrix's own values, not a copy
    S.stype = 1;
    S.itype = CHOLMOD_LONG;
    S.xtype = CHOLMOD_REAL;
    S.dtype = CHOLMOD_DOUBLE;
    S.sorted = 1;
    S.packed = 1;
    return S;
  }
};

CholmodDirect::CholmodDirect() : impl_(new Impl) {}
CholmodDirect::~CholmodDirect() = default;

void CholmodDirect::set_matrix(const Teuchos::RCP<const Matrix>& A) {
  auto& m = *impl_;
  m.A = A;
  auto lcl = A->getLocalMatrixDevice();
  const std::size_t n = static_cast<std::size_t>(lcl.numRows());
  m.p.resize(n + 1);
  for (std::size_t r = 0; r <= n; ++r) m.p[r] = static_cast<SuiteSparse_long>(lcl.graph.row_map(r));
  m.i.resize(lcl.graph.entries.extent(0));
  for (std::size_t k = 0; k < m.i.size(); ++k) m.i[k] = lcl.graph.entries(k);
  if (m.L) cholmod_l_free_factor(&m.L, &m.c);
  m.analysed = false;
}

bool CholmodDirect::solve(const Vector& b, Vector& x) {
  auto& m = *impl_;
  if (m.A.is_null()) throw std::logic_error("CholmodDirect::solve before set_matrix");
  cholmod_sparse S = m.view();
  bool analysed_now = false;
  if (!m.analysed) {
    m.L = cholmod_l_analyze(&S, &m.c);
    if (!m.L || m.c.status < CHOLMOD_OK)
      throw SolverError("Cholmod analysis failed: " + status_name(m.c.status));
    m.analysed = true;
    analysed_now = true;
  }
  if (!cholmod_l_factorize(&S, m.L, &m.c) || m.c.status != CHOLMOD_OK) {
    if (m.c.status == CHOLMOD_NOT_POSDEF)
      throw NotPositiveDefinite("Cholmod factorisation failed: " + status_name(m.c.status));
    throw SolverError("Cholmod factorisation failed: " + status_name(m.c.status));
  }
  auto bv = b.getLocalViewDevice(Tpetra::Access::ReadOnly);
  cholmod_dense B{};
  B.nrow = S.nrow;
  B.ncol = 1;
  B.nzmax = S.nrow;
  B.d = S.nrow;
  B.x = const_cast<double*>(bv.data());
  B.xtype = CHOLMOD_REAL;
  B.dtype = CHOLMOD_DOUBLE;
  if (!cholmod_l_solve2(CHOLMOD_A, m.L, &B, nullptr, &m.X, nullptr, &m.Y, &m.E, &m.c) || m.c.status != CHOLMOD_OK)
    throw SolverError("Cholmod solve failed: " + status_name(m.c.status));
  auto xv = x.getLocalViewDevice(Tpetra::Access::OverwriteAll);
  std::memcpy(xv.data(), m.X->x, S.nrow * sizeof(double));
  return analysed_now;
}

}  // namespace bfemp
