// Short loops on the calling thread (kernels/small_loops.hpp) and the explicit
// stepper's per-thread grid sums and per-step stencils (kernels/explicit/fields.hpp):
//  - small_fill / small_copy / small_reduce / small_scan give the same results
//    below and above kSerialBelow (where they switch from Kokkos::Serial to
//    ExecSpace): every entry written, integer sums exact, exclusive prefix sums;
//    a caller's serial_below moves the switch;
//  - Scatter: every contribution of a parallel particle loop counted once at
//    any thread count (integer-valued, so the sums are exact whatever the
//    order), the field's old values overwritten, and reset() forgets the
//    previous loop's contributions; with random doubles, bitwise the sums of a
//    duplicated Kokkos::ScatterView contributed into a zeroed field (the
//    stepper's results before the Scatter replaced it);
//  - compute_stencils stores exactly Shape::stencil of each particle (uGIMP
//    and quadratic B-spline, 2D and 3D).
#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include <Kokkos_ScatterView.hpp>

#include "kernels/explicit/fields.hpp"
#include "kernels/explicit/shape_functions.hpp"
#include "kernels/small_loops.hpp"

namespace {

using namespace bfemp;
using namespace bfemp::xmpm;

const std::vector<long> sizes = {0, 1, 17, kSerialBelow - 1, kSerialBelow, 3 * kSerialBelow + 7};

TEST(SmallLoops, FillAndCopyWriteEveryEntryOnBothSidesOfTheThreshold) {
  for (const long n : sizes) {
    Kokkos::View<double*, MemSpace> a("a", n), b("b", n);
    small_fill(a, 2.5);
    auto ha = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), a);
    for (long i = 0; i < n; ++i) ASSERT_EQ(ha(i), 2.5) << "n = " << n << ", i = " << i;
    Kokkos::parallel_for(
        "ramp", Kokkos::RangePolicy<ExecSpace>(0, n), KOKKOS_LAMBDA(const long i) { a(i) = 0.5 * i; });
    small_copy(b, a);
    auto hb = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), b);
    for (long i = 0; i < n; ++i) ASSERT_EQ(hb(i), 0.5 * i) << "n = " << n << ", i = " << i;
    // a 2D View (the Scatter's per-thread copies) is filled whole
    Kokkos::View<double**, Kokkos::LayoutRight, MemSpace> c("c", 3, n);
    small_fill(c, -1.0);
    auto hc = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), c);
    for (int r = 0; r < 3; ++r)
      for (long i = 0; i < n; ++i) ASSERT_EQ(hc(r, i), -1.0);
  }
  Kokkos::View<double*, MemSpace> x("x", 4), y("y", 5);
  EXPECT_THROW(small_copy(x, y), std::logic_error);
  Kokkos::View<double**, Kokkos::LayoutRight, MemSpace> r23("r23", 2, 3), r32("r32", 3, 2);
  EXPECT_THROW(small_copy(r23, r32), std::logic_error);  // same size, other shape
  EXPECT_THROW(small_copy(Kokkos::subview(y, std::make_pair(1, 5)), Kokkos::subview(y, std::make_pair(0, 4))),
               std::logic_error);  // overlapping
}

TEST(SmallLoops, ReduceAndScanAgreeWithClosedFormsOnBothSidesOfTheThreshold) {
  for (const long n : sizes) {
    long sum = 0;
    small_reduce(
        "sum", n, KOKKOS_LAMBDA(const long i, long& acc) { acc += i; }, sum);
    EXPECT_EQ(sum, n * (n - 1) / 2) << "n = " << n;
    int mx = -1;
    small_reduce(
        "max", n, KOKKOS_LAMBDA(const long i, int& acc) { acc = (i % 1000) > acc ? int(i % 1000) : acc; },
        Kokkos::Max<int>(mx));
    EXPECT_EQ(mx, n == 0 ? std::numeric_limits<int>::lowest() : int(std::min<long>(n - 1, 999))) << "n = " << n;
    Kokkos::View<long*, MemSpace> prefix("prefix", n);
    long total = 0;
    small_scan(
        "scan", n,
        KOKKOS_LAMBDA(const long i, long& off, const bool final) {
          if (final) prefix(i) = off;
          off += i;
        },
        total);
    EXPECT_EQ(total, n * (n - 1) / 2) << "n = " << n;
    auto hp = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), prefix);
    for (long i = 0; i < n; ++i) ASSERT_EQ(hp(i), i * (i - 1) / 2) << "n = " << n << ", i = " << i;
  }
}

