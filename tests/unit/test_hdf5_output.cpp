// Hdf5FrameWriter + XdmfSeriesWriter + write_file_atomically.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "io/atomic_file.hpp"
#include "io/hdf5_frames.hpp"
#include "io/xdmf_writer.hpp"

namespace {

namespace fs = std::filesystem;
using namespace bfemp;

std::string scratch(const std::string& name) {
  const std::string dir = std::string(BFEMP_BINARY_DIR) + "/test_scratch/hdf5_output";
  fs::create_directories(dir);
  return dir + "/" + name;
}

std::string slurp(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t p = text.find(what); p != std::string::npos; p = text.find(what, p + 1)) ++n;
  return n;
}

// Balanced tags (ignoring <? ?> and <! >), so the file is well-formed XML-ish.
bool tags_balanced(const std::string& xml) {
  std::vector<std::string> open;
  const std::regex tag("<(/?)([A-Za-z_][A-Za-z0-9_:.-]*)[^>]*?(/?)>");
  for (auto it = std::sregex_iterator(xml.begin(), xml.end(), tag); it != std::sregex_iterator();
       ++it) {
    const std::smatch& m = *it;
    if (m[1] == "/") {
      if (open.empty() || open.back() != m[2].str()) return false;
      open.pop_back();
    } else if (m[3] != "/") {
      open.push_back(m[2]);
    }
  }
  return open.empty();
}

// Test data: frame f, n nodes in 2D, 2 triangles.
struct FrameData {
  std::vector<double> positions, velocities, pressure;
  std::vector<long long> ids;
  FrameData(int f, int n) {
    for (int i = 0; i < n; ++i) {
      positions.push_back(i + 0.1 * f);
      positions.push_back(-i / 3.0 + f);
      velocities.push_back(std::sqrt(2.0) * f + i);
      velocities.push_back(1e-300 * i - f);
      ids.push_back(1000000000000LL * f + i);
    }
    pressure = {f / 7.0, -f / 11.0};
  }
};

const std::vector<long long> kCells = {0, 1, 2, 0, 2, 3};
const double kTimes[3] = {0.0, 0.1, 0.30000000000000004};

void check_frame(const std::string& file, int f) {
  const std::string g = Hdf5FrameWriter::frame_group_name(f);
  const FrameData d(f, 4);
  std::vector<std::size_t> shape;
  EXPECT_EQ(read_dataset(file, g + "/positions", &shape), d.positions);
  EXPECT_EQ(shape, (std::vector<std::size_t>{4, 2}));
  EXPECT_EQ(read_dataset(file, g + "/velocity", &shape), d.velocities);
  EXPECT_EQ(read_dataset(file, g + "/pressure", &shape), d.pressure);
  EXPECT_EQ(shape, (std::vector<std::size_t>{2}));
  EXPECT_EQ(read_dataset_int(file, g + "/ids", &shape), d.ids);
  EXPECT_EQ(read_attribute(file, g, "time"), kTimes[f]);
  EXPECT_EQ(read_attribute(file, g, "step"), 10.0 * f + 1);
  EXPECT_EQ(read_attribute(file, g, "index"), f);
}

void write_frame(Hdf5FrameWriter& w, int f) {
  const FrameData d(f, 4);
  w.begin_frame(f, kTimes[f], 10L * f + 1);
  w.write_array("positions", d.positions.data(), 4, 2);
  w.write_array("velocity", d.velocities.data(), 4, 2);
  w.write_array("pressure", d.pressure.data(), 2, 1);
  w.write_array("ids", d.ids.data(), 4, 1);
  w.end_frame();
}

TEST(Hdf5Frames, WritesThreeFramesReadableWhileOpen) {
  const std::string file = scratch("frames.h5");
  const std::string snapshot = scratch("frames_snapshot.h5");
  {
    Hdf5FrameWriter w(file);
    w.write_static("cells", kCells.data(), 2, 3);
    for (int f = 0; f < 3; ++f) {
      write_frame(w, f);
      // A byte copy of the file as it is on disk now must be a complete file.
      fs::copy_file(file, snapshot, fs::copy_options::overwrite_existing);
      for (int g = 0; g <= f; ++g) check_frame(snapshot, g);
      EXPECT_FALSE(dataset_exists(snapshot, Hdf5FrameWriter::frame_group_name(f + 1) + "/positions"));
      // A second, read-only handle on the live file.
      check_frame(file, f);
    }
  }
  std::vector<std::size_t> shape;
  EXPECT_EQ(read_dataset_int(file, "/mesh/cells", &shape), kCells);
  EXPECT_EQ(shape, (std::vector<std::size_t>{2, 3}));
  for (int f = 0; f < 3; ++f) check_frame(file, f);
}

