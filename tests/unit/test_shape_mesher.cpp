// mesh_shape: measures, orientation, node sets, refinement, error messages.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>

#include "io/shape_mesher.hpp"

namespace {

using bfemp::mesh_shape;
using bfemp::MeshData;
using bfemp::ShapeSpec;

constexpr double kPi = 3.14159265358979323846;

ShapeSpec spec(const std::string& kind, std::vector<double> center, std::vector<double> size,
               double inner, double outer, double h) {
  ShapeSpec s;
  s.kind = kind;
  s.center = std::move(center);
  s.size = std::move(size);
  s.inner_radius = inner;
  s.outer_radius = outer;
  s.element_size = h;
  return s;
}

void expect_valid(const MeshData& m, int dim) {
  ASSERT_EQ(m.dim, dim);
  ASSERT_GT(m.num_cells(), 0u);
  ASSERT_EQ(m.cells.size(), m.num_cells() * (dim + 1));
  std::vector<int> used(m.num_nodes(), 0);
  for (long long v : m.cells) {
    ASSERT_GE(v, 0);
    ASSERT_LT(v, static_cast<long long>(m.num_nodes()));
    used[v] = 1;
  }
  for (std::size_t i = 0; i < used.size(); ++i) EXPECT_TRUE(used[i]) << "unused node " << i;
  for (std::size_t c = 0; c < m.num_cells(); ++c)
    ASSERT_GT(bfemp::cell_determinant(m, c), 0.0) << "cell " << c;
}

// Longest and mean edge length (edges counted once per cell).
struct EdgeStats {
  double max = 0.0, mean = 0.0;
};
EdgeStats edge_stats(const MeshData& m) {
  const int d = m.dim;
  EdgeStats s;
  std::size_t n = 0;
  for (std::size_t c = 0; c < m.num_cells(); ++c)
    for (int a = 0; a <= d; ++a)
      for (int b = a + 1; b <= d; ++b) {
        double l2 = 0.0;
        for (int k = 0; k < d; ++k) {
          const double e = m.coords[m.cells[c * (d + 1) + a] * d + k] -
                           m.coords[m.cells[c * (d + 1) + b] * d + k];
          l2 += e * e;
        }
        s.max = std::max(s.max, std::sqrt(l2));
        s.mean += std::sqrt(l2);
        ++n;
      }
  s.mean /= double(n);
  return s;
}

// The element size is honoured roughly. 2D: mean edge within 15 % of h, no
// edge > 2 h. 3D: Gmsh's Delaunay refinement leaves interior edges of up to
// ~1.4 h (measured mean 1.15-1.3 h for boxes and shells), so the mean must lie
// in [0.9 h, 1.4 h] and no edge may exceed 2.5 h.
void expect_size_honoured(const MeshData& m, double h) {
  const EdgeStats s = edge_stats(m);
  const bool two_d = m.dim == 2;
  EXPECT_GT(s.mean, (two_d ? 0.85 : 0.9) * h);
  EXPECT_LT(s.mean, (two_d ? 1.15 : 1.4) * h);
  EXPECT_LT(s.max, (two_d ? 2.0 : 2.5) * h);
}

std::string error_of(const ShapeSpec& s, int dim) {
  try {
    mesh_shape(s, dim);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(ShapeMesher, RectangleAreaAndSides) {
  const MeshData m = mesh_shape(spec("rectangle", {2.0, 3.0}, {2.0, 1.0}, 0, 0, 0.1), 2);
  expect_valid(m, 2);
  EXPECT_NEAR(bfemp::total_measure(m), 2.0, 2e-14);
  expect_size_honoured(m, 0.1);
  const struct { const char* name; int axis; double value; } sides[] = {
      {"left", 0, 1.0}, {"right", 0, 3.0}, {"bottom", 1, 2.5}, {"top", 1, 3.5}};
  for (const auto& side : sides) {
    const auto& set = m.node_sets.at(side.name);
    EXPECT_GE(set.size(), side.axis == 0 ? 11u : 21u) << side.name;
    EXPECT_TRUE(std::is_sorted(set.begin(), set.end()));
    for (long long v : set) EXPECT_NEAR(m.coords[2 * v + side.axis], side.value, 1e-12) << side.name;
  }
  // Every boundary node lies in some side set: count nodes on the bottom line.
  std::size_t bottom = 0;
  for (std::size_t i = 0; i < m.num_nodes(); ++i) bottom += std::abs(m.coords[2 * i + 1] - 2.5) < 1e-6;
  EXPECT_EQ(m.node_sets.at("bottom").size(), bottom);
}

TEST(ShapeMesher, RefinementQuadruplesTriangles) {
  const MeshData coarse = mesh_shape(spec("rectangle", {0, 0}, {2.0, 1.0}, 0, 0, 0.1), 2);
  const MeshData fine = mesh_shape(spec("rectangle", {0, 0}, {2.0, 1.0}, 0, 0, 0.05), 2);
  const double ratio = double(fine.num_cells()) / coarse.num_cells();
  EXPECT_GT(ratio, 3.4);
  EXPECT_LT(ratio, 4.6);
  // ~ area / (sqrt(3)/4 h^2) equilateral triangles.
  const double expected = 2.0 / (std::sqrt(3.0) / 4 * 0.05 * 0.05);
  EXPECT_GT(fine.num_cells(), 0.7 * expected);
  EXPECT_LT(fine.num_cells(), 1.4 * expected);
}

// Chords lose pi h^2 / 6 of area per circle of any radius (to leading order),
// so for a ring the outer and inner losses cancel; the disk shows the
// convergence order, the ring is held to the one-circle bound.
TEST(ShapeMesher, DiskAreaConvergesQuadratically) {
  const double exact = kPi * 4.0;
  double previous_error = 1.0;
  for (double h : {0.2, 0.1, 0.05}) {
    const MeshData m = mesh_shape(spec("disk", {}, {}, 0, 2.0, h), 2);
    expect_valid(m, 2);
    expect_size_honoured(m, h);
    const double error = std::abs(bfemp::total_measure(m) - exact) / exact;
    EXPECT_LT(error, 0.02) << "h = " << h;
    EXPECT_LT(error, 0.4 * previous_error) << "h = " << h;  // ~0.25 for O(h^2)
    previous_error = error;
    EXPECT_GE(m.node_sets.at("outer").size(), std::size_t(2 * kPi * 2.0 / (1.5 * h)));
  }
}

TEST(ShapeMesher, RingArea) {
  const double exact = kPi * (1.0 - 0.25);
  for (double h : {0.2, 0.1, 0.05}) {
    const MeshData m = mesh_shape(spec("ring", {0.5, -0.5}, {}, 0.5, 1.0, h), 2);
    expect_valid(m, 2);
    expect_size_honoured(m, h);
    const double error = std::abs(bfemp::total_measure(m) - exact);
    EXPECT_LT(error, 0.03 * exact) << "h = " << h;
    EXPECT_LT(error, kPi * (1.5 * h) * (1.5 * h) / 6) << "h = " << h;
    for (long long v : m.node_sets.at("inner"))
      EXPECT_NEAR(std::hypot(m.coords[2 * v] - 0.5, m.coords[2 * v + 1] + 0.5), 0.5, 1e-9);
    for (long long v : m.node_sets.at("outer"))
      EXPECT_NEAR(std::hypot(m.coords[2 * v] - 0.5, m.coords[2 * v + 1] + 0.5), 1.0, 1e-9);
    EXPECT_GE(m.node_sets.at("outer").size(), std::size_t(2 * kPi / (1.5 * h)));
    EXPECT_GE(m.node_sets.at("inner").size(), std::size_t(kPi / (1.5 * h)));
  }
}

TEST(ShapeMesher, HalfRingAndFeet) {
  const double cy = 1.0;
  const MeshData m = mesh_shape(spec("half-ring", {0.0, cy}, {}, 0.6, 1.0, 0.05), 2);
  expect_valid(m, 2);
  expect_size_honoured(m, 0.05);
  const double exact = 0.5 * kPi * (1.0 - 0.36);
  EXPECT_NEAR(bfemp::total_measure(m), exact, 0.02 * exact);
  double ymin = 1e30;
  for (std::size_t i = 0; i < m.num_nodes(); ++i) ymin = std::min(ymin, m.coords[2 * i + 1]);
  EXPECT_NEAR(ymin, cy, 1e-12);
  const auto& feet = m.node_sets.at("feet");
  EXPECT_GE(feet.size(), 2u * 8u);  // two feet of width 0.4 at h = 0.05
  double xmin = 1e30, xmax = -1e30;
  for (long long v : feet) {
    EXPECT_NEAR(m.coords[2 * v + 1], cy, 1e-9);
    EXPECT_GE(std::abs(m.coords[2 * v]), 0.6 - 1e-9);
    xmin = std::min(xmin, m.coords[2 * v]);
    xmax = std::max(xmax, m.coords[2 * v]);
  }
  EXPECT_NEAR(xmin, -1.0, 1e-9);
  EXPECT_NEAR(xmax, 1.0, 1e-9);
}

TEST(ShapeMesher, BoxVolumeAndFaces) {
  const MeshData m = mesh_shape(spec("box", {0, 0, 1}, {1.0, 0.5, 2.0}, 0, 0, 0.25), 3);
  expect_valid(m, 3);
  expect_size_honoured(m, 0.25);
  EXPECT_NEAR(bfemp::total_measure(m), 1.0, 1e-13);
  const struct { const char* name; int axis; double value; } faces[] = {
      {"left", 0, -0.5}, {"right", 0, 0.5}, {"bottom", 1, -0.25},
      {"top", 1, 0.25},  {"back", 2, 0.0},  {"front", 2, 2.0}};
  for (const auto& f : faces) {
    const auto& set = m.node_sets.at(f.name);
    EXPECT_GE(set.size(), 4u) << f.name;
    for (long long v : set) EXPECT_NEAR(m.coords[3 * v + f.axis], f.value, 1e-12) << f.name;
  }
}

TEST(ShapeMesher, SphericalShellVolume) {
  const MeshData m = mesh_shape(spec("spherical-shell", {1, 2, 3}, {}, 0.5, 1.0, 0.15), 3);
  expect_valid(m, 3);
  const double exact = 4.0 / 3.0 * kPi * (1.0 - 0.125);
  EXPECT_NEAR(bfemp::total_measure(m), exact, 0.04 * exact);
  expect_size_honoured(m, 0.15);
  for (long long v : m.node_sets.at("outer"))
    EXPECT_NEAR(std::hypot(m.coords[3 * v] - 1, m.coords[3 * v + 1] - 2, m.coords[3 * v + 2] - 3),
                1.0, 1e-9);
}

TEST(ShapeMesher, RepeatedCallsGiveSameMesh) {
  const ShapeSpec s = spec("ring", {0, 0}, {}, 0.3, 1.0, 0.1);
  const MeshData a = mesh_shape(s, 2);
  const MeshData b = mesh_shape(s, 2);
  EXPECT_EQ(a.num_cells(), b.num_cells());
  EXPECT_EQ(a.num_nodes(), b.num_nodes());
  EXPECT_NEAR(bfemp::total_measure(a), bfemp::total_measure(b), 1e-12);
}

TEST(ShapeMesher, BadParametersNamed) {
  EXPECT_NE(error_of(spec("hexagon", {0, 0}, {1, 1}, 0, 0, 0.1), 2).find("'kind' = 'hexagon'"),
            std::string::npos);
  EXPECT_NE(error_of(spec("box", {0, 0}, {1, 1}, 0, 0, 0.1), 2).find("'kind'"), std::string::npos);
  EXPECT_NE(error_of(spec("rectangle", {0, 0}, {1, -1}, 0, 0, 0.1), 2).find("'size[1]' = -1"),
            std::string::npos);
  EXPECT_NE(error_of(spec("rectangle", {0, 0}, {1}, 0, 0, 0.1), 2).find("'size'"),
            std::string::npos);
  EXPECT_NE(error_of(spec("rectangle", {0, 0, 0}, {1, 1}, 0, 0, 0.1), 2).find("'center'"),
            std::string::npos);
  EXPECT_NE(error_of(spec("rectangle", {0, 0}, {1, 1}, 0, 0, 0), 2).find("'element_size' = 0"),
            std::string::npos);
  EXPECT_NE(error_of(spec("rectangle", {0, 0}, {1, 1}, 0, 0, 1e-6), 2).find("'element_size'"),
            std::string::npos);
  const std::string msg = error_of(spec("ring", {0, 0}, {}, 1.0, 1.0, 0.1), 2);
  EXPECT_NE(msg.find("'inner_radius' = 1: expected < outer_radius = 1"), std::string::npos) << msg;
  EXPECT_NE(error_of(spec("disk", {0, 0}, {}, 0, -2, 0.1), 2).find("'outer_radius' = -2"),
            std::string::npos);
  EXPECT_NE(error_of(spec("spherical-shell", {0, 0, 0}, {}, 0, 1, 0.1), 3).find("'inner_radius'"),
            std::string::npos);
}

}  // namespace