// The caller's threshold decides where a loop runs: below it on the calling
// thread (no OpenMP region), at or above it on ExecSpace (inside one, when the
// pool has more than one thread); every iteration runs once either way.
TEST(SmallLoops, TheCallersThresholdChoosesTheSpace) {
  const long n = 200;
  for (const long below : {kSerialBelowHeavy, n, n + 1, kSerialBelow}) {
    Kokkos::View<int*, MemSpace> ran("ran", n), inside("inside", n);
    small_for(
        "threshold_for", n,
        KOKKOS_LAMBDA(const long i) {
          ran(i) += 1;
          inside(i) = omp_in_parallel() ? 1 : 0;
        },
        below);
    Kokkos::fence();
    int runs = 0, parallel = 0;
    for (long i = 0; i < n; ++i) runs += ran(i) == 1, parallel += inside(i);
    EXPECT_EQ(runs, n) << "serial_below = " << below;
    if (n < below) {
      EXPECT_EQ(parallel, 0) << "serial_below = " << below;
    } else if (ExecSpace().concurrency() > 1) {
      EXPECT_EQ(parallel, n) << "serial_below = " << below;
    }
    long sum = 0;
    small_reduce(
        "threshold_reduce", n, KOKKOS_LAMBDA(const long i, long& acc) { acc += omp_in_parallel() ? 0 : i; }, sum,
        below);
    if (n < below) {
      EXPECT_EQ(sum, n * (n - 1) / 2) << "serial_below = " << below;
    } else if (ExecSpace().concurrency() > 1) {
      EXPECT_EQ(sum, 0) << "serial_below = " << below;
    }
    long scanned = 0;
    small_scan(
        "threshold_scan", n,
        KOKKOS_LAMBDA(const long i, long& off, const bool final) {
          if (final) inside(i) = omp_in_parallel() ? 1 : 0;
          off += i;
        },
        scanned, below);
    Kokkos::fence();
    parallel = 0;
    for (long i = 0; i < n; ++i) parallel += inside(i);
    EXPECT_EQ(scanned, n * (n - 1) / 2) << "serial_below = " << below;
    if (n < below) {
      EXPECT_EQ(parallel, 0) << "serial_below = " << below;
    } else if (ExecSpace().concurrency() > 1) {
      EXPECT_EQ(parallel, n) << "serial_below = " << below;
    }
  }
}

// Contributions k(q) * (1 + slot % 3) of "particle" q to a few slots each; the
// sums are integers below 2^53, exact in any order.
void scatter_round(const Scatter& s, long nq, long nslots, int seed, std::vector<double>& expect) {
  expect.assign(nslots, 0.0);
  for (long q = 0; q < nq; ++q)
    for (int k = 0; k < 5; ++k) {
      const long slot = (q * 7 + k * 13 + seed) % nslots;
      expect[slot] += double((q + k + seed) % 11) * (1 + slot % 3);
    }
  s.reset();
  Kokkos::parallel_for(
      "contribute", Kokkos::RangePolicy<ExecSpace>(0, nq), KOKKOS_LAMBDA(const long q) {
        auto acc = s.access();
        for (int k = 0; k < 5; ++k) {
          const long slot = (q * 7 + k * 13 + seed) % nslots;
          acc(slot) += double((q + k + seed) % 11) * (1 + slot % 3);
        }
      });
  s.contribute();
}

TEST(ExplicitScatter, EveryContributionCountedOnceAndTheFieldOverwritten) {
  for (const long nslots : {long(40), 3 * kSerialBelow + 5}) {
    const long nq = 5 * nslots + 3;
    Kokkos::View<double*, MemSpace> field("field", nslots);
    small_fill(field, std::numeric_limits<double>::quiet_NaN());  // contribute must not add to old values
    const Scatter s(field);
    std::vector<double> expect;
    for (int seed : {0, 5}) {  // the second round must not see the first's contributions
      scatter_round(s, nq, nslots, seed, expect);
      auto h = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), field);
      for (long i = 0; i < nslots; ++i)
        ASSERT_EQ(h(i), expect[i]) << "slots " << nslots << ", seed " << seed << ", slot " << i;
    }
  }
}

