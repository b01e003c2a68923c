// Contact broad phase (kernels/contact/broad_phase.hpp), 2D and 3D: the
// spatial hash's pair list equals a brute-force O(n m) reference (computed
// here only) on random scenes mixing small, zero-size and scene-spanning boxes,
// exactly touching boxes and boxes on a coarse binary lattice; no duplicates;
// sorted by (query, box), also above the size where the hash is built in
// parallel; repeated queries and rebuilds after moving boxes give
// the reference again without reallocating; empty inputs; memory stays bounded
// for huge boxes; point_boxes / simplex_boxes against host formulas; and
// point_in_simplex on inside, outside, edge, vertex and near points.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <type_traits>
#include <utility>
#include <vector>

#include "kernels/contact/broad_phase.hpp"
#include "kernels/contact/point_in_simplex.hpp"

namespace {

using namespace bfemp;
using PairList = std::vector<std::pair<int, int>>;

// Host box list: lo/hi interleaved (i*dim + d).
template <int dim>
struct HostBoxes {
  std::vector<double> lo, hi;
  int size() const { return static_cast<int>(lo.size() / dim); }
  void add(const double* l, const double* h) {
    lo.insert(lo.end(), l, l + dim);
    hi.insert(hi.end(), h, h + dim);
  }
};

template <int dim>
Boxes<dim> to_device(const HostBoxes<dim>& h, Boxes<dim> b = Boxes<dim>()) {
  b.resize(h.size());
  auto lo = Kokkos::create_mirror_view(b.lo), hi = Kokkos::create_mirror_view(b.hi);
  for (int i = 0; i < h.size(); ++i)
    for (int d = 0; d < dim; ++d) lo(i, d) = h.lo[i * dim + d], hi(i, d) = h.hi[i * dim + d];
  Kokkos::deep_copy(b.lo, lo);
  Kokkos::deep_copy(b.hi, hi);
  return b;
}

// Every overlapping (closed boxes) pair, by query then box.
template <int dim>
PairList brute_force(const HostBoxes<dim>& q, const HostBoxes<dim>& b) {
  PairList out;
  for (int i = 0; i < q.size(); ++i)
    for (int j = 0; j < b.size(); ++j) {
      bool hit = true;
      for (int d = 0; d < dim; ++d)
        hit = hit && q.lo[i * dim + d] <= b.hi[j * dim + d] && b.lo[j * dim + d] <= q.hi[i * dim + d];
      if (hit) out.emplace_back(i, j);
    }
  return out;
}

PairList to_host(const Kokkos::View<LO* [2], MemSpace>& pairs, LO count) {
  auto h = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), pairs);
  PairList out;
  for (LO k = 0; k < count; ++k) out.emplace_back(h(k, 0), h(k, 1));
  return out;
}

template <int dim>
PairList hash_pairs(SpatialHash<dim>& hash, const HostBoxes<dim>& q, Kokkos::View<LO* [2], MemSpace>& pairs) {
  const LO n = hash.query(to_device(q), pairs);
  return to_host(pairs, n);
}

// Equality with the reference implies: no duplicates, contiguous per query,
// ascending box index. The explicit checks give clearer messages.
void expect_same(const PairList& got, const PairList& ref) {
  ASSERT_EQ(got.size(), ref.size());
  for (std::size_t k = 1; k < got.size(); ++k) ASSERT_LT(got[k - 1], got[k]) << "unsorted or duplicate at " << k;
  for (std::size_t k = 0; k < got.size(); ++k)
    ASSERT_EQ(got[k], ref[k]) << "pair " << k << " of " << got.size();
}

// Random scene in [0, 10]^dim: small boxes, every 50th zero-size, three
// scene-spanning plates (thin in the last axis); with `lattice` every
// coordinate is a multiple of 1/8, so many faces and corners coincide.
template <int dim>
HostBoxes<dim> random_boxes(int n, unsigned seed, bool lattice) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> pos(0, 10), half(0, 0.25);
  auto snap = [&](double x) { return lattice ? std::round(8 * x) / 8 : x; };
  HostBoxes<dim> b;
  for (int i = 0; i < n; ++i) {
    double lo[dim], hi[dim];
    const bool plate = i == 7 || i == n / 4 || i == n - 3;
    for (int d = 0; d < dim; ++d) {
      const double c = pos(rng), r = (i % 50 == 0) ? 0.0 : half(rng);
      lo[d] = snap(c - r), hi[d] = snap(c + r);
      if (plate) lo[d] = d == dim - 1 ? snap(c) : -1.0, hi[d] = d == dim - 1 ? snap(c) + 0.125 : 11.0;
    }
    b.add(lo, hi);
  }
  return b;
}

