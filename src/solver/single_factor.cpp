#include "solver/single_factor.hpp"

#include <Kokkos_Core.hpp>
#include <algorithm>
#include <cmath>
#include <limits>

namespace bfemp {

void SingleFactor::clear() { n_ = 0; }  // (the buffers stay: the next copy writes over them)

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
  n_ = L.n;
  return true;
}

namespace {

// One supernode's columns j0 .. j0+B-1 (stored columns c[0..B), nsrow rows, v
// the supernode's rows). Forward: solve the B x B triangle at rows j0.., then
// v[i] -= sum_k c_k[i] y_k for every row below it (the rest of the diagonal
// block and the rows outside it alike), so v is read and written once per B
// columns.
template <int B>
inline void forward_block(const float* lk, SuiteSparse_long nsrow, SuiteSparse_long j0, double* v) {
  const float* c[B];
  for (int k = 0; k < B; ++k) c[k] = lk + (j0 + k) * nsrow;
  double y[B];
  for (int k = 0; k < B; ++k) {
    double a = v[j0 + k];
    for (int q = 0; q < k; ++q) a -= static_cast<double>(c[q][j0 + k]) * y[q];
    y[k] = a / static_cast<double>(c[k][j0 + k]);
    v[j0 + k] = y[k];
  }
#pragma omp simd
  for (SuiteSparse_long i = j0 + B; i < nsrow; ++i) {
    double a = 0.0;
    for (int k = 0; k < B; ++k) a += static_cast<double>(c[k][i]) * y[k];
    v[i] -= a;
  }
}

// Backward: the rows below the block are final; each column's dot product
// with them (B columns share the loads of v), then the B x B triangle
// transposed, last column first.
template <int B>
inline void backward_block(const float* lk, SuiteSparse_long nsrow, SuiteSparse_long j0, double* v) {
  const float* c[B];
  for (int k = 0; k < B; ++k) c[k] = lk + (j0 + k) * nsrow;
  double acc[B] = {};
  if constexpr (B == 8) {
    double a0 = 0, a1 = 0, a2 = 0, a3 = 0, a4 = 0, a5 = 0, a6 = 0, a7 = 0;
#pragma omp simd reduction(+ : a0, a1, a2, a3, a4, a5, a6, a7)
    for (SuiteSparse_long i = j0 + B; i < nsrow; ++i) {
      const double vi = v[i];
      a0 += static_cast<double>(c[0][i]) * vi;
      a1 += static_cast<double>(c[1][i]) * vi;
      a2 += static_cast<double>(c[2][i]) * vi;
      a3 += static_cast<double>(c[3][i]) * vi;
      a4 += static_cast<double>(c[4][i]) * vi;
      a5 += static_cast<double>(c[5][i]) * vi;
      a6 += static_cast<double>(c[6][i]) * vi;
      a7 += static_cast<double>(c[7][i]) * vi;
    }
    acc[0] = a0, acc[1] = a1, acc[2] = a2, acc[3] = a3, acc[4] = a4, acc[5] = a5, acc[6] = a6, acc[7] = a7;
  } else {
    for (int k = 0; k < B; ++k) {
      double a = 0;
      const float* ck = c[k];
#pragma omp simd reduction(+ : a)
      for (SuiteSparse_long i = j0 + B; i < nsrow; ++i) a += static_cast<double>(ck[i]) * v[i];
      acc[k] = a;
    }
  }
  for (int k = B; k-- > 0;) {
    double a = v[j0 + k] - acc[k];
    for (int q = k + 1; q < B; ++q) a -= static_cast<double>(c[k][j0 + q]) * v[j0 + q];
    v[j0 + k] = a / static_cast<double>(c[k][j0 + k]);
  }
}

constexpr int kBlock = 8;

}  // namespace

void SingleFactor::solve(const double* b, double* z) {
  const std::size_t n = n_;
  const SuiteSparse_long* perm = perm_.data();
  const SuiteSparse_long* s = s_.data();
  const float* x = x_.data();
  double* w = w_.data();
  double* v = v_.data();
  const std::size_t ns = super_.size() - 1;
  for (std::size_t i = 0; i < n; ++i) w[i] = b[perm[i]];
  // L y = P b, one supernode at a time: v holds its rows; the columns' own
  // rows are solved in v, the rows below collect -L21 y1 and are added into w.
  for (std::size_t k = 0; k < ns; ++k) {
    const SuiteSparse_long k1 = super_[k], nscol = super_[k + 1] - k1;
    const SuiteSparse_long psi = pi_[k], nsrow = pi_[k + 1] - psi;
    const float* lk = x + px_[k];
    for (SuiteSparse_long i = 0; i < nscol; ++i) v[i] = w[k1 + i];
    for (SuiteSparse_long i = nscol; i < nsrow; ++i) v[i] = 0.0;
    SuiteSparse_long j = 0;
    for (; j + kBlock <= nscol; j += kBlock) forward_block<kBlock>(lk, nsrow, j, v);
    for (; j < nscol; ++j) forward_block<1>(lk, nsrow, j, v);
    for (SuiteSparse_long i = 0; i < nscol; ++i) w[k1 + i] = v[i];
    for (SuiteSparse_long i = nscol; i < nsrow; ++i) w[s[psi + i]] += v[i];
  }
  // L^T u = y, supernodes in reverse, column blocks in reverse: each column's
  // entry from a dot product of its stored column with the rows already solved.
  for (std::size_t kk = ns; kk-- > 0;) {
    const SuiteSparse_long k1 = super_[kk], nscol = super_[kk + 1] - k1;
    const SuiteSparse_long psi = pi_[kk], nsrow = pi_[kk + 1] - psi;
    const float* lk = x + px_[kk];
    for (SuiteSparse_long i = 0; i < nscol; ++i) v[i] = w[k1 + i];
    for (SuiteSparse_long i = nscol; i < nsrow; ++i) v[i] = w[s[psi + i]];
    SuiteSparse_long j = nscol;
    for (; j > 0 && j % kBlock != 0; --j) backward_block<1>(lk, nsrow, j - 1, v);
    for (; j > 0; j -= kBlock) backward_block<kBlock>(lk, nsrow, j - kBlock, v);
    for (SuiteSparse_long i = 0; i < nscol; ++i) w[k1 + i] = v[i];
  }
  for (std::size_t i = 0; i < n; ++i) z[perm[i]] = w[i];
}

}  // namespace bfemp
