#include "io/xdmf_writer.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <set>
#include <stdexcept>
#include <utility>

#include "io/atomic_file.hpp"
#include "io/hdf5_frames.hpp"

namespace bfemp {

XdmfGrid xdmf_particle_grid(int index, std::size_t num_particles, int dim) {
  XdmfGrid g;
  g.name = "particles";
  g.group = Hdf5FrameWriter::frame_group_name(index);
  g.topology = {"Polyvertex", num_particles, 1, "/mesh/particle_vertices"};
  g.num_nodes = num_particles;
  g.dim = dim;
  g.geometry = "particle_positions";
  return g;
}
namespace {

std::string escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

// Shortest of %.15g/%.16g/%.17g that reads back to the same double.
std::string exact(double v) {
  char buf[40];
  for (int digits = 15; digits <= 17; ++digits) {
    std::snprintf(buf, sizeof buf, "%.*g", digits, v);
    if (std::strtod(buf, nullptr) == v) break;
  }
  return buf;
}

[[noreturn]] void bad(const std::string& xdmf, const std::string& grid, const std::string& what) {
  throw std::invalid_argument("XDMF file '" + xdmf + "', grid '" + grid + "': " + what);
}

std::string attribute_type(int components) {
  switch (components) {
    case 1: return "Scalar";
    case 2:
    case 3: return "Vector";
    case 6: return "Tensor6";
    case 9: return "Tensor";
    default: return "Matrix";
  }
}

class GridRenderer {
 public:
  GridRenderer(const std::string& xdmf, const std::string& h5) : xdmf_(xdmf), h5_(h5) {}

  std::string render(const XdmfGrid& g, const std::string& indent, const std::string& time_xml) {
    validate(g);
    const XdmfTopology& t = g.topology;
    std::string s = indent + "<Grid Name=\"" + escape(g.name) + "\" GridType=\"Uniform\">\n";
    const std::string in = indent + "  ";
    s += time_xml.empty() ? "" : in + time_xml + "\n";
    s += in + "<Topology TopologyType=\"" + t.type + "\" NumberOfElements=\"" +
         std::to_string(t.num_cells) + "\" NodesPerElement=\"" +
         std::to_string(t.nodes_per_cell) + "\"";
    if (t.dataset.empty()) {
      s += "/>\n";
    } else {
      s += ">\n" + data_item(g, t.dataset, t.num_cells, t.nodes_per_cell, true, in + "  ") +
           in + "</Topology>\n";
    }
    s += in + "<Geometry GeometryType=\"" + (g.dim == 2 ? "XY" : "XYZ") + "\">\n" +
         data_item(g, g.geometry, g.num_nodes, g.dim, false, in + "  ") + in + "</Geometry>\n";
    for (const XdmfAttribute& a : g.node_attributes) s += attribute(g, a, "Node", g.num_nodes, in);
    for (const XdmfAttribute& a : g.cell_attributes) s += attribute(g, a, "Cell", t.num_cells, in);
    return s + indent + "</Grid>\n";
  }

 private:
  void validate(const XdmfGrid& g) const {
    const XdmfTopology& t = g.topology;
    if (g.name.empty()) bad(xdmf_, g.name, "empty grid name");
    const int expected_npc = t.type == "Triangle" ? 3 : t.type == "Tetrahedron" ? 4
                           : t.type == "Polyvertex" ? 1 : 0;
    if (expected_npc == 0)
      bad(xdmf_, g.name, "topology type '" + t.type + "', expected Triangle, Tetrahedron or Polyvertex");
    if (t.nodes_per_cell != expected_npc)
      bad(xdmf_, g.name, "nodes_per_cell = " + std::to_string(t.nodes_per_cell) + ", expected " +
                             std::to_string(expected_npc) + " for " + t.type);
    if (g.dim != 2 && g.dim != 3)
      bad(xdmf_, g.name, "dim = " + std::to_string(g.dim) + ", expected 2 or 3");
    if (t.type == "Tetrahedron" && g.dim != 3) bad(xdmf_, g.name, "Tetrahedron topology needs dim = 3");
    if (t.dataset.empty() && t.type != "Polyvertex")
      bad(xdmf_, g.name, "empty topology dataset, required for " + t.type);
    if (t.dataset.empty() && t.num_cells != g.num_nodes)
      bad(xdmf_, g.name, "Polyvertex without connectivity needs num_cells (" +
                             std::to_string(t.num_cells) + ") == num_nodes (" +
                             std::to_string(g.num_nodes) + ")");
    std::set<std::string> names;
    for (const auto* list : {&g.node_attributes, &g.cell_attributes})
      for (const XdmfAttribute& a : *list) {
        if (a.name.empty() || !names.insert(a.name).second)
          bad(xdmf_, g.name, "attribute name '" + a.name + "' empty or repeated");
        if (a.components < 1)
          bad(xdmf_, g.name, "attribute '" + a.name + "' components = " +
                                 std::to_string(a.components) + ", expected >= 1");
      }
  }