// Queries: small, zero-size, a few large, one covering everything, and some
// built from a box to touch it exactly on a face or only at a corner.
template <int dim>
HostBoxes<dim> random_queries(int m, const HostBoxes<dim>& boxes, unsigned seed, bool lattice) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> pos(-0.5, 10.5), half(0, 0.1);
  auto snap = [&](double x) { return lattice ? std::round(8 * x) / 8 : x; };
  HostBoxes<dim> q;
  for (int i = 0; i < m; ++i) {
    double lo[dim], hi[dim];
    const int j = (i * 7) % boxes.size();
    for (int d = 0; d < dim; ++d) {
      const double c = pos(rng), r = i % 40 == 0 ? 0.0 : i % 97 == 0 ? 3.0 : half(rng);
      lo[d] = snap(c - r), hi[d] = snap(c + r);
      const double bl = boxes.lo[j * dim + d], bh = boxes.hi[j * dim + d];
      if (i % 10 == 3) lo[d] = d == 0 ? bh : bl, hi[d] = d == 0 ? bh + (bh - bl) : bh;  // face touch
      if (i % 10 == 7) lo[d] = bh, hi[d] = bh + 0.125;                                   // corner touch
      if (i == 1) lo[d] = -2, hi[d] = 12;
    }
    q.add(lo, hi);
  }
  return q;
}

template <class T>
class BroadPhase : public ::testing::Test {};
using Dims = ::testing::Types<std::integral_constant<int, 2>, std::integral_constant<int, 3>>;
TYPED_TEST_SUITE(BroadPhase, Dims);

template <int dim>
void check_scene(bool lattice, unsigned seed, int n_boxes = 2000) {
  const auto boxes = random_boxes<dim>(n_boxes, seed, lattice);
  const auto queries = random_queries<dim>(500, boxes, seed + 1, lattice);
  SpatialHash<dim> hash;
  hash.build(to_device(boxes));
  Kokkos::View<LO* [2], MemSpace> pairs;
  const PairList ref = brute_force(queries, boxes);
  ASSERT_GT(ref.size(), static_cast<std::size_t>(n_boxes));  // the covering query alone hits every box
  expect_same(hash_pairs(hash, queries, pairs), ref);
  EXPECT_LE(hash.stats().oversize, SpatialHash<dim>::kMaxOversize);
  EXPECT_LE(hash.stats().entries, SpatialHash<dim>::kEntriesPerBox * boxes.size());
  EXPECT_GT(hash.stats().cell_size, 0);
}

TYPED_TEST(BroadPhase, MatchesBruteForce) { check_scene<TypeParam::value>(false, 11); }
// Below kSerialBelow boxes the hash is built on the calling thread
// (kernels/small_loops.hpp); this scene is built with ExecSpace's parallel
// loops (atomic bucket counts and fills, parallel scans).
TYPED_TEST(BroadPhase, MatchesBruteForceAboveTheSerialThreshold) {
  check_scene<TypeParam::value>(false, 31, static_cast<int>(kSerialBelow) + 1000);
}

TYPED_TEST(BroadPhase, MatchesBruteForceOnLatticeWithTouchingBoxes) { check_scene<TypeParam::value>(true, 23); }

// The three plates go to the oversize list rather than into thousands of cells.
TYPED_TEST(BroadPhase, SceneSpanningBoxesAreOversize) {
  constexpr int dim = TypeParam::value;
  SpatialHash<dim> hash;
  hash.build(to_device(random_boxes<dim>(2000, 5, false)));
  EXPECT_EQ(hash.stats().oversize, 3);
  EXPECT_LE(hash.stats().cell_size, 1.0);  // set by the small boxes, not the plates
}

