#pragma once
// Contact broad phase (paper §4): a Kokkos spatial hash of axis-aligned boxes
// (FEM boundary facets, inflated by dhat and swept along the search direction)
// queried by boxes (MPM particles, likewise swept). No O(queries x boxes) loop
// except against the short list of oversize boxes (see below).
//
// API (namespace bfemp, dim = 2 or 3):
//   template <int dim> struct Boxes;       // lo(i, c), hi(i, c); size(); resize(n) grows, never shrinks
//   template <int dim> class SpatialHash {
//     void build(const Boxes<dim>& boxes);  // copies and hashes the boxes
//     LO query(const Boxes<dim>& queries, Kokkos::View<LO* [2], MemSpace>& pairs);
//       // pairs(k, 0) = query, pairs(k, 1) = box for every overlapping (closed, touching counts)
//       // pair, each once; sorted by query then box (deterministic for any thread count);
//       // returns the count; `pairs` grows when too small (never shrinks).
//     LO query(queries, pairs, keep);   // only the pairs with keep(q, j) true (a device predicate,
//                                       // e.g. no contact of an FEM body with itself)
//     const SpatialHashStats& stats() const;  // cell size, entries, oversize count, buckets
//     std::size_t storage_capacity() const;    // allocated entries (for reuse checks)
//   };
//   point_boxes<dim>(x, dx, pad, out)            // x node-interleaved (node*dim + c), one box per node
//   point_boxes<dim>(x, dx, t, pad, out)         // swept to x + t*dx; dx empty = static
//   simplex_boxes<dim, k>(nodes, x, dx, pad, out)   // one box per row of nodes (k vertices)
//   simplex_boxes<dim, k>(nodes, x, dx, t, pad, out)
//   Box = [min(x, x + t dx) - pad, max(x, x + t dx) + pad] over the item's nodes. For contact,
//   pad the facets by dhat and the particles by 0 (or both by dhat/2).
//   simplex_boxes needs explicit <dim, k> when `nodes` is a non-const View.
//
// Cell size h: the scene extent L times a power of two, at or above the
// median (over non-degenerate boxes) of the largest box side, from a 64-bin
// log2 histogram, so a median box spans at most 2 cells per axis; h >= L/2^20
// (cell keys fit in 64 bits). A box covering more than 4^dim cells is
// "oversize": kept in a separate list tested against every query. h doubles
// until at most 64 boxes are oversize and the (box, cell) entries are at most
// 2^(dim+2) per box, so memory is O(boxes) for any input (h >= L ends it: every
// box then covers <= 2^dim cells). Cells are hashed (no dense grid) into
// next_pow2(entries) buckets stored CSR; each entry keeps its cell key, so
// hash collisions cost time, never correctness. A pair is reported only from
// the cell holding the low corner of the two boxes' intersection, hence once.
// A query covering more cells than there are regular boxes tests them all
// directly instead (bounded by the boxes, never worse than walking cells).
// All storage persists across build/query calls and grows by 25% headroom.
#include <Kokkos_Core.hpp>
#include <climits>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "core/types.hpp"
#include "kernels/small_loops.hpp"