  std::string resolve(const XdmfGrid& g, const std::string& dataset) const {
    if (dataset.empty()) bad(xdmf_, g.name, "empty dataset name");
    if (dataset[0] == '/') return dataset;
    if (g.group.empty() || g.group[0] != '/')
      bad(xdmf_, g.name, "dataset '" + dataset + "' is relative but group '" + g.group +
                             "' is not an absolute HDF5 path");
    return g.group + (g.group.back() == '/' ? "" : "/") + dataset;
  }

  std::string data_item(const XdmfGrid& g, const std::string& dataset, std::size_t rows,
                        int cols, bool integer, const std::string& indent) const {
    const std::string dims = std::to_string(rows) + (cols == 1 ? "" : " " + std::to_string(cols));
    return indent + "<DataItem Dimensions=\"" + dims + "\" NumberType=\"" +
           (integer ? "Int" : "Float") + "\" Precision=\"8\" Format=\"HDF\">" +
           escape(h5_) + ":" + escape(resolve(g, dataset)) + "</DataItem>\n";
  }

  std::string attribute(const XdmfGrid& g, const XdmfAttribute& a, const char* center,
                        std::size_t rows, const std::string& indent) const {
    return indent + "<Attribute Name=\"" + escape(a.name) + "\" AttributeType=\"" +
           attribute_type(a.components) + "\" Center=\"" + center + "\">\n" +
           data_item(g, a.dataset, rows, a.components, a.integer, indent + "  ") + indent +
           "</Attribute>\n";
  }

  const std::string& xdmf_;
  const std::string& h5_;
};

}  // namespace

XdmfSeriesWriter::XdmfSeriesWriter(std::string xdmf_path, std::string h5_name)
    : xdmf_path_(std::move(xdmf_path)), h5_name_(std::move(h5_name)) {
  if (h5_name_.empty())
    throw std::invalid_argument("XDMF file '" + xdmf_path_ + "': empty HDF5 file name");
}

void XdmfSeriesWriter::add_frame(const XdmfFrame& frame, bool write) {
  const std::string frame_name = "frame_" + std::to_string(frames_.size());
  if (!std::isfinite(frame.time))
    bad(xdmf_path_, frame_name, "time = " + exact(frame.time) + ", expected a finite value");
  if (frame.grids.empty()) bad(xdmf_path_, frame_name, "frame without grids");
  std::set<std::string> names;
  for (const XdmfGrid& g : frame.grids)
    if (!names.insert(g.name).second) bad(xdmf_path_, g.name, "grid name repeated in one frame");

  GridRenderer renderer(xdmf_path_, h5_name_);
  const std::string time_xml = "<Time Value=\"" + exact(frame.time) + "\"/>";
  const std::string indent = "      ";
  std::string xml;
  if (frame.grids.size() == 1) {
    xml = renderer.render(frame.grids[0], indent, time_xml);
  } else {
    xml = indent + "<Grid Name=\"" + frame_name +
          "\" GridType=\"Collection\" CollectionType=\"Spatial\">\n" + indent + "  " +
          time_xml + "\n";
    for (const XdmfGrid& g : frame.grids) xml += renderer.render(g, indent + "  ", "");
    xml += indent + "</Grid>\n";
  }
  frames_.push_back(std::move(xml));
  if (!write) return;
  try {
    write_file_atomically(xdmf_path_, render());
  } catch (...) {
    frames_.pop_back();
    throw;
  }
}

void XdmfSeriesWriter::write() const { write_file_atomically(xdmf_path_, render()); }

std::string XdmfSeriesWriter::render() const {
  std::string s =
      "<?xml version=\"1.0\" ?>\n"
      "<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n"
      "<Xdmf Version=\"3.0\" xmlns:xi=\"http://www.w3.org/2001/XInclude\">\n"
      "  <Domain>\n"
      "    <Grid Name=\"TimeSeries\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
  for (const std::string& f : frames_) s += f;
  return s + "    </Grid>\n  </Domain>\n</Xdmf>\n";
}

}  // namespace bfemp
