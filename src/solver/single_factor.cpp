#include "solver/single_factor.hpp"

#include <Kokkos_Core.hpp>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>
#include <utility>

#include "solver/supernode_kernels.hpp"

namespace bfemp {

void SingleFactor::clear() {
  n_ = 0;
  schedule_.clear();
  schedule_tried_ = 0;
}  // (the buffers stay: the next copy writes over them)

bool SingleFactor::assign(const cholmod_factor& L) {
  clear();
  if (!L.is_super || !L.is_ll || L.xtype != CHOLMOD_REAL || L.dtype != CHOLMOD_DOUBLE ||
      L.itype != CHOLMOD_LONG || L.minor < L.n || L.x == nullptr || L.Perm == nullptr || L.n == 0)
    return false;
  const auto* super = static_cast<const SuiteSparse_long*>(L.super);
  const auto* pi = static_cast<const SuiteSparse_long*>(L.pi);
  const auto* px = static_cast<const SuiteSparse_long*>(L.px);
  const auto* s = static_cast<const SuiteSparse_long*>(L.s);
  const auto* perm = static_cast<const SuiteSparse_long*>(L.Perm);
  const std::size_t ns = L.nsuper;
  perm_.assign(perm, perm + L.n);
  super_.assign(super, super + ns + 1);
  pi_.assign(pi, pi + ns + 1);
  px_.assign(px, px + ns + 1);
  s_.assign(s, s + L.ssize);
  const std::size_t room = L.xsize + L.xsize / 4;
  step_room_ = std::max(step_room_, room);
  if (L.xsize > x_.capacity()) {  // a new buffer: nothing of the old one to keep
    x_.clear();
    x_.shrink_to_fit();
    x_.reserve(room);
  }
  x_.resize(L.xsize);
  // Round to float; an entry out of float's range, or a diagonal entry that
  // is not a normal positive float, leaves the copy unusable (the caller then
  // solves with the double factor).
  const double* lx = static_cast<const double*>(L.x);
  float* fx = x_.data();
  constexpr double kMax = static_cast<double>(std::numeric_limits<float>::max());
  long bad = 0;
  Kokkos::parallel_reduce(
      "single_factor_round", Kokkos::RangePolicy<Kokkos::DefaultHostExecutionSpace>(0, L.xsize),
      [=](const std::size_t k, long& acc) {
        const double a = lx[k];
        if (!(std::abs(a) <= kMax)) ++acc;
        fx[k] = static_cast<float>(a);
      },
      bad);
  if (bad == 0) {
    for (std::size_t k = 0; k < ns && bad == 0; ++k) {
      const SuiteSparse_long nscol = super[k + 1] - super[k], nsrow = pi[k + 1] - pi[k];
      for (SuiteSparse_long j = 0; j < nscol; ++j)
        if (!(fx[px[k] + j * nsrow + j] >= std::numeric_limits<float>::min())) ++bad;
    }
  }
  if (bad != 0) {
    clear();
    return false;
  }
  SuiteSparse_long rows = 0;
  for (std::size_t k = 0; k < ns; ++k) rows = std::max(rows, pi[k + 1] - pi[k]);
  w_.resize(L.n);
  v_.resize(static_cast<std::size_t>(rows));
  max_rows_ = rows;
  n_ = L.n;
  return true;
}

namespace {

using supernode::Long;

// The rows [lo, hi) shared among a team: thread t's contiguous part.
inline std::pair<Long, Long> share(Long lo, Long hi, int t, int team) {
  const Long len = hi - lo;
  return {lo + len * t / team, lo + len * (t + 1) / team};
}

}  // namespace

// Forward solve of supernode k on one thread: v holds its rows; the columns'
// own rows are solved in v, the rows below collect -L21 y1 and are added into
// w, or, for rows at or beyond col_end when buf is given, into buf (the top's
// rows, indexed by top_index).
void SingleFactor::forward_one(std::size_t k, double* w, double* v, Long col_end, double* buf) const {
  const Long k1 = super_[k], nscol = super_[k + 1] - k1;
  const Long psi = pi_[k], nsrow = pi_[k + 1] - psi;
  const Long* s = s_.data() + psi;
  for (Long i = 0; i < nscol; ++i) v[i] = w[k1 + i];
  for (Long i = nscol; i < nsrow; ++i) v[i] = 0.0;
  supernode::forward_columns(x_.data() + px_[k], nsrow, 0, nscol, v, nsrow);
  for (Long i = 0; i < nscol; ++i) w[k1 + i] = v[i];
  if (buf == nullptr) {
    for (Long i = nscol; i < nsrow; ++i) w[s[i]] += v[i];
    return;
  }
  const Long* top_index = schedule_.top_index.data();
  Long i = nscol;
  for (; i < nsrow && s[i] < col_end; ++i) w[s[i]] += v[i];  // rows sorted: the subtree's own first
  for (; i < nsrow; ++i) buf[top_index[s[i]]] += v[i];
}

// Backward solve of supernode k on one thread (its rows below are final).
void SingleFactor::backward_one(std::size_t k, double* w, double* v) const {
  const Long k1 = super_[k], nscol = super_[k + 1] - k1;
  const Long psi = pi_[k], nsrow = pi_[k + 1] - psi;
  const Long* s = s_.data() + psi;
  for (Long i = 0; i < nscol; ++i) v[i] = w[k1 + i];
  for (Long i = nscol; i < nsrow; ++i) v[i] = w[s[i]];
  supernode::backward_columns(x_.data() + px_[k], nsrow, 0, nscol, v, nsrow, nullptr);
  for (Long i = 0; i < nscol; ++i) w[k1 + i] = v[i];
}

void SingleFactor::solve_serial(double* w) {
  const std::size_t ns = super_.size() - 1;
  double* v = v_.data();
  for (std::size_t k = 0; k < ns; ++k) forward_one(k, w, v, 0, nullptr);
  for (std::size_t k = ns; k-- > 0;) backward_one(k, w, v);
}

// Supernode k solved by the whole team (called by every thread of it): each
// panel of kPanel columns is solved by thread 0 down to the panel's last row,
// then every thread applies it to its share of the rows below. v is shared.
void SingleFactor::forward_shared(std::size_t k, double* w, double* v, int t, int team) const {
  const Long k1 = super_[k], nscol = super_[k + 1] - k1;
  const Long psi = pi_[k], nsrow = pi_[k + 1] - psi;
  const Long* s = s_.data() + psi;
  const float* lk = x_.data() + px_[k];
  auto [lo, hi] = share(0, nsrow, t, team);
  for (Long i = lo; i < hi; ++i) v[i] = i < nscol ? w[k1 + i] : 0.0;
#pragma omp barrier
  for (Long p0 = 0; p0 < nscol; p0 += SupernodeSchedule::kPanel) {
    const Long pe = std::min(p0 + SupernodeSchedule::kPanel, nscol);
    if (t == 0) supernode::forward_columns(lk, nsrow, p0, pe, v, pe);
#pragma omp barrier
    const auto [ib, ie] = share(pe, nsrow, t, team);
    Long j = p0;
    for (; j + supernode::kBlock <= pe; j += supernode::kBlock)
      supernode::update_rows<supernode::kBlock>(lk, nsrow, j, v, ib, ie);
    for (; j < pe; ++j) supernode::update_rows<1>(lk, nsrow, j, v, ib, ie);
#pragma omp barrier
  }
  for (Long i = lo; i < hi; ++i) {
    if (i < nscol)
      w[k1 + i] = v[i];
    else
      w[s[i]] += v[i];
  }
#pragma omp barrier
}

void SingleFactor::backward_shared(std::size_t k, double* w, double* v, int t, int team) {
  const Long k1 = super_[k], nscol = super_[k + 1] - k1;
  const Long psi = pi_[k], nsrow = pi_[k + 1] - psi;
  const Long* s = s_.data() + psi;
  const float* lk = x_.data() + px_[k];
  constexpr Long kPanel = SupernodeSchedule::kPanel;
  auto [lo, hi] = share(0, nsrow, t, team);
  for (Long i = lo; i < hi; ++i) v[i] = i < nscol ? w[k1 + i] : w[s[i]];
#pragma omp barrier
  // The rows below a panel in P = schedule_.threads shares whatever the team's
  // size (share u taken by thread u mod team), summed in share order: the
  // same bits with a smaller team.
  const int P = schedule_.threads;
  for (Long p0 = (nscol - 1) / kPanel * kPanel; p0 >= 0; p0 -= kPanel) {
    const Long pe = std::min(p0 + kPanel, nscol);
    for (int u = t; u < P; u += team) {
      double* part = part_.data() + static_cast<std::size_t>(u) * kPanel;
      for (Long c = 0; c < pe - p0; ++c) part[c] = 0.0;
      const auto [ib, ie] = share(pe, nsrow, u, P);
      Long j = p0;
      for (; j + supernode::kBlock <= pe; j += supernode::kBlock)
        supernode::dot_rows<supernode::kBlock>(lk, nsrow, j, v, ib, ie, part + (j - p0));
      for (; j < pe; ++j) supernode::dot_rows<1>(lk, nsrow, j, v, ib, ie, part + (j - p0));
    }
#pragma omp barrier
    if (t == 0) {
      double acc[kPanel];
      for (Long c = 0; c < pe - p0; ++c) {
        double a = 0.0;
        for (int q = 0; q < P; ++q) a += part_[static_cast<std::size_t>(q) * kPanel + c];
        acc[c] = a;
      }
      supernode::backward_columns(lk, nsrow, p0, pe, v, pe, acc);
    }
#pragma omp barrier
  }
  std::tie(lo, hi) = share(0, nscol, t, team);
  for (Long i = lo; i < hi; ++i) w[k1 + i] = v[i];
#pragma omp barrier
}

void SingleFactor::solve_threaded(double* w) {
  const SupernodeSchedule& S = schedule_;
  const int P = S.threads;
  const std::size_t nt = S.top_rows.size();
  const auto rows = static_cast<std::size_t>(max_rows_);
#pragma omp parallel num_threads(P)
  {
    const int t = omp_get_thread_num(), team = omp_get_num_threads();
    double* v = vt_.data() + static_cast<std::size_t>(t) * rows;
    // The subtrees, forward: thread t solves those dealt to t, t + team, ...
    // (all of them when the team is smaller than the schedule's).
    for (int u = t; u < P; u += team) {
      double* buf = buf_.data() + static_cast<std::size_t>(u) * nt;
      std::fill(buf, buf + nt, 0.0);
      for (int o = S.thread_begin[u]; o < S.thread_begin[u + 1]; ++o) {
        const auto q = static_cast<std::size_t>(S.order[o]);
        for (Long k = S.first[q]; k <= S.root[q]; ++k) forward_one(static_cast<std::size_t>(k), w, v, S.col_end[q], buf);
      }
    }
#pragma omp barrier
    {
      const auto [lo, hi] = share(0, static_cast<Long>(nt), t, team);
      for (Long q = lo; q < hi; ++q) {
        double a = 0.0;
        for (int u = 0; u < P; ++u) a += buf_[static_cast<std::size_t>(u) * nt + static_cast<std::size_t>(q)];
        w[S.top_rows[static_cast<std::size_t>(q)]] += a;
      }
    }
#pragma omp barrier
    // The top, forward (children first), then backward (parents first).
    double* shared = v_.data();
    for (std::size_t i = 0; i < S.top.size(); ++i) {
      const auto k = static_cast<std::size_t>(S.top[i]);
      if (S.top_shared[i]) {
#pragma omp barrier
        forward_shared(k, w, shared, t, team);
      } else if (t == 0) {
        forward_one(k, w, v, 0, nullptr);
      }
    }
#pragma omp barrier
    for (std::size_t i = S.top.size(); i-- > 0;) {
      const auto k = static_cast<std::size_t>(S.top[i]);
      if (S.top_shared[i]) {
#pragma omp barrier
        backward_shared(k, w, shared, t, team);
      } else if (t == 0) {
        backward_one(k, w, v);
      }
    }
#pragma omp barrier
    // The subtrees, backward: each reads the top's rows, now final.
    for (int u = t; u < P; u += team)
      for (int o = S.thread_begin[u]; o < S.thread_begin[u + 1]; ++o) {
        const auto q = static_cast<std::size_t>(S.order[o]);
        for (Long k = S.root[q]; k >= S.first[q]; --k) backward_one(static_cast<std::size_t>(k), w, v);
      }
  }
}

void SingleFactor::solve(const double* b, double* z, int threads) {
  const std::size_t n = n_;
  const SuiteSparse_long* perm = perm_.data();
  double* w = w_.data();
  bool threaded = threads > 1;  // as asked
  if (threads <= 0) {           // as the host's threads and the factor's size make worth it
    threads = Kokkos::DefaultHostExecutionSpace().concurrency();
    threaded = threads > 1 && x_.size() >= kThreadedEntries;
  }
  if (threaded && schedule_tried_ != threads) {
    schedule_tried_ = threads;
    if (schedule_.build(threads, n, super_.size() - 1, super_.data(), pi_.data(), s_.data())) {
      vt_.resize(static_cast<std::size_t>(threads) * static_cast<std::size_t>(max_rows_));
      buf_.resize(static_cast<std::size_t>(threads) * schedule_.top_rows.size());
      part_.resize(static_cast<std::size_t>(threads) * SupernodeSchedule::kPanel);
    }
  }
  threaded = threaded && schedule_.threads == threads;
  for (std::size_t i = 0; i < n; ++i) w[i] = b[perm[i]];
  if (threaded)
    solve_threaded(w);
  else
    solve_serial(w);
  for (std::size_t i = 0; i < n; ++i) z[perm[i]] = w[i];
}

}  // namespace bfemp