// Every box large: the cell size grows instead of the entry count.
TYPED_TEST(BroadPhase, ManyHugeBoxesKeepMemoryBounded) {
  constexpr int dim = TypeParam::value;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0, 1);
  HostBoxes<dim> boxes;
  for (int i = 0; i < 600; ++i) {
    double lo[dim], hi[dim];
    for (int d = 0; d < dim; ++d) {
      const bool huge = i % 3 != 0;
      lo[d] = huge ? -10 * u(rng) : 10 * u(rng);
      hi[d] = huge ? 10 + 10 * u(rng) : lo[d] + 0.01;
    }
    boxes.add(lo, hi);
  }
  const auto queries = random_queries<dim>(300, boxes, 4, false);
  SpatialHash<dim> hash;
  hash.build(to_device(boxes));
  EXPECT_LE(hash.stats().oversize, SpatialHash<dim>::kMaxOversize);
  EXPECT_LE(hash.stats().entries, SpatialHash<dim>::kEntriesPerBox * boxes.size());
  Kokkos::View<LO* [2], MemSpace> pairs;
  expect_same(hash_pairs(hash, queries, pairs), brute_force(queries, boxes));
}

// Repeating a query gives the same list in the same buffer; a rebuild after
// moving the boxes matches the reference again; rebuilding the same scenes
// again allocates nothing.
TYPED_TEST(BroadPhase, RepeatedQueriesAndRebuildsReuseStorage) {
  constexpr int dim = TypeParam::value;
  const auto a = random_boxes<dim>(2000, 31, false);
  auto b = a;
  std::mt19937 rng(32);
  std::uniform_real_distribution<double> move(-0.3, 0.3);
  for (int i = 0; i < b.size(); ++i)
    for (int d = 0; d < dim; ++d) {
      const double s = move(rng);
      b.lo[i * dim + d] += s, b.hi[i * dim + d] += s;
    }
  const auto queries = random_queries<dim>(500, a, 33, false);
  const PairList ref_a = brute_force(queries, a), ref_b = brute_force(queries, b);
  SpatialHash<dim> hash;
  Kokkos::View<LO* [2], MemSpace> pairs;
  const Boxes<dim> qdev = to_device(queries);
  Boxes<dim> dev = to_device(a);
  hash.build(dev);
  const LO na = hash.query(qdev, pairs);
  const LO* buffer = pairs.data();
  expect_same(to_host(pairs, na), ref_a);
  EXPECT_EQ(hash.query(qdev, pairs), na);
  EXPECT_EQ(pairs.data(), buffer);
  expect_same(to_host(pairs, na), ref_a);

  dev = to_device(b, dev);  // same capacity: overwritten in place
  hash.build(dev);
  expect_same(to_host(pairs, hash.query(qdev, pairs)), ref_b);
  dev = to_device(a, dev);
  hash.build(dev);
  expect_same(to_host(pairs, hash.query(qdev, pairs)), ref_a);
  const std::size_t capacity = hash.storage_capacity();
  const LO* buffer2 = pairs.data();
  const HostBoxes<dim>* order[] = {&b, &a};
  for (const HostBoxes<dim>* s : order) {
    dev = to_device(*s, dev);
    hash.build(dev);
    expect_same(to_host(pairs, hash.query(qdev, pairs)), s == &a ? ref_a : ref_b);
    EXPECT_EQ(hash.storage_capacity(), capacity);
    EXPECT_EQ(pairs.data(), buffer2);
  }
}

TYPED_TEST(BroadPhase, EmptyInputs) {
  constexpr int dim = TypeParam::value;
  const auto boxes = random_boxes<dim>(100, 41, false);
  const auto queries = random_queries<dim>(50, boxes, 42, false);
  SpatialHash<dim> hash;
  Kokkos::View<LO* [2], MemSpace> pairs;
  EXPECT_EQ(hash.query(to_device(queries), pairs), 0);  // never built
  hash.build(Boxes<dim>());
  EXPECT_EQ(hash.query(to_device(queries), pairs), 0);
  EXPECT_EQ(hash.query(Boxes<dim>(), pairs), 0);
  hash.build(to_device(boxes));
  EXPECT_EQ(hash.query(Boxes<dim>(), pairs), 0);
  expect_same(hash_pairs(hash, queries, pairs), brute_force(queries, boxes));
  hash.build(Boxes<dim>());  // emptied again after a real build
  EXPECT_EQ(hash.query(to_device(queries), pairs), 0);
}

