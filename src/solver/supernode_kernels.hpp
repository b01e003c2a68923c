#pragma once
// Dense kernels of the triangular solves with one supernode of a float copy
// of a CHOLMOD factor (SingleFactor), in double arithmetic.
//
// Layout: the supernode's entries are a column-major block with leading
// dimension ld (its number of rows); column j's entry in the supernode's row
// i is lk[j * ld + i]. Its first nscol rows are its own columns (the
// diagonal block, lower triangle used), the rows below go to other columns.
// v holds the supernode's rows of the vector being solved.
//
// The forward solve (L y = b) of columns j0 .. j0+B-1 is tri_forward (the
// B x B triangle at rows j0..) then update_rows over every row below the
// triangle; the backward solve (L^T u = y) is dot_rows over the rows below
// (already final), then tri_backward. Splitting the rows below into ranges
// lets several threads share one supernode; with one range [j0+B, nsrow) the
// results are those of the single-thread solve, bit for bit.
#include <cholmod.h>

namespace bfemp::supernode {

using Long = SuiteSparse_long;
constexpr int kBlock = 8;

// v[j0+k] <- y_k = (v[j0+k] - sum_{q<k} L(j0+k, j0+q) y_q) / L(j0+k, j0+k).
template <int B>
inline void tri_forward(const float* lk, Long ld, Long j0, double* v) {
  for (int k = 0; k < B; ++k) {
    double a = v[j0 + k];
    for (int q = 0; q < k; ++q) a -= static_cast<double>(lk[(j0 + q) * ld + j0 + k]) * v[j0 + q];
    v[j0 + k] = a / static_cast<double>(lk[(j0 + k) * ld + j0 + k]);
  }
}

// v[i] -= sum_k L(i, j0+k) v[j0+k] for i in [ib, ie) (v[j0..j0+B) solved).
template <int B>
inline void update_rows(const float* lk, Long ld, Long j0, double* v, Long ib, Long ie) {
  const float* c[B];
  double y[B];
  for (int k = 0; k < B; ++k) c[k] = lk + (j0 + k) * ld, y[k] = v[j0 + k];
#pragma omp simd
  for (Long i = ib; i < ie; ++i) {
    double a = 0.0;
    for (int k = 0; k < B; ++k) a += static_cast<double>(c[k][i]) * y[k];
    v[i] -= a;
  }
}

// acc[k] += sum_{i in [ib, ie)} L(i, j0+k) v[i].
template <int B>
inline void dot_rows(const float* lk, Long ld, Long j0, const double* v, Long ib, Long ie, double* acc) {
  const float* c[B];
  for (int k = 0; k < B; ++k) c[k] = lk + (j0 + k) * ld;
  if constexpr (B == 8) {
    double a0 = 0, a1 = 0, a2 = 0, a3 = 0, a4 = 0, a5 = 0, a6 = 0, a7 = 0;
#pragma omp simd reduction(+ : a0, a1, a2, a3, a4, a5, a6, a7)
    for (Long i = ib; i < ie; ++i) {
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
    acc[0] += a0, acc[1] += a1, acc[2] += a2, acc[3] += a3, acc[4] += a4, acc[5] += a5, acc[6] += a6, acc[7] += a7;
  } else {
    for (int k = 0; k < B; ++k) {
      double a = 0;
      const float* ck = c[k];
#pragma omp simd reduction(+ : a)
      for (Long i = ib; i < ie; ++i) a += static_cast<double>(ck[i]) * v[i];
      acc[k] += a;
    }
  }
}

// v[j0+k] <- (v[j0+k] - acc[k] - sum_{k<q<B} L(j0+q, j0+k) v[j0+q]) / L(j0+k, j0+k),
// last column first; acc holds the dot products with the rows below the block.
template <int B>
inline void tri_backward(const float* lk, Long ld, Long j0, double* v, const double* acc) {
  for (int k = B; k-- > 0;) {
    const float* ck = lk + (j0 + k) * ld;
    double a = v[j0 + k] - acc[k];
    for (int q = k + 1; q < B; ++q) a -= static_cast<double>(ck[j0 + q]) * v[j0 + q];
    v[j0 + k] = a / static_cast<double>(ck[j0 + k]);
  }
}

// The whole forward solve of columns [cb, ce) of a supernode with nsrow rows
// on one thread, rows below each block up to `rows`: blocks of kBlock, then
// single columns (ce - cb need not be a multiple of kBlock).
inline void forward_columns(const float* lk, Long ld, Long cb, Long ce, double* v, Long rows) {
  Long j = cb;
  for (; j + kBlock <= ce; j += kBlock) {
    tri_forward<kBlock>(lk, ld, j, v);
    update_rows<kBlock>(lk, ld, j, v, j + kBlock, rows);
  }
  for (; j < ce; ++j) {
    tri_forward<1>(lk, ld, j, v);
    update_rows<1>(lk, ld, j, v, j + 1, rows);
  }
}

// The backward solve of columns [cb, ce) on one thread, rows up to `rows`
// (the rows beyond it already folded into acc[j - cb], or none when acc is
// null), single columns at the end first so the blocks align with cb.
inline void backward_columns(const float* lk, Long ld, Long cb, Long ce, double* v, Long rows, const double* acc) {
  Long j = ce;
  for (; j > cb && (j - cb) % kBlock != 0; --j) {
    double a[1] = {acc ? acc[j - 1 - cb] : 0.0};
    dot_rows<1>(lk, ld, j - 1, v, j, rows, a);
    tri_backward<1>(lk, ld, j - 1, v, a);
  }
  for (; j > cb; j -= kBlock) {
    double a[kBlock];
    for (int k = 0; k < kBlock; ++k) a[k] = acc ? acc[j - kBlock + k - cb] : 0.0;
    dot_rows<kBlock>(lk, ld, j - kBlock, v, j, rows, a);
    tri_backward<kBlock>(lk, ld, j - kBlock, v, a);
  }
}

}  // namespace bfemp::supernode