namespace bfemp {

template <int dim>
struct Boxes {
  Kokkos::View<double* [dim], MemSpace> lo, hi;
  LO n = 0;  // items in use (capacity = lo.extent(0))
  Boxes() = default;
  Boxes(Kokkos::View<double* [dim], MemSpace> l, Kokkos::View<double* [dim], MemSpace> h)
      : lo(l), hi(h), n(static_cast<LO>(l.extent(0))) {}
  LO size() const { return n; }
  // Sets the size; reallocates (contents lost) only when capacity is short.
  void resize(LO count) {
    if (static_cast<LO>(lo.extent(0)) < count) {
      const LO cap = count + count / 4;
      lo = Kokkos::View<double* [dim], MemSpace>(Kokkos::view_alloc(Kokkos::WithoutInitializing, "bfemp_box_lo"), cap);
      hi = Kokkos::View<double* [dim], MemSpace>(Kokkos::view_alloc(Kokkos::WithoutInitializing, "bfemp_box_hi"), cap);
    }
    n = count;
  }
};

struct SpatialHashStats {
  double cell_size = 0;
  std::int64_t entries = 0;  // (box, cell) entries of the regular boxes
  LO oversize = 0;           // boxes in the every-query list
  LO buckets = 0;
};

namespace broad_phase_detail {

// Grows a rank-1 view to at least n entries (25% headroom); contents lost.
template <class V>
void grow(V& v, std::size_t n, const char* label) {
  if (v.extent(0) < n) v = V(Kokkos::view_alloc(Kokkos::WithoutInitializing, std::string(label)), n + n / 4);
}

template <int dim, class A, class B>
KOKKOS_INLINE_FUNCTION bool overlap(const double* qlo, const double* qhi, const A& lo, const B& hi, LO j) {
  for (int d = 0; d < dim; ++d)
    if (qhi[d] < lo(j, d) || hi(j, d) < qlo[d]) return false;
  return true;
}

KOKKOS_INLINE_FUNCTION double dmin(double a, double b) { return b < a ? b : a; }
KOKKOS_INLINE_FUNCTION double dmax(double a, double b) { return a < b ? b : a; }

KOKKOS_INLINE_FUNCTION std::uint64_t mix(std::uint64_t z) {  // splitmix64 finaliser
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

// Uniform grid over the boxes' bounding box; cell(x, d) is monotone in x and
// clamped to [0, nc[d]), so every box coordinate maps inside.
template <int dim>
struct HashGrid {
  double origin[dim] = {}, inv_h = 1;
  LO nc[dim] = {};
  std::uint64_t mask = 0;
  KOKKOS_INLINE_FUNCTION LO cell(double x, int d) const {
    const double t = (x - origin[d]) * inv_h;
    if (!(t >= 0)) return 0;
    if (t >= nc[d]) return nc[d] - 1;
    return static_cast<LO>(t);
  }
  KOKKOS_INLINE_FUNCTION std::int64_t key(const LO* c) const {
    std::int64_t k = c[0];
    for (int d = 1; d < dim; ++d) k = k * nc[d] + c[d];
    return k;
  }
  KOKKOS_INLINE_FUNCTION LO bucket(std::int64_t key) const {
    return static_cast<LO>(mix(static_cast<std::uint64_t>(key)) & mask);
  }
  template <class V>
  KOKKOS_INLINE_FUNCTION void range(const V& lo, const V& hi, LO i, LO* c0, LO* c1) const {
    for (int d = 0; d < dim; ++d) {
      c0[d] = cell(lo(i, d), d);
      c1[d] = cell(hi(i, d), d);
    }
  }
};

// Calls f(c) for every cell c in [c0, c1] (inclusive, odometer order).
template <int dim, class F>
KOKKOS_INLINE_FUNCTION void for_each_cell(const LO* c0, const LO* c1, F& f) {
  LO c[dim];
  for (int d = 0; d < dim; ++d) c[d] = c0[d];
  while (true) {
    f(c);
    int d = dim - 1;
    while (d >= 0 && c[d] == c1[d]) c[d] = c0[d], --d;
    if (d < 0) return;
    ++c[d];
  }
}

template <int dim>
KOKKOS_INLINE_FUNCTION std::int64_t cell_count(const LO* c0, const LO* c1) {
  std::int64_t n = 1;
  for (int d = 0; d < dim; ++d) n *= c1[d] - c0[d] + 1;
  return n;
}

// Sorts column 1 of pairs rows [b, e) ascending (insertion sort for short
// lists, heapsort otherwise).
template <class P>
KOKKOS_INLINE_FUNCTION void sort_segment(const P& pairs, std::int64_t b, std::int64_t e) {
  const std::int64_t n = e - b;
  if (n <= 32) {
    for (std::int64_t i = b + 1; i < e; ++i) {
      const LO v = pairs(i, 1);
      std::int64_t k = i;
      for (; k > b && pairs(k - 1, 1) > v; --k) pairs(k, 1) = pairs(k - 1, 1);
      pairs(k, 1) = v;
    }
    return;
  }
  auto sift = [&](std::int64_t root, std::int64_t len) {  // max-heap on offsets from b
    while (2 * root + 1 < len) {
      std::int64_t ch = 2 * root + 1;
      if (ch + 1 < len && pairs(b + ch, 1) < pairs(b + ch + 1, 1)) ++ch;
      if (!(pairs(b + root, 1) < pairs(b + ch, 1))) return;
      const LO t = pairs(b + root, 1);
      pairs(b + root, 1) = pairs(b + ch, 1);
      pairs(b + ch, 1) = t;
      root = ch;
    }
  };
  for (std::int64_t r = n / 2 - 1; r >= 0; --r) sift(r, n);
  for (std::int64_t len = n - 1; len > 0; --len) {
    const LO t = pairs(b, 1);
    pairs(b, 1) = pairs(b + len, 1);
    pairs(b + len, 1) = t;
    sift(0, len);
  }
}

// Everything a query kernel reads, captured by value.
template <int dim>
struct Traversal {
  HashGrid<dim> grid;
  Kokkos::View<double* [dim], MemSpace> lo, hi;
  Kokkos::View<char*, MemSpace> is_oversize;
  Kokkos::View<LO*, MemSpace> oversize, bucket_start, entry_box;
  Kokkos::View<std::int64_t*, MemSpace> entry_key;
  LO n = 0, n_oversize = 0;
  double scene_lo[dim] = {}, scene_hi[dim] = {};

  // Calls emit(j) once for every box j overlapping [qlo, qhi] (unordered).
  template <class Emit>
  KOKKOS_INLINE_FUNCTION void visit(const double* qlo, const double* qhi, Emit& emit) const {
    for (LO o = 0; o < n_oversize; ++o)
      if (overlap<dim>(qlo, qhi, lo, hi, oversize(o))) emit(oversize(o));
    if (n - n_oversize == 0) return;
    for (int d = 0; d < dim; ++d)
      if (qhi[d] < scene_lo[d] || qlo[d] > scene_hi[d]) return;
    LO c0[dim], c1[dim];
    for (int d = 0; d < dim; ++d) {
      c0[d] = grid.cell(qlo[d], d);
      c1[d] = grid.cell(qhi[d], d);
    }
    if (cell_count<dim>(c0, c1) > n - n_oversize) {  // cheaper to test every regular box
      for (LO j = 0; j < n; ++j)
        if (!is_oversize(j) && overlap<dim>(qlo, qhi, lo, hi, j)) emit(j);
      return;
    }
    auto in_cell = [&](const LO* c) {
      const std::int64_t key = grid.key(c);
      const LO b = grid.bucket(key);
      for (LO e = bucket_start(b); e < bucket_start(b + 1); ++e) {
        if (entry_key(e) != key) continue;  // another cell in the same bucket
        const LO j = entry_box(e);
        if (!overlap<dim>(qlo, qhi, lo, hi, j)) continue;
        bool home = true;  // the intersection's low corner lies in this cell
        for (int d = 0; d < dim; ++d) home = home && grid.cell(dmax(qlo[d], lo(j, d)), d) == c[d];
        if (home) emit(j);
      }
    };
    for_each_cell<dim>(c0, c1, in_cell);
  }
};

}  // namespace broad_phase_detail

template <int dim>
class SpatialHash {
 public:
  static constexpr std::int64_t kCellCap = std::int64_t(1) << (2 * dim);  // cells per regular box
  static constexpr std::int64_t kEntriesPerBox = std::int64_t(1) << (dim + 2);
  static constexpr LO kMaxOversize = 64;