TEST(Hdf5Frames, MisuseThrowsWithNames) {
  const std::string file = scratch("misuse.h5");
  Hdf5FrameWriter w(file);
  const double x[2] = {1, 2};
  try {
    w.write_array("orphan", x, 2, 1);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("'orphan'"), std::string::npos) << e.what();
  }
  w.begin_frame(3, 0.5, 7);
  EXPECT_THROW(w.begin_frame(4, 0.6, 8), std::runtime_error);
  w.write_array("x", x, 2, 1);
  try {
    w.write_array("x", x, 2, 1);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("'/frame_000003/x' already exists"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find(file), std::string::npos) << e.what();
  }
  EXPECT_THROW(w.write_array("a/b", x, 2, 1), std::invalid_argument);
  EXPECT_THROW(w.write_array("y", x, 2, 0), std::invalid_argument);
  w.end_frame();
  EXPECT_THROW(w.end_frame(), std::runtime_error);
  EXPECT_THROW(w.begin_frame(3, 0.7, 9), std::runtime_error);  // group exists
  EXPECT_THROW(w.begin_frame(-1, 0.7, 9), std::invalid_argument);
  w.close();
  EXPECT_EQ(read_dataset(file, "/frame_000003/x", nullptr), std::vector<double>({1, 2}));

  const std::string bad = scratch("no_such_dir/out.h5");
  try {
    Hdf5FrameWriter broken(bad);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("'" + bad + "': cannot create file"), std::string::npos)
        << e.what();
  }
  try {
    read_dataset(file, "/frame_000003/missing", nullptr);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("'/frame_000003/missing'"), std::string::npos);
  }
}

XdmfGrid fem_grid(int f, bool two_d) {
  XdmfGrid g;
  g.name = "fem";
  g.group = Hdf5FrameWriter::frame_group_name(f);
  g.topology = {"Triangle", 2, 3, "/mesh/cells"};
  g.num_nodes = 4;
  g.dim = two_d ? 2 : 3;
  g.node_attributes = {{"velocity", "velocity", 2}, {"ids", "ids", 1, true}};
  g.cell_attributes = {{"pressure", "pressure", 1}};
  return g;
}

// Every "frames.h5:/path" reference in the XDMF names a dataset in the file.
void expect_references_exist(const std::string& xml, const std::string& h5_name,
                             const std::string& h5_path, std::size_t expected) {
  const std::regex ref(">" + h5_name + ":(/[^<]+)</DataItem>");
  std::size_t n = 0;
  for (auto it = std::sregex_iterator(xml.begin(), xml.end(), ref); it != std::sregex_iterator();
       ++it, ++n)
    EXPECT_TRUE(dataset_exists(h5_path, (*it)[1].str())) << (*it)[1].str();
  EXPECT_EQ(n, expected);
}

TEST(XdmfSeries, RewrittenAfterEachFrame) {
  const std::string h5 = scratch("series.h5"), xdmf = scratch("series.xdmf");
  fs::remove(xdmf);
  Hdf5FrameWriter w(h5);
  w.write_static("cells", kCells.data(), 2, 3);
  XdmfSeriesWriter x(xdmf, "series.h5");
  for (int f = 0; f < 3; ++f) {
    write_frame(w, f);
    x.add_frame({kTimes[f], {fem_grid(f, true)}});
    ASSERT_TRUE(fs::exists(xdmf));
    EXPECT_FALSE(fs::exists(xdmf + ".tmp"));
    const std::string xml = slurp(xdmf);
    EXPECT_EQ(xml, x.render());
    EXPECT_TRUE(tags_balanced(xml)) << xml;
    EXPECT_EQ(count(xml, "CollectionType=\"Temporal\""), 1u);
    EXPECT_EQ(count(xml, "GridType=\"Uniform\""), std::size_t(f + 1));
    EXPECT_EQ(count(xml, "<Time "), std::size_t(f + 1));
    EXPECT_EQ(count(xml, "GeometryType=\"XY\""), std::size_t(f + 1));
    for (int g = 0; g <= f; ++g) {
      std::ostringstream t;
      t << "<Time Value=\"" << (g == 0 ? "0" : g == 1 ? "0.1" : "0.30000000000000004") << "\"/>";
      EXPECT_EQ(count(xml, t.str()), 1u) << t.str();
    }
    EXPECT_NE(xml.find("AttributeType=\"Vector\" Center=\"Node\""), std::string::npos);
    EXPECT_EQ(count(xml, "NumberType=\"Int\""), 2u * (f + 1));  // cells and ids
    EXPECT_NE(xml.find("Name=\"pressure\" AttributeType=\"Scalar\" Center=\"Cell\""),
              std::string::npos);
    // topology + geometry + 3 attributes per frame
    expect_references_exist(xml, "series.h5", h5, 5u * (f + 1));
  }
}

