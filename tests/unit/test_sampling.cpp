// Regular particle sampling of shapes: exact counts and masses for boxes,
// converging areas for disks, rings and half-rings, the origin-aligned
// lattice, mesh and signed-distance shapes, the particle fields, and the
// rejection of bad input with the field named.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "io/shape_mesher.hpp"
#include "kernels/mpm/particles.hpp"
#include "mpm/sampling.hpp"

namespace {

using namespace bfemp;
constexpr double kPi = 3.14159265358979323846;

SamplingShape shape(const std::string& kind, std::vector<double> center, std::vector<double> size,
                    double inner = 0.0, double outer = 0.0) {
  SamplingShape s;
  s.kind = kind;
  s.center = std::move(center);
  s.size = std::move(size);
  s.inner_radius = inner;
  s.outer_radius = outer;
  return s;
}

// A Gmsh-meshed 2D disk, and the sampling shape of a mesh.
MeshData disk_mesh(std::vector<double> center, double radius, double h) {
  ShapeSpec disk;
  disk.kind = "disk";
  disk.center = std::move(center);
  disk.outer_radius = radius;
  disk.element_size = h;
  return mesh_shape(disk, 2);
}

SamplingShape mesh_of(const MeshData& mesh) {
  SamplingShape m;
  m.kind = "mesh";
  m.mesh = &mesh;
  return m;
}

template <int dim>
double total(const Kokkos::View<double*, MemSpace>& v) {
  double sum = 0.0;
  Kokkos::parallel_reduce(
      "sum", Kokkos::RangePolicy<ExecSpace>(0, v.extent(0)),
      KOKKOS_LAMBDA(const int q, double& acc) { acc += v(q); }, sum);
  return sum;
}

// Every particle on the lattice (m + 1/2) dx / s, s = ppc^(1/dim).
template <int dim>
void expect_on_lattice(const Particles<dim>& p, double dx, int s) {
  auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.x);
  for (std::size_t q = 0; q < p.size(); ++q)
    for (int d = 0; d < dim; ++d) {
      const double m = x(q, d) / dx * s - 0.5;
      ASSERT_NEAR(m, std::round(m), 1e-9) << "particle " << q << " axis " << d;
    }
}

// |sampled volume / exact - 1| for dx.
double area_error_2d(const SamplingShape& s, double dx, int ppc) {
  const Particles<2> p = sample_particles<2>(s, dx, ppc, 1.0, 0, 0);
  return std::abs(p.size() * dx * dx / ppc / sampling_shape_measure(s, 2) - 1.0);
}

TEST(Sampling, UnitSquareGivesExactCountMassAndFields) {
  for (const auto& center : {std::vector<double>{0.5, 0.5}, std::vector<double>{0.0, 0.0}}) {
    const Particles<2> p = sample_particles<2>(shape("box", center, {1.0, 1.0}), 0.1, 4, 1000.0, 3, 2);
    ASSERT_EQ(p.size(), 400u);
    EXPECT_NEAR(total<2>(p.mass), 1000.0, 1e-9);
    EXPECT_NEAR(total<2>(p.volume0), 1.0, 1e-12);
    expect_on_lattice<2>(p, 0.1, 2);
    auto h = [](auto v) { return Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), v); };
    auto v = h(p.v);
    auto F = h(p.F);
    auto C = h(p.C);
    auto vol = h(p.volume0);
    auto body = h(p.body);
    auto mat = h(p.material);
    for (std::size_t q = 0; q < p.size(); ++q) {
      EXPECT_NEAR(vol(q), 0.0025, 1e-17);
      EXPECT_EQ(body(q), 3);
      EXPECT_EQ(mat(q), 2);
      for (int i = 0; i < 2; ++i) {
        EXPECT_EQ(v(q, i), 0.0);
        for (int j = 0; j < 2; ++j) {
          EXPECT_EQ(F(q, i, j), i == j ? 1.0 : 0.0);
          EXPECT_EQ(C(q, i, j), 0.0);
        }
      }
    }
  }
  // All allowed ppc in 2D fill the square exactly.
  for (int ppc : {1, 4, 9, 16}) {
    const Particles<2> p = sample_particles<2>(shape("rectangle", {0.5, 0.5}, {1.0, 1.0}), 0.1, ppc, 1.0, 0, 0);
    EXPECT_EQ(p.size(), 100u * ppc);
    expect_on_lattice<2>(p, 0.1, static_cast<int>(std::lround(std::sqrt(ppc))));
  }
}