  void build(const Boxes<dim>& in) {
    using namespace broad_phase_detail;
    const LO n = in.size();
    boxes_.resize(n);
    t_.n = n;
    t_.n_oversize = 0;
    stats_ = SpatialHashStats();
    if (n == 0) return;
    copy_boxes(in);
    scene_extent();
    double L = 0;
    for (int d = 0; d < dim; ++d) L = std::fmax(L, t_.scene_hi[d] - t_.scene_lo[d]);
    double h = L > 0 ? std::fmax(median_side_cell(L), std::ldexp(L, -20)) : 1.0;
    std::int64_t entries = 0;
    LO over = 0;
    for (int it = 0; it < 80; ++it, h *= 2) {  // terminates once h >= L (see header)
      set_grid(h);
      count_entries(entries, over);
      if (over <= kMaxOversize && entries <= kEntriesPerBox * n) break;
    }
    if (entries > (LO(1) << 30)) throw std::overflow_error("SpatialHash: more than 2^30 (box, cell) entries");
    LO buckets = 1;
    while (buckets < entries) buckets *= 2;
    t_.grid.mask = static_cast<std::uint64_t>(buckets - 1);
    stats_ = {h, entries, over, buckets};
    mark_oversize(over);
    fill_table(buckets, static_cast<LO>(entries));
  }