// All boxes zero-size, some coincident, or all at one single point (zero scene
// extent).
TYPED_TEST(BroadPhase, DegenerateScenes) {
  constexpr int dim = TypeParam::value;
  std::mt19937 rng(51);
  std::uniform_int_distribution<int> cell(0, 9);
  HostBoxes<dim> points, same;
  for (int i = 0; i < 400; ++i) {
    double p[dim], o[dim];
    for (int d = 0; d < dim; ++d) p[d] = 0.5 * cell(rng), o[d] = 1.25;
    points.add(p, p);
    same.add(o, o);
  }
  for (const auto* boxes : {&points, &same}) {
    const auto queries = random_queries<dim>(200, *boxes, 52, true);
    SpatialHash<dim> hash;
    hash.build(to_device(*boxes));
    Kokkos::View<LO* [2], MemSpace> pairs;
    expect_same(hash_pairs(hash, queries, pairs), brute_force(queries, *boxes));
    expect_same(hash_pairs(hash, *boxes, pairs), brute_force(*boxes, *boxes));
  }
}

TYPED_TEST(BroadPhase, PointAndSimplexBoxes) {
  constexpr int dim = TypeParam::value;
  constexpr int k = dim;  // boundary facets: segments in 2D, triangles in 3D
  const int nn = 40, ne = 30;
  std::mt19937 rng(61);
  std::uniform_real_distribution<double> u(-1, 1);
  Kokkos::View<double*, MemSpace> x("x", nn * dim), dx("dx", nn * dim), none;
  Kokkos::View<LO* [k], MemSpace> nodes("nodes", ne);
  for (int i = 0; i < nn * dim; ++i) x(i) = u(rng), dx(i) = u(rng);
  for (int e = 0; e < ne; ++e)
    for (int a = 0; a < k; ++a) nodes(e, a) = (e * 7 + a * 3) % nn;
  const double t = 0.4, pad = 0.05;
  for (const bool moving : {false, true}) {
    Boxes<dim> pb, sb;
    point_boxes<dim>(x, moving ? dx : none, t, pad, pb);
    simplex_boxes<dim, k>(nodes, x, moving ? dx : none, t, pad, sb);
    ASSERT_EQ(pb.size(), nn);
    ASSERT_EQ(sb.size(), ne);
    auto end = [&](int n, int d) { return x(n * dim + d) + (moving ? t * dx(n * dim + d) : 0.0); };
    for (int n = 0; n < nn; ++n)
      for (int d = 0; d < dim; ++d) {
        EXPECT_EQ(pb.lo(n, d), std::min(x(n * dim + d), end(n, d)) - pad);
        EXPECT_EQ(pb.hi(n, d), std::max(x(n * dim + d), end(n, d)) + pad);
      }
    for (int e = 0; e < ne; ++e)
      for (int d = 0; d < dim; ++d) {
        double mn = 1e300, mx = -1e300;
        for (int a = 0; a < k; ++a) {
          const int n = nodes(e, a);
          mn = std::min({mn, x(n * dim + d), end(n, d)});
          mx = std::max({mx, x(n * dim + d), end(n, d)});
        }
        EXPECT_EQ(sb.lo(e, d), mn - pad);
        EXPECT_EQ(sb.hi(e, d), mx + pad);
      }
  }
  Boxes<dim> b;
  point_boxes<dim>(x, dx, pad, b);  // t = 1 form
  EXPECT_EQ(b.hi(0, 0), std::max(x(0), x(0) + dx(0)) + pad);
  Kokkos::View<double*, MemSpace> short_dx("short", 3);
  EXPECT_THROW(point_boxes<dim>(x, short_dx, pad, b), std::invalid_argument);
}