TEST(XdmfSeries, SpatialCollectionWithParticles) {
  const std::string h5 = scratch("mixed.h5"), xdmf = scratch("mixed.xdmf");
  Hdf5FrameWriter w(h5);
  w.write_static("cells", kCells.data(), 2, 3);
  XdmfSeriesWriter x(xdmf, "mixed.h5");
  const std::vector<double> particles = {0, 0, 0, 1, 1, 1, 2, 2, 2};
  const std::vector<double> mass = {1, 2, 3};
  for (int f = 0; f < 2; ++f) {
    const FrameData d(f, 4);
    std::vector<double> p3;
    for (int i = 0; i < 4; ++i) p3.insert(p3.end(), {d.positions[2 * i], d.positions[2 * i + 1], 0.0});
    w.begin_frame(f, kTimes[f], f);
    w.write_array("positions", p3.data(), 4, 3);
    w.write_array("velocity", d.velocities.data(), 4, 2);
    w.write_array("ids", d.ids.data(), 4, 1);
    w.write_array("pressure", d.pressure.data(), 2, 1);
    w.write_array("particle_positions", particles.data(), 3, 3);
    w.write_array("particle_mass", mass.data(), 3, 1);
    w.end_frame();
    XdmfGrid cloud;
    cloud.name = "particles";
    cloud.group = Hdf5FrameWriter::frame_group_name(f);
    cloud.topology = {"Polyvertex", 3, 1, ""};
    cloud.num_nodes = 3;
    cloud.dim = 3;
    cloud.geometry = "particle_positions";
    cloud.node_attributes = {{"mass", "particle_mass", 1}};
    x.add_frame({kTimes[f], {fem_grid(f, false), cloud}});
  }
  const std::string xml = slurp(xdmf);
  EXPECT_TRUE(tags_balanced(xml)) << xml;
  EXPECT_EQ(count(xml, "CollectionType=\"Spatial\""), 2u);
  EXPECT_EQ(count(xml, "GridType=\"Uniform\""), 4u);
  EXPECT_EQ(count(xml, "TopologyType=\"Polyvertex\" NumberOfElements=\"3\""), 2u);
  EXPECT_EQ(count(xml, "<Time "), 2u);
  expect_references_exist(xml, "mixed.h5", h5, 2u * (5 + 2));

  XdmfGrid broken = fem_grid(0, true);
  broken.topology.type = "Hexahedron";
  EXPECT_THROW(x.add_frame({1.0, {broken}}), std::invalid_argument);
  EXPECT_THROW(x.add_frame({1.0, {fem_grid(0, true), fem_grid(0, true)}}), std::invalid_argument);
  EXPECT_THROW(x.add_frame({1.0, {}}), std::invalid_argument);
  EXPECT_EQ(x.num_frames(), 2u);
  EXPECT_EQ(slurp(xdmf), xml);
}

TEST(XdmfAtomicFile, ReplacesWholeFile) {
  const std::string path = scratch("atomic.txt");
  write_file_atomically(path, "first version, rather long\n");
  write_file_atomically(path, "second\n");
  EXPECT_EQ(slurp(path), "second\n");
  EXPECT_FALSE(fs::exists(path + ".tmp"));
  try {
    write_file_atomically(scratch("no_such_dir/x.txt"), "x");
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no_such_dir/x.txt"), std::string::npos) << e.what();
  }
}

}  // namespace