  LO query(const Boxes<dim>& queries, Kokkos::View<LO* [2], MemSpace>& pairs) {
    return query(queries, pairs, KeepAll{});
  }
  struct KeepAll {
    KOKKOS_INLINE_FUNCTION bool operator()(LO, LO) const { return true; }
  };
  template <class Keep>
  LO query(const Boxes<dim>& queries, Kokkos::View<LO* [2], MemSpace>& pairs, const Keep& keep) {
    using namespace broad_phase_detail;
    const LO m = queries.size();
    if (m == 0 || t_.n == 0) return 0;
    grow(offsets_, m + 1, "bfemp_bp_offsets");
    const auto tr = t_;
    const auto qlo = queries.lo, qhi = queries.hi;
    const auto off = offsets_;
    small_for(
        "bp_query_count", m, KOKKOS_LAMBDA(const LO q) {
          double lo[dim], hi[dim];
          for (int d = 0; d < dim; ++d) lo[d] = qlo(q, d), hi[d] = qhi(q, d);
          std::int64_t c = 0;
          auto emit = [&](LO j) { c += keep(q, j) ? 1 : 0; };
          tr.visit(lo, hi, emit);
          off(q) = c;
        },
        kSerialBelowHeavy);
    std::int64_t total = 0;
    small_scan(
        "bp_query_scan", m + 1,
        KOKKOS_LAMBDA(const LO q, std::int64_t& acc, const bool final) {
          const std::int64_t c = q < m ? off(q) : 0;
          if (final) off(q) = acc;
          acc += c;
        },
        total);
    if (total > INT_MAX) throw std::overflow_error("SpatialHash::query: more than INT_MAX pairs");
    if (static_cast<std::int64_t>(pairs.extent(0)) < total)
      pairs = Kokkos::View<LO* [2], MemSpace>(Kokkos::view_alloc(Kokkos::WithoutInitializing, "bfemp_contact_pairs"),
                                              total + total / 4);
    const auto pr = pairs;
    small_for(
        "bp_query_fill", m, KOKKOS_LAMBDA(const LO q) {
          double lo[dim], hi[dim];
          for (int d = 0; d < dim; ++d) lo[d] = qlo(q, d), hi[d] = qhi(q, d);
          std::int64_t k = off(q);
          auto emit = [&](LO j) {
            if (!keep(q, j)) return;
            pr(k, 0) = q;
            pr(k, 1) = j;
            ++k;
          };
          tr.visit(lo, hi, emit);
          sort_segment(pr, off(q), k);
        },
        kSerialBelowHeavy);
    return static_cast<LO>(total);
  }

