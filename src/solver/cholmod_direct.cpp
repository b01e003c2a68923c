#include "solver/cholmod_direct.hpp"

#include <Tpetra_CrsMatrix.hpp>
#include <Tpetra_Vector.hpp>
#include <cholmod.h>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include "solver/blas_threads.hpp"
#include "solver/cholmod_common.hpp"
#include "solver/cholmod_views.hpp"
#include "solver/single_factor.hpp"
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
  cholmod_factor* L = nullptr;      // the factor solves use (after the analysis: symbolic)
  cholmod_factor* spare = nullptr;  // same analysis; a factorisation while L is valid goes here,
                                    // so a failed one (not positive definite) leaves L usable
  cholmod_dense* X = nullptr;  // solution workspace, reused
  cholmod_dense* Y = nullptr;
  cholmod_dense* E = nullptr;
  Teuchos::RCP<const Matrix> A;
  std::vector<SuiteSparse_long> p, i;  // CHOLMOD's index type; built once per graph
  bool analysed = false;
  bool factor_ok = false;  // L holds a complete numeric factor of this graph
  SingleFactor single;      // L in float (reuse.single), made once L has served a few CG iterations
  int cg_on_factor = 0;       // CG iterations run on this factor so far
  bool spare_wanted = false;  // a non-positive pivot was met in this step: keep L while refactorising
  Reuse reuse;
  int budget = 0;  // CG iterations allowed on the previous factor (reuse.max_iterations, or by cost)
  double flops = 0;  // of one numeric factorisation (the analysis' Common->fl)
  using V = Kokkos::View<double*, MemSpace>;
  V cg_x, cg_r, cg_z, cg_p, cg_q;  // CG work, sized once per graph

  explicit Impl(Reuse r) : reuse(r) {
    start_cholmod(c);  // LL' factors, relaxed supernodes (solver/cholmod_common.hpp)
  }
  ~Impl() {
    if (L) cholmod_l_free_factor(&L, &c);
    if (spare) cholmod_l_free_factor(&spare, &c);
    if (X) cholmod_l_free_dense(&X, &c);
    if (Y) cholmod_l_free_dense(&Y, &c);
    if (E) cholmod_l_free_dense(&E, &c);
    cholmod_l_finish(&c);
  }

  cholmod_sparse view() {  // the matrix's own values, not a copy
    return symmetric_csc_view(p, i, A->getLocalMatrixDevice().values.data());
  }
};

CholmodDirect::CholmodDirect(Reuse reuse) : impl_(new Impl(reuse)) {}
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
  if (m.spare) cholmod_l_free_factor(&m.spare, &m.c);
  m.analysed = false;
  m.factor_ok = false;
  m.single.forget();
  if (m.reuse.max_iterations > 0 && m.cg_x.extent(0) != n) {
    m.cg_x = Impl::V("cholmod_cg_x", n);
    m.cg_r = Impl::V("cholmod_cg_r", n);
    m.cg_z = Impl::V("cholmod_cg_z", n);
    m.cg_p = Impl::V("cholmod_cg_p", n);
    m.cg_q = Impl::V("cholmod_cg_q", n);
  }
}

void CholmodDirect::forget_factor() {  // a new step starts as a restart would
  impl_->factor_ok = false;
  impl_->single.new_step();
  impl_->spare_wanted = false;
}