TEST(Sampling, BoxIn3D) {
  const Particles<3> p = sample_particles<3>(shape("box", {0.5, 0.5, 0.5}, {1.0, 1.0, 1.0}), 0.1, 8, 100.0, 0, 0);
  EXPECT_EQ(p.size(), 8000u);
  EXPECT_NEAR(total<3>(p.mass), 100.0, 1e-9);
  expect_on_lattice<3>(p, 0.1, 2);
  for (int ppc : {1, 27})
    EXPECT_EQ(sample_particles<3>(shape("box", {0.5, 0.5, 0.5}, {1.0, 1.0, 1.0}), 0.1, ppc, 1.0, 0, 0).size(),
              1000u * ppc);
}

TEST(Sampling, CurvedShapesConvergeToTheirArea) {
  const std::vector<SamplingShape> shapes = {
      shape("disk", {0.123, -0.456}, {}, 0.0, 0.5),
      shape("ring", {0.31, 0.17}, {}, 0.25, 0.5),
      shape("half-ring", {-0.2, 0.05}, {}, 0.3, 0.6)};
  // The error of one sampling depends on where the boundary cuts the lattice;
  // its worst case over shifted centres shrinks with dx.
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> shift(-0.5, 0.5);
  for (const SamplingShape& s0 : shapes) {
    double coarse = 0.0, mid = 0.0, fine = 0.0;
    for (int k = 0; k < 8; ++k) {
      SamplingShape s = s0;
      s.center = {s0.center[0] + shift(rng), s0.center[1] + shift(rng)};
      coarse = std::max(coarse, area_error_2d(s, 0.1, 4));
      mid = std::max(mid, area_error_2d(s, 0.05, 4));
      fine = std::max(fine, area_error_2d(s, 0.0125, 4));
    }
    std::printf("%-9s worst |area error| dx 0.1: %.2e  0.05: %.2e  0.0125: %.2e\n", s0.kind.c_str(),
                coarse, mid, fine);
    EXPECT_LT(coarse, 0.05) << s0.kind;
    EXPECT_LT(mid, 0.03) << s0.kind;
    EXPECT_LT(fine, 0.005) << s0.kind;
    EXPECT_LT(mid, coarse) << s0.kind;
    EXPECT_LT(fine, mid) << s0.kind;
    expect_on_lattice<2>(sample_particles<2>(s0, 0.05, 9, 1.0, 0, 0), 0.05, 3);
  }
  // Half-ring: nothing below the centre line.
  const Particles<2> p = sample_particles<2>(shapes[2], 0.02, 4, 1.0, 0, 0);
  auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.x);
  for (std::size_t q = 0; q < p.size(); ++q) ASSERT_GT(x(q, 1), 0.05);
  // Sphere.
  const SamplingShape ball = shape("sphere", {0.1, 0.2, -0.3}, {}, 0.0, 0.5);
  const Particles<3> b = sample_particles<3>(ball, 0.05, 8, 1.0, 0, 0);
  EXPECT_NEAR(b.size() * std::pow(0.05, 3) / 8 / (4.0 / 3.0 * kPi * 0.125), 1.0, 0.02);
  expect_on_lattice<3>(b, 0.05, 2);
}

TEST(Sampling, SignedDistanceMatchesAnalyticDisk) {
  SamplingShape sdf = shape("sdf", {0.0, 0.0}, {1.2, 1.2});
  sdf.sdf = [](const double* x) { return std::hypot(x[0] - 0.1, x[1]) - 0.5; };
  const auto a = sample_particles<2>(sdf, 0.05, 4, 1.0, 0, 0);
  const auto b = sample_particles<2>(shape("disk", {0.1, 0.0}, {}, 0.0, 0.5), 0.05, 4, 1.0, 0, 0);
  ASSERT_EQ(a.size(), b.size());
  auto xa = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), a.x);
  auto xb = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), b.x);
  for (std::size_t q = 0; q < a.size(); ++q)
    for (int d = 0; d < 2; ++d) ASSERT_EQ(xa(q, d), xb(q, d));
}

TEST(Sampling, ClosedMeshMatchesAnalyticShape) {
  const MeshData mesh = disk_mesh({0.05, -0.1}, 0.5, 0.04);
  SamplingShape m = mesh_of(mesh);
  const std::size_t n_mesh = sample_particles<2>(m, 0.02, 4, 1.0, 0, 0).size();
  const std::size_t n_disk =
      sample_particles<2>(shape("disk", {0.05, -0.1}, {}, 0.0, 0.5), 0.02, 4, 1.0, 0, 0).size();
  EXPECT_NEAR(static_cast<double>(n_mesh) / n_disk, 1.0, 0.01);
  EXPECT_NEAR(n_mesh * 0.02 * 0.02 / 4 / sampling_shape_measure(m, 2), 1.0, 0.01);

  // A box mesh whose faces miss the lattice points gives the exact count.
  ShapeSpec box;
  box.kind = "box";
  box.center = {0.5, 0.5, 0.5};
  box.size = {1.0, 1.0, 1.0};
  box.element_size = 0.3;
  const MeshData bmesh = mesh_shape(box, 3);
  m.mesh = &bmesh;
  const Particles<3> p = sample_particles<3>(m, 0.1, 8, 1.0, 0, 0);
  EXPECT_EQ(p.size(), 8000u);
  expect_on_lattice<3>(p, 0.1, 2);
}