  const SpatialHashStats& stats() const { return stats_; }
  // Total allocated entries of the internal views (unchanged = nothing reallocated).
  std::size_t storage_capacity() const {
    return boxes_.lo.extent(0) + t_.is_oversize.extent(0) + t_.oversize.extent(0) + t_.bucket_start.extent(0) +
           cursor_.extent(0) + t_.entry_key.extent(0) + t_.entry_box.extent(0) + offsets_.extent(0) +
           hist_.extent(0);
  }

 private:
  void copy_boxes(const Boxes<dim>& in) {
    const auto ilo = in.lo, ihi = in.hi, lo = boxes_.lo, hi = boxes_.hi;
    small_for(
        "bp_copy_boxes", in.size(), KOKKOS_LAMBDA(const LO i) {
          for (int d = 0; d < dim; ++d) lo(i, d) = ilo(i, d), hi(i, d) = ihi(i, d);
        });
    t_.lo = lo;
    t_.hi = hi;
  }

  void scene_extent() {
    const auto lo = boxes_.lo, hi = boxes_.hi;
    for (int d = 0; d < dim; ++d) {
      double a = 0, b = 0;
      small_reduce(
          "bp_scene_lo", boxes_.size(),
          KOKKOS_LAMBDA(const LO i, double& acc) { acc = broad_phase_detail::dmin(acc, lo(i, d)); }, Kokkos::Min<double>(a));
      small_reduce(
          "bp_scene_hi", boxes_.size(),
          KOKKOS_LAMBDA(const LO i, double& acc) { acc = broad_phase_detail::dmax(acc, hi(i, d)); }, Kokkos::Max<double>(b));
      t_.scene_lo[d] = a;
      t_.scene_hi[d] = b;
    }
  }

  // Upper edge of the log2 histogram bin (relative to L) holding the median
  // largest side of the non-degenerate boxes; L / n^(1/dim) if all are points.
  double median_side_cell(double L) {
    broad_phase_detail::grow(hist_, 64, "bfemp_bp_hist");
    const auto hist = Kokkos::subview(hist_, Kokkos::make_pair(0, 64));
    small_fill(hist, 0);
    const auto lo = boxes_.lo, hi = boxes_.hi;
    small_for(
        "bp_side_histogram", boxes_.size(), KOKKOS_LAMBDA(const LO i) {
          double s = 0;
          for (int d = 0; d < dim; ++d) s = broad_phase_detail::dmax(s, hi(i, d) - lo(i, d));
          int b = 63;  // degenerate
          if (s > 0) {  // bin b: L 2^-(b+1) <= s <= L 2^-b (b = 62 collects anything smaller)
            double e = 1;
            for (b = 0; b < 62 && s < 0.5 * e * L; ++b) e *= 0.5;
          }
          Kokkos::atomic_increment(&hist(b));
        });
    const auto h = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), hist);
    const LO solid = boxes_.size() - h(63);
    if (solid == 0) return L / std::pow(static_cast<double>(boxes_.size()), 1.0 / dim);
    LO acc = 0;
    for (int b = 62; b >= 0; --b)
      if ((acc += h(b)) >= (solid + 1) / 2) return std::ldexp(L, -b);
    return L;
  }

  void set_grid(double h) {
    auto& g = t_.grid;
    g.inv_h = 1.0 / h;
    for (int d = 0; d < dim; ++d) {
      g.origin[d] = t_.scene_lo[d];
      g.nc[d] = 1 << 30;  // unclamped while measuring the extent
      g.nc[d] = g.cell(t_.scene_hi[d], d) + 1;
    }
  }