namespace {
using Range = Kokkos::RangePolicy<ExecSpace>;

// Row i of A times v, summed in four interleaved partial sums: one running sum
// is a chain of dependent adds (4 cycles each here), and a 3D MPM row has
// about 375 entries, so a single sum made the product compute-bound at a
// third of the memory bandwidth. The order is fixed by the row alone.
template <class Rows, class Cols, class Vals, class V>
KOKKOS_INLINE_FUNCTION double row_times(const Rows& rows, const Cols& cols, const Vals& vals, const V& v,
                                        const std::size_t i) {
  double a0 = 0, a1 = 0, a2 = 0, a3 = 0;
  auto k = rows(i);
  const auto end = rows(i + 1);
  for (; k + 4 <= end; k += 4) {
    a0 += vals(k) * v(cols(k));
    a1 += vals(k + 1) * v(cols(k + 1));
    a2 += vals(k + 2) * v(cols(k + 2));
    a3 += vals(k + 3) * v(cols(k + 3));
  }
  for (; k < end; ++k) a0 += vals(k) * v(cols(k));
  return (a0 + a1) + (a2 + a3);
}

double dot(const Kokkos::View<double*, MemSpace>& a, const Kokkos::View<double*, MemSpace>& b) {
  double s = 0;
  Kokkos::parallel_reduce(
      "cholmod_cg_dot", Range(0, a.extent(0)), KOKKOS_LAMBDA(const std::size_t k, double& acc) { acc += a(k) * b(k); }, s);
  return s;
}
}  // namespace

// CG on A x = b preconditioned by the stored factor; true when it reached the
// tolerance (x then in m.cg_x). `its` counts the iterations run.
static bool cg_on_old_factor(CholmodDirect::Reuse reuse, cholmod_common& c, cholmod_factor* L, SingleFactor& single,
                             cholmod_dense*& X, cholmod_dense*& Y, cholmod_dense*& E, const Matrix& A, const Vector& b,
                             Kokkos::View<double*, MemSpace> x, Kokkos::View<double*, MemSpace> r,
                             Kokkos::View<double*, MemSpace> z, Kokkos::View<double*, MemSpace> p,
                             Kokkos::View<double*, MemSpace> q, const Vector* x0, int& its) {
  const auto lcl = A.getLocalMatrixDevice();
  const auto rows = lcl.graph.row_map;
  const auto cols = lcl.graph.entries;
  const auto vals = lcl.values;
  const std::size_t n = x.extent(0);
  const auto bv = b.getLocalViewDevice(Tpetra::Access::ReadOnly);
  double bn = 0;
  Kokkos::parallel_reduce(
      "cholmod_cg_bnorm", Range(0, n), KOKKOS_LAMBDA(const std::size_t k, double& acc) { acc += bv(k, 0) * bv(k, 0); },
      bn);
  bn = std::sqrt(bn);
  its = 0;
  if (bn == 0.0) {
    Kokkos::deep_copy(x, 0.0);
    return true;
  }
  if (x0) {  // r = b - A x0: CG goes on from the caller's iterate
    const auto xv = x0->getLocalViewDevice(Tpetra::Access::ReadOnly);
    const auto x0v = Kokkos::subview(xv, Kokkos::ALL, 0);
    Kokkos::parallel_for(
        "cholmod_cg_init_from", Range(0, n), KOKKOS_LAMBDA(const std::size_t i) {
          x(i) = xv(i, 0);
          r(i) = bv(i, 0) - row_times(rows, cols, vals, x0v, i);
        });
  } else {
    Kokkos::parallel_for(
        "cholmod_cg_init", Range(0, n), KOKKOS_LAMBDA(const std::size_t k) {
          x(k) = 0.0;
          r(k) = bv(k, 0);
        });
  }
  double r0n = x0 ? std::sqrt(dot(r, r)) : bn;  // the rate test measures from here
  if (x0 && !(r0n <= bn)) {  // a start worse than 0: from 0
    Kokkos::parallel_for(
        "cholmod_cg_init", Range(0, n), KOKKOS_LAMBDA(const std::size_t k) {
          x(k) = 0.0;
          r(k) = bv(k, 0);
        });
    r0n = bn;
  }
  const double stop = reuse.tolerance * bn;
  if (r0n <= stop) return true;
  auto precondition = [&]() {  // z = (L L^T)^-1 r
    if (single.ready()) {
      Kokkos::fence();
      single.solve(r.data(), z.data());
      return true;
    }
    cholmod_dense R = dense_column_view(r.data(), n);
    {
      CholmodSerialScope serial;
      if (!cholmod_l_solve2(CHOLMOD_A, L, &R, nullptr, &X, nullptr, &Y, &E, &c) || c.status != CHOLMOD_OK) return false;
    }
    const double* xs = static_cast<const double*>(X->x);
    Kokkos::parallel_for("cholmod_cg_z", Range(0, n), KOKKOS_LAMBDA(const std::size_t k) { z(k) = xs[k]; });
    return true;
  };
  if (!precondition()) return false;
  Kokkos::deep_copy(p, z);
  double rz = dot(r, z);
  for (its = 1; its <= reuse.max_iterations; ++its) {
    Kokkos::parallel_for(
        "cholmod_cg_spmv", Range(0, n), KOKKOS_LAMBDA(const std::size_t i) {
          q(i) = row_times(rows, cols, vals, p, i);
        });
    const double pq = dot(p, q);
    if (!(pq > 0.0) || !(rz > 0.0)) {
      // p^T A p < 0 for some p proves A indefinite, whatever the
      // preconditioner: say so without a factorisation bound to fail. A
      // round-off zero (a positive semi-definite A) goes to the factorisation.
      const double pn = std::sqrt(dot(p, p)), qn = std::sqrt(dot(q, q));
      if (pq < -1e-8 * pn * qn)
        throw NotPositiveDefinite("CG on the previous Cholmod factor met negative curvature (p^T A p = " +
                                  std::to_string(pq) + "): the matrix is not positive definite");
      return false;
    }
    const double alpha = rz / pq;
    double rr = 0;
    Kokkos::parallel_reduce(
        "cholmod_cg_update", Range(0, n),
        KOKKOS_LAMBDA(const std::size_t k, double& acc) {
          x(k) += alpha * p(k);
          r(k) -= alpha * q(k);
          acc += r(k) * r(k);
        },
        rr);
    const double rn = std::sqrt(rr);
    if (!std::isfinite(rn)) return false;
    if (rn <= stop) return true;
    // Too slow to arrive within the cap at the mean rate so far: factorise.
    if (its >= 4 && its < reuse.max_iterations) {
      const double rate = std::pow(rn / r0n, 1.0 / its);
      if (rate >= 1.0 || its + std::log(stop / rn) / std::log(rate) > reuse.max_iterations) return false;
    }
    if (its == reuse.max_iterations) break;
    if (!precondition()) return false;
    const double rz1 = dot(r, z);
    const double beta = rz1 / rz;
    rz = rz1;
    Kokkos::parallel_for("cholmod_cg_dir", Range(0, n), KOKKOS_LAMBDA(const std::size_t k) { p(k) = z(k) + beta * p(k); });
  }
  its = std::min(its, reuse.max_iterations);
  return false;
}