TEST(Sampling, ConcatenateKeepsBodiesAndFields) {
  auto a = sample_particles<2>(shape("box", {0.5, 0.5}, {1.0, 1.0}), 0.1, 1, 2.0, 0, 1);
  auto b = sample_particles<2>(shape("disk", {3.0, 0.0}, {}, 0.0, 0.3), 0.1, 4, 5.0, 1, 0);
  const Particles<2> all = concatenate<2>({a, b});
  ASSERT_EQ(all.size(), a.size() + b.size());
  EXPECT_NEAR(total<2>(all.mass), total<2>(a.mass) + total<2>(b.mass), 1e-12);
  auto body = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), all.body);
  auto F = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), all.F);
  auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), all.x);
  auto xb = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), b.x);
  for (std::size_t q = 0; q < all.size(); ++q) {
    EXPECT_EQ(body(q), q < a.size() ? 0 : 1);
    EXPECT_EQ(F(q, 0, 0), 1.0);
    EXPECT_EQ(F(q, 0, 1), 0.0);
  }
  EXPECT_EQ(x(a.size(), 0), xb(0, 0));
  EXPECT_EQ(concatenate<3>({}).size(), 0u);
  const std::string line = sampling_report<2>(shape("box", {0.5, 0.5}, {1.0, 1.0}), a, 0.1, 1);
  EXPECT_NE(line.find("100 particles"), std::string::npos) << line;
}

// The message names the field and the offending value.
template <int dim>
void expect_rejected(const SamplingShape& s, double dx, int ppc, double density, const std::string& part1,
                     const std::string& part2) {
  try {
    sample_particles<dim>(s, dx, ppc, density, 0, 0);
    ADD_FAILURE() << "accepted; expected an error naming " << part1;
  } catch (const std::invalid_argument& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(part1), std::string::npos) << msg;
    EXPECT_NE(msg.find(part2), std::string::npos) << msg;
  }
}

TEST(Sampling, BadInputIsRejectedWithTheFieldNamed) {
  const SamplingShape box = shape("box", {0.5, 0.5}, {1.0, 1.0});
  expect_rejected<2>(shape("blob", {}, {}), 0.1, 4, 1.0, "'kind'", "blob");
  expect_rejected<2>(shape("sphere", {}, {}, 0.0, 1.0), 0.1, 4, 1.0, "'kind'", "sphere");
  expect_rejected<3>(shape("disk", {}, {}, 0.0, 1.0), 0.1, 8, 1.0, "'kind'", "disk");
  expect_rejected<2>(box, 0.1, 5, 1.0, "'ppc'", "5");
  expect_rejected<3>(shape("box", {}, {1.0, 1.0, 1.0}), 0.1, 4, 1.0, "'ppc'", "4");
  expect_rejected<2>(box, 0.0, 4, 1.0, "'dx'", "0");
  expect_rejected<2>(box, -0.1, 4, 1.0, "'dx'", "-0.1");
  expect_rejected<2>(box, std::nan(""), 4, 1.0, "'dx'", "nan");
  expect_rejected<2>(box, 0.1, 4, -2.0, "'density'", "-2");
  expect_rejected<2>(box, 1e-6, 4, 1.0, "'dx'", "1e-06");
  expect_rejected<2>(shape("box", {0.5, 0.5}, {1.0}), 0.1, 4, 1.0, "'size'", "1 entries");
  expect_rejected<2>(shape("box", {0.5, 0.5}, {1.0, 0.0}), 0.1, 4, 1.0, "'size[1]'", "0");
  expect_rejected<2>(shape("box", {0.5, 0.5, 0.5}, {1.0, 1.0}), 0.1, 4, 1.0, "'center'", "3 entries");
  expect_rejected<2>(shape("disk", {}, {}, 0.0, 0.0), 0.1, 4, 1.0, "'outer_radius'", "0");
  expect_rejected<2>(shape("ring", {}, {}, 0.0, 1.0), 0.1, 4, 1.0, "'inner_radius'", "0");
  expect_rejected<2>(shape("ring", {}, {}, 1.0, 0.5), 0.1, 4, 1.0, "'inner_radius'", "1");
  expect_rejected<2>(shape("half-ring", {}, {}, 0.5, 0.5), 0.1, 4, 1.0, "'inner_radius'", "0.5");
  expect_rejected<2>(shape("mesh", {}, {}), 0.1, 4, 1.0, "'mesh'", "null");
  expect_rejected<2>(shape("sdf", {}, {1.0, 1.0}), 0.1, 4, 1.0, "'sdf'", "empty");
  expect_rejected<2>(shape("ring", {}, {}, 0.01, 0.03), 0.1, 4, 1.0,
                     "shape 'ring' with dx 0.1 produced no particles", "ppc 4");
  expect_rejected<2>(shape("disk", {}, {}, 0.0, 0.01), 0.1, 1, 1.0,
                     "shape 'disk' with dx 0.1 produced no particles", "ppc 1");
  EXPECT_THROW(sample_particles<2>(box, 0.1, 4, 1.0, -1, 0), std::invalid_argument);
  EXPECT_THROW(sample_particles<2>(box, 0.1, 4, 1.0, 0, -1), std::invalid_argument);
}

}  // namespace