  void count_entries(std::int64_t& entries, LO& over) const {
    const auto g = t_.grid;
    const auto lo = boxes_.lo, hi = boxes_.hi;
    constexpr std::int64_t cap = kCellCap;
    entries = 0;
    over = 0;
    small_reduce(
        "bp_count_entries", boxes_.size(),
        KOKKOS_LAMBDA(const LO i, std::int64_t& acc) {
          LO c0[dim], c1[dim];
          g.range(lo, hi, i, c0, c1);
          const std::int64_t c = broad_phase_detail::cell_count<dim>(c0, c1);
          if (c <= cap) acc += c;
        },
        entries);
    small_reduce(
        "bp_count_oversize", boxes_.size(),
        KOKKOS_LAMBDA(const LO i, LO& acc) {
          LO c0[dim], c1[dim];
          g.range(lo, hi, i, c0, c1);
          if (broad_phase_detail::cell_count<dim>(c0, c1) > cap) ++acc;
        },
        over);
  }

  // Flags oversize boxes and lists them in ascending order.
  void mark_oversize(LO over) {
    using namespace broad_phase_detail;
    const LO n = boxes_.size();
    grow(t_.is_oversize, n, "bfemp_bp_is_oversize");
    grow(t_.oversize, over, "bfemp_bp_oversize");
    const auto g = t_.grid;
    const auto lo = boxes_.lo, hi = boxes_.hi;
    const auto flag = t_.is_oversize;
    const auto list = t_.oversize;
    constexpr std::int64_t cap = kCellCap;
    LO count = 0;
    small_scan(
        "bp_oversize_list", n,
        KOKKOS_LAMBDA(const LO i, LO& acc, const bool final) {
          LO c0[dim], c1[dim];
          g.range(lo, hi, i, c0, c1);
          const bool big = cell_count<dim>(c0, c1) > cap;
          if (final) {
            flag(i) = big;
            if (big) list(acc) = i;
          }
          acc += big;
        },
        count);
    t_.n_oversize = count;
  }

  // CSR hash table: count per bucket, exclusive scan, scatter through cursors.
  void fill_table(LO buckets, LO entries) {
    using namespace broad_phase_detail;
    grow(t_.bucket_start, buckets + 1, "bfemp_bp_bucket_start");
    grow(cursor_, buckets, "bfemp_bp_cursor");
    grow(t_.entry_key, entries, "bfemp_bp_entry_key");
    grow(t_.entry_box, entries, "bfemp_bp_entry_box");
    const auto start = t_.bucket_start;
    small_fill(Kokkos::subview(start, Kokkos::make_pair(0, buckets + 1)), 0);
    const auto g = t_.grid;
    const auto lo = boxes_.lo, hi = boxes_.hi;
    const auto flag = t_.is_oversize;
    small_for(
        "bp_bucket_count", boxes_.size(), KOKKOS_LAMBDA(const LO i) {
          if (flag(i)) return;
          LO c0[dim], c1[dim];
          g.range(lo, hi, i, c0, c1);
          auto add = [&](const LO* c) { Kokkos::atomic_increment(&start(g.bucket(g.key(c)))); };
          for_each_cell<dim>(c0, c1, add);
        });
    LO total = 0;
    small_scan(
        "bp_bucket_scan", buckets + 1,
        KOKKOS_LAMBDA(const LO b, LO& acc, const bool final) {
          const LO c = start(b);
          if (final) start(b) = acc;
          acc += c;
        },
        total);
    const auto cur = cursor_;
    small_for(
        "bp_cursor_init", buckets, KOKKOS_LAMBDA(const LO b) { cur(b) = start(b); });
    const auto ekey = t_.entry_key;
    const auto ebox = t_.entry_box;
    small_for(
        "bp_bucket_fill", boxes_.size(), KOKKOS_LAMBDA(const LO i) {
          if (flag(i)) return;
          LO c0[dim], c1[dim];
          g.range(lo, hi, i, c0, c1);
          auto put = [&](const LO* c) {
            const std::int64_t key = g.key(c);
            const LO e = Kokkos::atomic_fetch_add(&cur(g.bucket(key)), 1);
            ekey(e) = key;
            ebox(e) = i;
          };
          for_each_cell<dim>(c0, c1, put);
        });
    (void)total;  // == entries
  }