TEST(PointInSimplex, Triangle) {
  const Vec<2> v[3] = {Vec<2>(0, 0), Vec<2>(2, 0), Vec<2>(0, 1)};
  const Vec<2> w[3] = {v[0], v[2], v[1]};  // opposite orientation
  for (const Vec<2>* s : {v, w}) {
    EXPECT_TRUE(point_in_simplex<2>(Vec<2>(0.5, 0.25), s, 0));   // inside
    EXPECT_FALSE(point_in_simplex<2>(Vec<2>(2, 1), s, 1e-9));     // outside
    EXPECT_TRUE(point_in_simplex<2>(Vec<2>(1, 0.5), s, 1e-12));   // on the hypotenuse
    EXPECT_TRUE(point_in_simplex<2>(Vec<2>(1, 0), s, 0));         // on an edge
    for (int i = 0; i < 3; ++i) EXPECT_TRUE(point_in_simplex<2>(s[i], s, 1e-12));  // vertices
    EXPECT_FALSE(point_in_simplex<2>(Vec<2>(1, -1e-3), s, 1e-4));  // 1e-3 below the bottom edge
    EXPECT_TRUE(point_in_simplex<2>(Vec<2>(1, -1e-3), s, 2e-3));
    // 1e-3 beyond the hypotenuse (unit normal (1, 2)/sqrt 5): tol is a distance.
    const Vec<2> out = Vec<2>(1, 0.5) + 1e-3 * Vec<2>(1, 2) / std::sqrt(5.0);
    EXPECT_FALSE(point_in_simplex<2>(out, s, 0.9e-3));
    EXPECT_TRUE(point_in_simplex<2>(out, s, 1.1e-3));
    EXPECT_FALSE(point_in_simplex<2>(Vec<2>(-0.1, 1.2), s, 0.05));  // beyond a vertex
  }
  const Vec<2> flat[3] = {Vec<2>(0, 0), Vec<2>(1, 0), Vec<2>(2, 0)};
  EXPECT_FALSE(point_in_simplex<2>(Vec<2>(1, 0), flat, 1e-3));
}

TEST(PointInSimplex, Tetrahedron) {
  const Vec<3> v[4] = {Vec<3>(0, 0, 0), Vec<3>(1, 0, 0), Vec<3>(0, 2, 0), Vec<3>(0, 0, 1)};
  const Vec<3> w[4] = {v[1], v[0], v[2], v[3]};
  for (const Vec<3>* s : {v, w}) {
    EXPECT_TRUE(point_in_simplex<3>(Vec<3>(0.2, 0.3, 0.2), s, 0));
    EXPECT_FALSE(point_in_simplex<3>(Vec<3>(1, 1, 1), s, 1e-9));
    EXPECT_FALSE(point_in_simplex<3>(Vec<3>(0.2, 0.2, -0.01), s, 1e-3));
    EXPECT_TRUE(point_in_simplex<3>(Vec<3>(0.2, 0.2, -0.01), s, 0.02));
    EXPECT_TRUE(point_in_simplex<3>(Vec<3>(1.0 / 3, 2.0 / 3, 1.0 / 3), s, 1e-12));  // slanted face centroid
    EXPECT_TRUE(point_in_simplex<3>(Vec<3>(0.5, 0, 0.5), s, 1e-12));                // edge midpoint
    EXPECT_TRUE(point_in_simplex<3>(Vec<3>(0.3, 0.4, 0), s, 0));                    // on a face
    for (int i = 0; i < 4; ++i) EXPECT_TRUE(point_in_simplex<3>(s[i], s, 1e-12));
    // Slanted face x + y/2 + z = 1, unit normal (1, 1/2, 1)/1.5.
    const Vec<3> out = Vec<3>(1.0 / 3, 2.0 / 3, 1.0 / 3) + 1e-3 * Vec<3>(1, 0.5, 1) / 1.5;
    EXPECT_FALSE(point_in_simplex<3>(out, s, 0.9e-3));
    EXPECT_TRUE(point_in_simplex<3>(out, s, 1.1e-3));
  }
  const Vec<3> flat[4] = {Vec<3>(0, 0, 0), Vec<3>(1, 0, 0), Vec<3>(0, 1, 0), Vec<3>(1, 1, 0)};
  EXPECT_FALSE(point_in_simplex<3>(Vec<3>(0.2, 0.2, 0), flat, 1e-3));
}

}  // namespace
