// read_gmsh_msh4: fixtures from tests/data and hand-written MSH 4.1 snippets.
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

#include "io/gmsh_reader.hpp"

namespace {

using bfemp::MeshData;
using bfemp::read_gmsh_msh4;

std::string data_path(const std::string& name) {
  return std::string(BFEMP_SOURCE_DIR) + "/tests/data/" + name;
}

std::string scratch(const std::string& name) {
  const std::string dir = std::string(BFEMP_BINARY_DIR) + "/test_scratch/gmsh_reader";
  std::filesystem::create_directories(dir);
  return dir + "/" + name;
}

std::string write_text(const std::string& name, const std::string& text) {
  const std::string path = scratch(name);
  std::ofstream(path) << text;
  return path;
}

std::string slurp(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Message of the std::exception thrown by read_gmsh_msh4, or "" if none.
std::string error_of(const std::string& path, int dim) {
  try {
    read_gmsh_msh4(path, dim);
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

void expect_positive_orientation(const MeshData& m) {
  for (std::size_t c = 0; c < m.num_cells(); ++c)
    ASSERT_GT(bfemp::cell_determinant(m, c), 0.0) << "cell " << c;
}

const std::string kHeader = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n";
const std::string kFourNodes =
    "$Nodes\n1 4 1 4\n2 1 0 4\n1\n2\n3\n4\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n$EndNodes\n";

TEST(GmshReader, SquareFixture) {
  const MeshData m = read_gmsh_msh4(data_path("square_tri.msh"), 2);
  EXPECT_EQ(m.dim, 2);
  EXPECT_EQ(m.num_nodes(), 30u);
  EXPECT_EQ(m.num_cells(), 42u);
  EXPECT_EQ(m.coords.size(), 60u);
  EXPECT_NEAR(bfemp::total_measure(m), 1.0, 1e-14);
  expect_positive_orientation(m);

  ASSERT_EQ(m.node_sets.size(), 6u);
  const auto check_side = [&](const std::string& name, int axis, double value) {
    const auto& set = m.node_sets.at(name);
    EXPECT_EQ(set.size(), 5u) << name;
    EXPECT_TRUE(std::is_sorted(set.begin(), set.end())) << name;
    for (long long v : set) EXPECT_EQ(m.coords[v * 2 + axis], value) << name << " node " << v;
  };
  check_side("left", 0, 0.0);
  check_side("right", 0, 1.0);
  check_side("bottom", 1, 0.0);
  check_side("top", 1, 1.0);
  ASSERT_EQ(m.node_sets.at("origin").size(), 1u);
  const long long o = m.node_sets.at("origin")[0];
  EXPECT_EQ(m.coords[2 * o], 0.0);
  EXPECT_EQ(m.coords[2 * o + 1], 0.0);
  EXPECT_EQ(m.node_sets.at("domain").size(), 30u);
}

TEST(GmshReader, CubeFixture) {
  const MeshData m = read_gmsh_msh4(data_path("cube_tet.msh"), 3);
  EXPECT_EQ(m.dim, 3);
  EXPECT_EQ(m.num_nodes(), 45u);
  EXPECT_EQ(m.num_cells(), 101u);
  EXPECT_NEAR(bfemp::total_measure(m), 1.0, 1e-13);
  expect_positive_orientation(m);
  std::size_t on_x0 = 0, on_x1 = 0;
  for (std::size_t i = 0; i < m.num_nodes(); ++i) {
    on_x0 += m.coords[3 * i] == 0.0;
    on_x1 += m.coords[3 * i] == 1.0;
  }
  EXPECT_EQ(m.node_sets.at("x0").size(), on_x0);
  EXPECT_EQ(m.node_sets.at("x1").size(), on_x1);
  for (long long v : m.node_sets.at("x0")) EXPECT_EQ(m.coords[3 * v], 0.0);
  for (long long v : m.node_sets.at("x1")) EXPECT_EQ(m.coords[3 * v], 1.0);
  EXPECT_EQ(m.node_sets.at("solid").size(), 45u);
}

TEST(GmshReader, ReversedCellIsReoriented) {
  // Element 2 lists (0,0), (0,1), (1,1): clockwise.
  const std::string path = write_text(
      "reversed.msh", kHeader + kFourNodes + "$Elements\n1 2 1 2\n2 1 2 2\n1 1 2 3\n2 1 4 3\n$EndElements\n");
  const MeshData m = read_gmsh_msh4(path, 2);
  ASSERT_EQ(m.num_cells(), 2u);
  expect_positive_orientation(m);
  EXPECT_NEAR(bfemp::total_measure(m), 1.0, 1e-15);
  EXPECT_TRUE(m.node_sets.empty());
}

TEST(GmshReader, DegenerateCellRejected) {
  const std::string path = write_text(
      "degenerate.msh",
      kHeader +
          "$Nodes\n1 4 1 4\n2 1 0 4\n1\n2\n3\n4\n0 0 0\n1 0 0\n1 1 0\n2 0 0\n$EndNodes\n"
          "$Elements\n1 2 1 2\n2 1 2 2\n1 1 2 3\n2 1 2 4\n$EndElements\n");
  const std::string msg = error_of(path, 2);
  EXPECT_NE(msg.find("degenerate"), std::string::npos) << msg;
  EXPECT_NE(msg.find("inverted or degenerate element 1 in mesh '" + path + "'"), std::string::npos)
      << msg;
}

TEST(GmshReader, TagsCompactedAndUnusedNodesDropped) {
  // Node tags 10..50; node 50 (a physical point) is used by no triangle.
  const std::string path = write_text(
      "sparse_tags.msh",
      kHeader +
          "$PhysicalNames\n2\n0 7 \"lonely\"\n1 8 \"base\"\n$EndPhysicalNames\n"
          "$Entities\n1 1 1 0\n5 3 3 0 1 7\n1 0 0 0 1 0 0 1 8 0\n1 0 0 0 1 1 0 0 0\n$EndEntities\n"
          "$Nodes\n2 5 10 50\n2 1 0 4\n10\n20\n30\n40\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n"
          "0 5 0 1\n50\n3 3 0\n$EndNodes\n"
          "$Comments\nanything $Nodes here is skipped\n$EndComments\n"
          "$Elements\n3 4 1 4\n0 5 15 1\n1 50\n1 1 1 1\n2 10 20\n2 1 2 2\n3 10 20 30\n4 10 30 40\n"
          "$EndElements\n");
  const MeshData m = read_gmsh_msh4(path, 2);
  EXPECT_EQ(m.num_nodes(), 4u);
  EXPECT_EQ(m.num_cells(), 2u);
  for (long long v : m.cells) EXPECT_LT(v, 4);
  EXPECT_TRUE(m.node_sets.at("lonely").empty());
  const auto& base = m.node_sets.at("base");
  ASSERT_EQ(base.size(), 2u);
  for (long long v : base) EXPECT_EQ(m.coords[2 * v + 1], 0.0);
}

TEST(GmshReader, MissingFileNamesPath) {
  const std::string path = scratch("does_not_exist.msh");
  const std::string msg = error_of(path, 2);
  EXPECT_NE(msg.find("'" + path + "'"), std::string::npos) << msg;
  EXPECT_NE(msg.find("cannot open"), std::string::npos) << msg;
}

TEST(GmshReader, Msh22Rejected) {
  const std::string path = write_text(
      "old.msh", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n3\n1 0 0 0\n2 1 0 0\n3 0 1 0\n"
                 "$EndNodes\n$Elements\n1\n1 2 2 0 1 1 2 3\n$EndElements\n");
  const std::string msg = error_of(path, 2);
  EXPECT_NE(msg.find("expected MSH 4.1 ASCII"), std::string::npos) << msg;
  EXPECT_NE(msg.find("2.2"), std::string::npos) << msg;
}

TEST(GmshReader, BinaryRejected) {
  const std::string path = write_text("binary.msh", "$MeshFormat\n4.1 1 8\n\x01\0\0\0\n$EndMeshFormat\n");
  EXPECT_NE(error_of(path, 2).find("expected MSH 4.1 ASCII"), std::string::npos);
}

TEST(GmshReader, TruncatedFileRejected) {
  const std::string full = slurp(data_path("square_tri.msh"));
  const std::size_t cuts[] = {full.size() / 2, full.find("$EndElements"), full.find("$Elements"),
                              full.find("$EndNodes") - 5};
  for (std::size_t cut : cuts) {
    const std::string path = write_text("truncated.msh", full.substr(0, cut));
    const std::string msg = error_of(path, 2);
    EXPECT_NE(msg.find(path), std::string::npos) << "cut at " << cut << ": " << msg;
    EXPECT_NE(msg.find("truncated"), std::string::npos) << "cut at " << cut << ": " << msg;
  }
}

TEST(GmshReader, WrongDimensionAndGarbage) {
  std::string msg = error_of(data_path("square_tri.msh"), 3);
  EXPECT_NE(msg.find("no 4-node tetrahedron (type 4)"), std::string::npos) << msg;
  EXPECT_THROW(read_gmsh_msh4(data_path("square_tri.msh"), 1), std::invalid_argument);
  const std::string path = write_text(
      "garbage.msh", kHeader + "$Nodes\n1 4 1 4\n2 1 0 4\n1\n2\nthree\n$EndNodes\n");
  msg = error_of(path, 2);
  EXPECT_NE(msg.find("line 9: expected an integer (node tag), found 'three'"), std::string::npos)
      << msg;
  const std::string unknown = write_text(
      "unknown_node.msh", kHeader + kFourNodes + "$Elements\n1 1 1 1\n2 1 2 1\n1 1 2 9\n$EndElements\n");
  msg = error_of(unknown, 2);
  EXPECT_NE(msg.find("unknown node tag 9"), std::string::npos) << msg;
}

// Structured n x n grid of the unit square (2 (n-1)^2 triangles), written as
// one MSH 4.1 node block and one element block.
TEST(GmshReader, LargeStructuredGrid) {
  const int n = 317;  // ~1e5 nodes
  std::string text = kHeader + "$Nodes\n1 " + std::to_string(n * n) + " 1 " +
                     std::to_string(n * n) + "\n2 1 0 " + std::to_string(n * n) + "\n";
  for (int i = 1; i <= n * n; ++i) text += std::to_string(i) + "\n";
  char buf[96];
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      std::snprintf(buf, sizeof buf, "%.17g %.17g 0\n", double(i) / (n - 1), double(j) / (n - 1));
      text += buf;
    }
  const int ne = 2 * (n - 1) * (n - 1);
  text += "$EndNodes\n$Elements\n1 " + std::to_string(ne) + " 1 " + std::to_string(ne) +
          "\n2 1 2 " + std::to_string(ne) + "\n";
  int tag = 0;
  for (int j = 0; j + 1 < n; ++j)
    for (int i = 0; i + 1 < n; ++i) {
      const int a = j * n + i + 1, b = a + 1, c = a + n + 1, d = a + n;
      const int t1 = ++tag, t2 = ++tag;
      text += std::to_string(t1) + " " + std::to_string(a) + " " + std::to_string(b) + " " +
              std::to_string(c) + "\n" + std::to_string(t2) + " " + std::to_string(a) + " " +
              std::to_string(d) + " " + std::to_string(c) + "\n";  // second one clockwise
    }
  text += "$EndElements\n";
  const std::string path = write_text("large.msh", text);
  const auto start = std::chrono::steady_clock::now();
  const MeshData m = read_gmsh_msh4(path, 2);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("read %zu nodes, %zu cells in %.3f s\n", m.num_nodes(), m.num_cells(), seconds);
  EXPECT_EQ(m.num_nodes(), std::size_t(n) * n);
  EXPECT_EQ(m.num_cells(), std::size_t(ne));
  EXPECT_NEAR(bfemp::total_measure(m), 1.0, 1e-12);
  expect_positive_orientation(m);
}

}  // namespace