  Boxes<dim> boxes_;
  broad_phase_detail::Traversal<dim> t_;
  Kokkos::View<LO*, MemSpace> cursor_, hist_;
  Kokkos::View<std::int64_t*, MemSpace> offsets_;
  SpatialHashStats stats_;
};

// Boxes of the nodes of x (node-interleaved), swept to x + t*dx and padded.
template <int dim>
void point_boxes(Kokkos::View<const double*, MemSpace> x, Kokkos::View<const double*, MemSpace> dx, double t,
                 double pad, Boxes<dim>& out) {
  const bool moving = dx.extent(0) > 0;
  if (moving && dx.extent(0) != x.extent(0))
    throw std::invalid_argument("point_boxes: dx has " + std::to_string(dx.extent(0)) + " entries, x has " +
                                std::to_string(x.extent(0)));
  out.resize(static_cast<LO>(x.extent(0) / dim));
  const auto lo = out.lo, hi = out.hi;
  small_for(
      "bp_point_boxes", out.size(), KOKKOS_LAMBDA(const LO i) {
        for (int c = 0; c < dim; ++c) {
          const double a = x(i * dim + c), b = moving ? a + t * dx(i * dim + c) : a;
          lo(i, c) = broad_phase_detail::dmin(a, b) - pad;
          hi(i, c) = broad_phase_detail::dmax(a, b) + pad;
        }
      });
}

template <int dim>
void point_boxes(Kokkos::View<const double*, MemSpace> x, Kokkos::View<const double*, MemSpace> dx, double pad,
                 Boxes<dim>& out) {
  point_boxes<dim>(x, dx, 1.0, pad, out);
}

// Boxes of the simplices nodes(i, 0..k-1) over positions x (node-interleaved),
// swept to x + t*dx and padded.
template <int dim, int k>
void simplex_boxes(Kokkos::View<const LO* [k], MemSpace> nodes, Kokkos::View<const double*, MemSpace> x,
                   Kokkos::View<const double*, MemSpace> dx, double t, double pad, Boxes<dim>& out) {
  const bool moving = dx.extent(0) > 0;
  if (moving && dx.extent(0) != x.extent(0))
    throw std::invalid_argument("simplex_boxes: dx has " + std::to_string(dx.extent(0)) + " entries, x has " +
                                std::to_string(x.extent(0)));
  out.resize(static_cast<LO>(nodes.extent(0)));
  const auto lo = out.lo, hi = out.hi;
  small_for(
      "bp_simplex_boxes", out.size(), KOKKOS_LAMBDA(const LO i) {
        for (int c = 0; c < dim; ++c) {
          double mn = x(nodes(i, 0) * dim + c), mx = mn;
          for (int a = 0; a < k; ++a) {
            const double p = x(nodes(i, a) * dim + c), q = moving ? p + t * dx(nodes(i, a) * dim + c) : p;
            mn = broad_phase_detail::dmin(mn, broad_phase_detail::dmin(p, q));
            mx = broad_phase_detail::dmax(mx, broad_phase_detail::dmax(p, q));
          }
          lo(i, c) = mn - pad;
          hi(i, c) = mx + pad;
        }
      });
}

template <int dim, int k>
void simplex_boxes(Kokkos::View<const LO* [k], MemSpace> nodes, Kokkos::View<const double*, MemSpace> x,
                   Kokkos::View<const double*, MemSpace> dx, double pad, Boxes<dim>& out) {
  simplex_boxes<dim, k>(nodes, x, dx, 1.0, pad, out);
}

}  // namespace bfemp