TEST(ExplicitScatter, BitwiseTheSumsOfADuplicatedScatterView) {
  for (const long nslots : {long(64), 3 * kSerialBelow + 5}) {
    const long nq = 4 * nslots + 1;
    Kokkos::View<double*, MemSpace> vals("vals", nq * 3);
    auto hv = Kokkos::create_mirror_view(vals);
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (long i = 0; i < nq * 3; ++i) hv(i) = u(rng) * std::pow(10.0, int(u(rng) * 8));
    Kokkos::deep_copy(vals, hv);
    Kokkos::View<double*, MemSpace> mine("mine", nslots), ref("ref", nslots);
    const Scatter s(mine);
    s.reset();
    Kokkos::parallel_for(
        "mine", Kokkos::RangePolicy<ExecSpace>(0, nq), KOKKOS_LAMBDA(const long q) {
          auto acc = s.access();
          for (int k = 0; k < 3; ++k) acc((q * 5 + k * 17) % nslots) += vals(q * 3 + k);
        });
    s.contribute();
    using SV = Kokkos::Experimental::ScatterView<double*, Kokkos::LayoutRight, ExecSpace,
                                                 Kokkos::Experimental::ScatterSum,
                                                 Kokkos::Experimental::ScatterDuplicated,
                                                 Kokkos::Experimental::ScatterNonAtomic>;
    SV sv(ref);
    sv.reset();
    Kokkos::parallel_for(
        "ref", Kokkos::RangePolicy<ExecSpace>(0, nq), KOKKOS_LAMBDA(const long q) {
          auto acc = sv.access();
          for (int k = 0; k < 3; ++k) acc((q * 5 + k * 17) % nslots) += vals(q * 3 + k);
        });
    Kokkos::deep_copy(ref, 0.0);
    Kokkos::Experimental::contribute(ref, sv);
    auto hm = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mine);
    auto hr = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), ref);
    for (long i = 0; i < nslots; ++i) ASSERT_EQ(hm(i), hr(i)) << "slots " << nslots << ", slot " << i;
  }
}

template <int dim, class Shape>
void check_stencils(double lp) {
  GridSpec<dim> g;
  g.dx = 1.0 / 128;  // powers of two: the first particles lie exactly on grid lines
  for (int d = 0; d < dim; ++d) {
    g.origin[d] = -0.125;
    g.n_cells[d] = 32;
  }
  const long n = 500;
  XParticles<dim> p;
  p.x = decltype(p.x)("x", n);
  p.lp = Kokkos::View<double*, MemSpace>("lp", n);
  p.mass = Kokkos::View<double*, MemSpace>("m", n);
  auto hx = Kokkos::create_mirror_view(p.x);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-0.09, 0.09);
  for (long q = 0; q < n; ++q)
    for (int d = 0; d < dim; ++d) hx(q, d) = q < 8 ? -0.0625 + q / 128.0 : u(rng);  // the first 8 on grid lines
  Kokkos::deep_copy(p.x, hx);
  Kokkos::deep_copy(p.lp, lp);
  StencilView<dim, Shape> sts;
  compute_stencils<dim, Shape>(g, p, sts);
  ASSERT_EQ(sts.extent(0), std::size_t(n));
  auto hs = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sts);
  for (long q = 0; q < n; ++q) {
    Vec<dim> x;
    for (int d = 0; d < dim; ++d) x(d) = hx(q, d);
    const auto ref = Shape::template stencil<dim>(g, x, lp);
    for (int d = 0; d < dim; ++d) {
      ASSERT_EQ(hs(q).base[d], ref.base[d]) << "particle " << q;
      for (int k = 0; k < Shape::per_axis; ++k) {
        ASSERT_EQ(hs(q).w[d][k], ref.w[d][k]) << "particle " << q;
        ASSERT_EQ(hs(q).dw[d][k], ref.dw[d][k]) << "particle " << q;
      }
    }
  }
}

TEST(ExplicitStencils, ComputeStencilsStoresEachParticlesStencil) {
  check_stencils<2, UGimp>(1.0 / 512);
  check_stencils<3, UGimp>(1.0 / 512);
  check_stencils<2, QuadraticBSpline>(1.0 / 512);
  check_stencils<3, QuadraticBSpline>(1.0 / 512);
}

}  // namespace
