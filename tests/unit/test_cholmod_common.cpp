// The CHOLMOD settings and serial scope of solver/cholmod_common.hpp:
//  - inside CholmodSerialScope every OpenMP parallel region runs on one
//    thread, even one that asks for 4 (as Debian's CHOLMOD does); on exit the
//    previous max-active-levels is back and Kokkos kernels use the whole pool
//    again (a kernel that ran on one thread would leave most of its range
//    undone); inside a parallel region the scope changes nothing;
//  - start_cholmod's relaxed amalgamation merges supernodes (fewer than
//    CHOLMOD's defaults give on the same matrix) and the factor still solves
//    the system to round-off.
#include <gtest/gtest.h>
#include <omp.h>

#include <Kokkos_Core.hpp>
#include <cholmod.h>
#include <cmath>
#include <cstdio>
#include <vector>

#include "core/types.hpp"
#include "solver/cholmod_common.hpp"
#include "solver/cholmod_views.hpp"

namespace {

using namespace bfemp;

int threads_in_region(int asked) {
  int n = 0;
#pragma omp parallel num_threads(asked)
  {
#pragma omp single
    n = omp_get_num_threads();
  }
  return n;
}

TEST(CholmodSerialScope, RegionsInsideRunOnOneThreadAndKokkosGetsItsPoolBack) {
  if (threads_in_region(2) < 2) GTEST_SKIP() << "OpenMP gives one thread here (OMP_THREAD_LIMIT?)";
  const int pool = ExecSpace().concurrency();
  const int levels = omp_get_max_active_levels();
  {
    CholmodSerialScope serial;
    EXPECT_EQ(omp_get_max_active_levels(), 0);
    EXPECT_EQ(threads_in_region(4), 1);
    {
      CholmodSerialScope again;  // nested scopes restore in order
      EXPECT_EQ(threads_in_region(2), 1);
    }
    EXPECT_EQ(omp_get_max_active_levels(), 0);
  }
  EXPECT_EQ(omp_get_max_active_levels(), levels);
  if (pool > 1) {
    EXPECT_EQ(threads_in_region(2), 2);
  }
  // Every entry of a Kokkos kernel is done, and by more than one thread when
  // the pool has more.
  const long n = 1 << 20;
  Kokkos::View<int*, MemSpace> who("who", n);
  Kokkos::parallel_for(
      "serial_scope_after", Kokkos::RangePolicy<ExecSpace>(0, n), KOKKOS_LAMBDA(const long i) {
        who(i) = 1 + omp_get_thread_num();
      });
  int lo = 1 << 30, hi = 0;
  Kokkos::parallel_reduce(
      "serial_scope_min", Kokkos::RangePolicy<ExecSpace>(0, n),
      KOKKOS_LAMBDA(const long i, int& acc) { acc = who(i) < acc ? who(i) : acc; }, Kokkos::Min<int>(lo));
  Kokkos::parallel_reduce(
      "serial_scope_max", Kokkos::RangePolicy<ExecSpace>(0, n),
      KOKKOS_LAMBDA(const long i, int& acc) { acc = who(i) > acc ? who(i) : acc; }, Kokkos::Max<int>(hi));
  EXPECT_GE(lo, 1);  // no entry left undone
  EXPECT_EQ(hi, pool);
}

TEST(CholmodSerialScope, InsideAParallelRegionItChangesNothing) {
  if (threads_in_region(2) < 2) GTEST_SKIP() << "OpenMP gives one thread here (OMP_THREAD_LIMIT?)";
  const int levels = omp_get_max_active_levels();
  int seen = -1;
#pragma omp parallel num_threads(2)
  {
#pragma omp master
    {
      CholmodSerialScope serial;
      seen = omp_get_max_active_levels();
    }
  }
  EXPECT_EQ(seen, levels);
  EXPECT_EQ(omp_get_max_active_levels(), levels);
}

// A 2D grid of m x m nodes with 2 DOFs each, every node coupled to the 5 x 5
// nodes around it (the quadratic B-spline pattern of an MPM grid), values of
// an SPD matrix: diagonally dominant, symmetric. Upper triangle by columns
// (rows sorted in each), as symmetric_csc_view wants it.
struct GridMatrix {
  std::vector<SuiteSparse_long> p, i;
  std::vector<double> x;
};

GridMatrix grid_matrix(int m) {
  GridMatrix g;
  const int n = m * m * 2;
  g.p.push_back(0);
  for (int col = 0; col < n; ++col) {
    const int node = col / 2, cx = node % m, cy = node / m;
    for (int row = 0; row <= col; ++row) {
      const int rn = row / 2, rx = rn % m, ry = rn / m;
      if (std::abs(rx - cx) > 2 || std::abs(ry - cy) > 2) continue;
      g.i.push_back(row);
      g.x.push_back(row == col ? 60.0 : -1.0 / (1.0 + std::abs(rx - cx) + std::abs(ry - cy) + (row % 2 != col % 2)));
    }
    g.p.push_back(static_cast<SuiteSparse_long>(g.i.size()));
  }
  return g;
}

struct Factored {
  long nsuper = 0;
  double residual = 0;  // |b - A x|_inf / |b|_inf
};

Factored factor_and_solve(GridMatrix& g, bool bfemp_settings) {
  cholmod_common c;
  if (bfemp_settings) {
    start_cholmod(c);
  } else {
    cholmod_l_start(&c);
    c.print = 0;
    c.final_ll = 1;
  }
  cholmod_sparse A = symmetric_csc_view(g.p, g.i, g.x.data());
  Factored out;
  {
    CholmodSerialScope serial;
    cholmod_factor* L = cholmod_l_analyze(&A, &c);
    if (!L) {
      ADD_FAILURE() << "cholmod_l_analyze failed, status " << c.status;
      cholmod_l_finish(&c);
      return out;
    }
    EXPECT_TRUE(cholmod_l_factorize(&A, L, &c));
    EXPECT_EQ(c.status, CHOLMOD_OK);
    EXPECT_TRUE(L->is_super);
    out.nsuper = static_cast<long>(L->nsuper);
    cholmod_dense* b = cholmod_l_ones(A.nrow, 1, CHOLMOD_REAL, &c);
    for (std::size_t k = 0; k < A.nrow; ++k) static_cast<double*>(b->x)[k] = std::sin(0.37 * k) + 0.1;
    cholmod_dense* x = cholmod_l_solve(CHOLMOD_A, L, b, &c);
    // r = b - A x (A symmetric, upper triangle stored).
    std::vector<double> r(static_cast<double*>(b->x), static_cast<double*>(b->x) + A.nrow);
    const double* xv = static_cast<const double*>(x->x);
    for (std::size_t col = 0; col < A.ncol; ++col)
      for (auto k = g.p[col]; k < g.p[col + 1]; ++k) {
        const auto row = static_cast<std::size_t>(g.i[k]);
        r[row] -= g.x[k] * xv[col];
        if (row != col) r[col] -= g.x[k] * xv[row];
      }
    double rn = 0, bn = 0;
    for (std::size_t k = 0; k < A.nrow; ++k) {
      rn = std::fmax(rn, std::fabs(r[k]));
      bn = std::fmax(bn, std::fabs(static_cast<double*>(b->x)[k]));
    }
    out.residual = rn / bn;
    cholmod_l_free_dense(&x, &c);
    cholmod_l_free_dense(&b, &c);
    cholmod_l_free_factor(&L, &c);
  }
  cholmod_l_finish(&c);
  return out;
}

TEST(CholmodSettings, RelaxedAmalgamationMergesSupernodesAndStillSolves) {
  GridMatrix g = grid_matrix(40);  // 3200 DOFs
  const Factored plain = factor_and_solve(g, false);
  const Factored ours = factor_and_solve(g, true);
  EXPECT_LT(plain.residual, 1e-13);
  EXPECT_LT(ours.residual, 1e-13);
  EXPECT_LT(ours.nsuper, plain.nsuper);
  std::printf("supernodes: CHOLMOD's defaults %ld, bfemp's %ld\n", plain.nsuper, ours.nsuper);
}

}  // namespace