// Ranges of the sampling (each MPI rank samples its id block of a body):
// count_particles is the whole sampling's size, and the ranges of any split
// [n k / K, n (k+1) / K), empty ones included, concatenate to the whole
// sampling bit for bit, fields included; a range past the end is refused.
template <int dim>
void expect_ranges_tile(const SamplingShape& s, double dx, int ppc) {
  const Particles<dim> whole = sample_particles<dim>(s, dx, ppc, 2.5, 3, 1);
  const long long n = count_particles<dim>(s, dx, ppc);
  ASSERT_EQ(n, static_cast<long long>(whole.size())) << s.kind;
  auto xw = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), whole.x);
  for (long long K : {1LL, 2LL, 3LL, 7LL, n + 2}) {
    long long row = 0;
    for (long long k = 0; k < K; ++k) {
      const long long lo = n * k / K, hi = n * (k + 1) / K;
      const Particles<dim> part = sample_particles<dim>(s, dx, ppc, 2.5, 3, 1, lo, hi - lo);
      ASSERT_EQ(static_cast<long long>(part.size()), hi - lo) << s.kind << " K " << K << " k " << k;
      auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), part.x);
      auto m = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), part.mass);
      auto b = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), part.body);
      auto mat = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), part.material);
      for (std::size_t q = 0; q < part.size(); ++q, ++row) {
        for (int d = 0; d < dim; ++d) ASSERT_EQ(x(q, d), xw(row, d)) << s.kind << " K " << K << " row " << row;
        ASSERT_EQ(m(q), 2.5 * std::pow(dx, dim) / ppc);
        ASSERT_EQ(b(q), 3);
        ASSERT_EQ(mat(q), 1);
      }
    }
    EXPECT_EQ(row, n) << s.kind << " K " << K;
  }
  EXPECT_EQ(sample_particles<dim>(s, dx, ppc, 2.5, 3, 1, n, 0).size(), 0u);
  EXPECT_THROW(sample_particles<dim>(s, dx, ppc, 2.5, 3, 1, n - 1, 2), std::invalid_argument) << s.kind;
  EXPECT_THROW(sample_particles<dim>(s, dx, ppc, 2.5, 3, 1, -1, 1), std::invalid_argument) << s.kind;
}

TEST(Sampling, RangesTileTheWholeSampling) {
  expect_ranges_tile<2>(shape("ring", {0.1, -0.2}, {}, 0.3, 0.5), 0.05, 4);
  expect_ranges_tile<2>(shape("half-ring", {0.0, 0.0}, {}, 0.2, 0.4), 0.05, 9);
  expect_ranges_tile<3>(shape("box", {0.5, 0.5, 0.5}, {0.3, 0.2, 0.4}), 0.1, 8);
  const MeshData mesh = disk_mesh({0.05, -0.1}, 0.3, 0.05);
  expect_ranges_tile<2>(mesh_of(mesh), 0.05, 4);
  // The empty sampling is refused by the count as by the sampling.
  EXPECT_THROW(count_particles<2>(shape("disk", {0.0, 0.0}, {}, 0.0, 1e-4), 0.05, 4), std::invalid_argument);
}

