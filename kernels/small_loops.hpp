#pragma once
// Loops too short to pay for a parallel launch.
//
// A parallel_for on the OpenMP backend forks and joins its threads: about
// 3.5 µs per launch at 2 threads and 1.5 µs at 1 thread on the development VM
// (an empty loop; Kokkos::Serial: 0.03 µs); the explicit step of B1 at the
// paper's size launched ~75 per step, which made 2 threads slower than 1. A loop over grid slots or
// contact nodes costs a few ns per iteration, so below kSerialBelow
// iterations (a caller's serial_below for costlier bodies) it runs on the calling thread (Kokkos::Serial, the same
// HostSpace memory) and above it on ExecSpace. The loop body is the same
// either way; element-wise loops and integer reductions give identical
// results, and a floating-point reduction over fewer than the threshold in use
// is summed in index order.
//
// Preconditions, asserted: MemSpace is host memory (Kokkos::Serial runs on
// the host) and ExecSpace is a host space that finishes its kernels before
// parallel_for returns (OpenMP, Serial), so a serial branch may read what the
// previous parallel kernel wrote; the serial branches fence anyway.
#include <Kokkos_Core.hpp>
#include <algorithm>
#include <stdexcept>
#include <type_traits>

#include "core/types.hpp"

namespace bfemp {

inline constexpr long kSerialBelow = 8192;
// For loop bodies of ~50-100 ns (a spatial-hash query): at 2 threads a launch
// (3.5 us) pays for itself once n cost / 2 exceeds it, from about
// 7 us / cost iterations. Callers with other costs pass their own
// serial_below (e.g. kSerialBelow / 16 for a 20-60 ns body).
inline constexpr long kSerialBelowHeavy = 128;

static_assert(Kokkos::SpaceAccessibility<Kokkos::Serial, MemSpace>::accessible,
              "small_for runs short loops on Kokkos::Serial: MemSpace must be host memory");
static_assert(std::is_same_v<typename ExecSpace::memory_space, Kokkos::HostSpace>,
              "small_loops.hpp switches between ExecSpace and Kokkos::Serial: ExecSpace must be a host space");

template <class F>
void small_for(const char* name, long n, const F& f, long serial_below = kSerialBelow) {
  if (n < serial_below) {
    ExecSpace().fence();
    Kokkos::parallel_for(name, Kokkos::RangePolicy<Kokkos::Serial>(0, n), f);
  } else {
    Kokkos::parallel_for(name, Kokkos::RangePolicy<ExecSpace>(0, n), f);
  }
}

template <class F, class R>
void small_reduce(const char* name, long n, const F& f, R&& result, long serial_below = kSerialBelow) {
  if (n < serial_below) {
    ExecSpace().fence();
    Kokkos::parallel_reduce(name, Kokkos::RangePolicy<Kokkos::Serial>(0, n), f, result);
  } else {
    Kokkos::parallel_reduce(name, Kokkos::RangePolicy<ExecSpace>(0, n), f, result);
  }
}

template <class F, class T>
void small_scan(const char* name, long n, const F& f, T& total, long serial_below = kSerialBelow) {
  if (n < serial_below) {
    ExecSpace().fence();
    Kokkos::parallel_scan(name, Kokkos::RangePolicy<Kokkos::Serial>(0, n), f, total);
  } else {
    Kokkos::parallel_scan(name, Kokkos::RangePolicy<ExecSpace>(0, n), f, total);
  }
}

// v(i) = value for every i: std::fill on the calling thread when short,
// Kokkos::deep_copy (a parallel fill) otherwise.
template <class View>
void small_fill(const View& v, typename View::non_const_value_type value) {
  if (!v.span_is_contiguous()) throw std::logic_error("small_fill: the View is not contiguous");
  if (static_cast<long>(v.size()) < kSerialBelow) {
    ExecSpace().fence();
    std::fill_n(v.data(), v.size(), value);
  } else {
    Kokkos::deep_copy(v, value);
  }
}

// dst = src (same value type, rank, layout and extents; contiguous; not
// overlapping): std::copy when short, Kokkos::deep_copy otherwise.
template <class Dst, class Src>
void small_copy(const Dst& dst, const Src& src) {
  static_assert(std::is_same_v<typename Dst::non_const_value_type, typename Src::non_const_value_type>);
  static_assert(Dst::rank == Src::rank && std::is_same_v<typename Dst::array_layout, typename Src::array_layout>,
                "small_copy: Views of different ranks or layouts");
  for (unsigned r = 0; r < Dst::rank; ++r)
    if (dst.extent(r) != src.extent(r)) throw std::logic_error("small_copy: Views of different extents");
  if (!dst.span_is_contiguous() || !src.span_is_contiguous())
    throw std::logic_error("small_copy: Views not contiguous");
  if (dst.size() > 0 && dst.data() < src.data() + src.size() && src.data() < dst.data() + dst.size() &&
      dst.data() != src.data())
    throw std::logic_error("small_copy: overlapping Views");
  if (static_cast<long>(dst.size()) < kSerialBelow) {
    ExecSpace().fence();
    std::copy_n(src.data(), src.size(), dst.data());
  } else {
    Kokkos::deep_copy(dst, src);
  }
}

}  // namespace bfemp