CholmodDirect::Result CholmodDirect::solve(const Vector& b, Vector& x, double tolerance, bool from_x) {
  auto& m = *impl_;
  if (m.A.is_null()) throw std::logic_error("CholmodDirect::solve before set_matrix");
  Result res;
  if (m.factor_ok && m.reuse.max_iterations > 0) {
    Kokkos::Timer cg_timer;
    Reuse r = m.reuse;
    r.max_iterations = m.budget;
    r.tolerance = std::max(r.tolerance, tolerance);
    res.cg_budget = m.budget;
    if (m.reuse.single) m.single.copy_if_worth(*m.L, m.cg_on_factor);
    res.cg_single = m.single.ready();
    const bool ok = cg_on_old_factor(r, m.c, m.L, m.single, m.X, m.Y, m.E, *m.A, b, m.cg_x, m.cg_r, m.cg_z, m.cg_p,
                                     m.cg_q, from_x ? &x : nullptr, res.cg_iterations);
    res.cg_s = cg_timer.seconds();
    m.cg_on_factor += res.cg_iterations;
    if (ok) {
      res.tolerance = r.tolerance;
      auto xv = x.getLocalViewDevice(Tpetra::Access::OverwriteAll);
      const auto cx = m.cg_x;
      Kokkos::parallel_for("cholmod_cg_out", Kokkos::RangePolicy<ExecSpace>(0, cx.extent(0)),
                           KOKKOS_LAMBDA(const std::size_t k) { xv(k, 0) = cx(k); });
      Kokkos::fence();
      return res;
    }
  }
  cholmod_sparse S = m.view();
  Kokkos::Timer factor_timer;
  bool analysed_now = false;
  if (!m.analysed) {
    {
      CholmodSerialScope serial;  // each CHOLMOD call in one, with no Kokkos kernel inside
      m.L = cholmod_l_analyze(&S, &m.c);
    }
    if (!m.L || m.c.status < CHOLMOD_OK)
      throw SolverError("Cholmod analysis failed: " + status_name(m.c.status));
    m.analysed = true;
    m.flops = m.c.fl;
    analysed_now = true;
    m.budget = m.reuse.max_iterations;
    if (m.reuse.by_cost && m.reuse.max_iterations > 0 && m.L->is_super) {  // (a simplicial factor: no BLAS 3)
      const double per_iteration = 4.0 * static_cast<double>(m.L->xsize) + 2.0 * static_cast<double>(m.i.size());
      const double by_cost = std::min<double>(Reuse::kMaxByCost, m.c.fl / (Reuse::kBlas3Advantage * per_iteration));
      m.budget = std::max(m.budget, static_cast<int>(by_cost));
    }
  }
  res.analysed = analysed_now;
  res.factorised = true;
  // With reuse, once a non-positive pivot has been met (exact Hessian), keep
  // the valid factor until the new one succeeds, so that the projected
  // matrix's solve can still run CG on it. The spare is a copy made once per
  // graph, and only in runs that meet such pivots (it doubles the factor's
  // memory).
  const bool keep = m.factor_ok && m.reuse.max_iterations > 0 && m.spare_wanted;
  if (keep && !m.spare) {
    CholmodSerialScope serial;
    m.spare = cholmod_l_copy_factor(m.L, &m.c);
    if (!m.spare) throw SolverError("Cholmod factor copy failed: " + status_name(m.c.status));
  }
  cholmod_factor* target = keep ? m.spare : m.L;
  if (!keep) m.factor_ok = false;

  bool factorised;
  {
    BlasTeamScope team(m.flops);  // a large factorisation: the BLAS on the team's cores
    CholmodSerialScope serial;
    factorised = cholmod_l_factorize(&S, target, &m.c);
  }
  if (!factorised || m.c.status != CHOLMOD_OK) {
    if (m.c.status == CHOLMOD_NOT_POSDEF) {
      m.spare_wanted = true;
      throw NotPositiveDefinite("Cholmod factorisation failed: " + status_name(m.c.status));
    }
    throw SolverError("Cholmod factorisation failed: " + status_name(m.c.status));
  }
  if (keep) std::swap(m.L, m.spare);
  m.factor_ok = true;
  m.single.forget();
  m.cg_on_factor = 0;
  res.factor_s = factor_timer.seconds();
  auto bv = b.getLocalViewDevice(Tpetra::Access::ReadOnly);
  cholmod_dense B = dense_column_view(const_cast<double*>(bv.data()), S.nrow);
  bool solved;
  {
    CholmodSerialScope serial;
    solved = cholmod_l_solve2(CHOLMOD_A, m.L, &B, nullptr, &m.X, nullptr, &m.Y, &m.E, &m.c);
  }
  if (!solved || m.c.status != CHOLMOD_OK) throw SolverError("Cholmod solve failed: " + status_name(m.c.status));
  auto xv = x.getLocalViewDevice(Tpetra::Access::OverwriteAll);
  std::memcpy(xv.data(), m.X->x, S.nrow * sizeof(double));
  return res;
}

}  // namespace bfemp