// Overlap of two bodies from their shapes: first_shared_point agrees with
// the particles themselves (a pair of the two samplings closer than h / 2,
// h the lattice spacing, brute force), and the point it returns is the
// first such particle of the first shape, x fastest.
template <int dim>
void expect_shared_point(const SamplingShape& a, const SamplingShape& b, double dx, int ppc, bool expected) {
  const Particles<dim> pa = sample_particles<dim>(a, dx, ppc, 1.0, 0, 0);
  const Particles<dim> pb = sample_particles<dim>(b, dx, ppc, 1.0, 1, 0);
  auto xa = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), pa.x);
  auto xb = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), pb.x);
  const double h = dx / std::round(std::pow(ppc, 1.0 / dim));
  long long first = -1;
  for (std::size_t p = 0; p < pa.size() && first < 0; ++p)
    for (std::size_t q = 0; q < pb.size(); ++q) {
      double r2 = 0;
      for (int d = 0; d < dim; ++d) r2 += (xa(p, d) - xb(q, d)) * (xa(p, d) - xb(q, d));
      if (r2 < 0.25 * h * h) {
        first = static_cast<long long>(p);
        break;
      }
    }
  double x[dim];
  const bool found = first_shared_point<dim>(a, b, dx, ppc, x);
  EXPECT_EQ(found, first >= 0) << a.kind << " / " << b.kind;
  EXPECT_EQ(found, expected) << a.kind << " / " << b.kind;
  if (found && first >= 0)
    for (int d = 0; d < dim; ++d) EXPECT_EQ(x[d], xa(first, d)) << a.kind << " / " << b.kind << " axis " << d;
}

TEST(Sampling, SharedPointMatchesTheSamplings) {
  const auto ring = shape("ring", {0.0, 0.0}, {}, 0.3, 0.5);
  expect_shared_point<2>(ring, shape("disk", {0.0, 0.0}, {}, 0.0, 0.25), 0.05, 4, false);  // in the hole
  expect_shared_point<2>(ring, shape("disk", {0.1, 0.0}, {}, 0.0, 0.25), 0.05, 4, true);   // on the ring
  expect_shared_point<2>(shape("disk", {0.5, 0.1}, {}, 0.0, 0.25), ring, 0.05, 9, true);
  // Boxes sharing an edge are apart; overlapping by one sub-cell they are not.
  expect_shared_point<2>(shape("box", {0.3, 0.5}, {0.2, 0.2}), shape("box", {0.5, 0.5}, {0.2, 0.2}), 0.1, 4, false);
  expect_shared_point<2>(shape("box", {0.3, 0.5}, {0.2, 0.2}), shape("box", {0.47, 0.5}, {0.2, 0.2}), 0.1, 4, true);
  expect_shared_point<3>(shape("box", {0.0, 0.0, 0.0}, {0.4, 0.4, 0.4}), shape("sphere", {0.35, 0.0, 0.0}, {}, 0.0, 0.2),
                         0.1, 8, true);
  expect_shared_point<3>(shape("box", {0.0, 0.0, 0.0}, {0.4, 0.4, 0.4}), shape("sphere", {0.45, 0.0, 0.0}, {}, 0.0, 0.2),
                         0.1, 8, false);
}

// The first overlapping pair of several shapes, in pair order (a, then b):
// each shape's lattice made once; pairs whose lattices do not meet skipped.
TEST(Sampling, FirstOverlappingPairInPairOrder) {
  const MeshData mesh = disk_mesh({1.0, 0.0}, 0.2, 0.05);
  const std::vector<SamplingShape> shapes = {shape("box", {-1.0, 0.0}, {0.2, 0.2}), mesh_of(mesh),
                                             shape("disk", {1.25, 0.0}, {}, 0.0, 0.1),
                                             shape("disk", {-0.85, 0.0}, {}, 0.0, 0.1)};
  int a = -1, b = -1;
  double x[2];
  ASSERT_TRUE(first_overlapping_pair<2>(shapes, 0.05, 4, a, b, x));
  EXPECT_EQ(a, 0);  // the box and the last disk before the mesh and the middle disk
  EXPECT_EQ(b, 3);
  double y[2];
  ASSERT_TRUE(first_shared_point<2>(shapes[0], shapes[3], 0.05, 4, y));
  EXPECT_EQ(x[0], y[0]);
  EXPECT_EQ(x[1], y[1]);
  const std::vector<SamplingShape> apart = {shapes[0], shapes[1], shapes[2]};
  ASSERT_TRUE(first_overlapping_pair<2>(apart, 0.05, 4, a, b, x));
  EXPECT_EQ(a, 1);
  EXPECT_EQ(b, 2);
  EXPECT_FALSE(first_overlapping_pair<2>({shapes[0], shapes[2]}, 0.05, 4, a, b, x));
}
