#include "io/shape_mesher.hpp"

#include <gmsh.h>

#include <algorithm>
#include <cmath>
#include <exception>
#include <sstream>
#include <stdexcept>
#include <unordered_map>

namespace bfemp {
namespace {

constexpr double kPi = 3.14159265358979323846;

std::string fmt(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

[[noreturn]] void bad(const std::string& field, const std::string& value,
                      const std::string& expected) {
  throw std::invalid_argument("shape field '" + field + "' = " + value + ": expected " + expected);
}

void require_positive(const std::string& field, double v) {
  if (!(v > 0.0) || !std::isfinite(v)) bad(field, fmt(v), "a finite value > 0");
}

int shape_dim(const std::string& kind) {
  if (kind == "rectangle" || kind == "disk" || kind == "ring" || kind == "half-ring") return 2;
  if (kind == "box" || kind == "spherical-shell") return 3;
  bad("kind", "'" + kind + "'",
      "one of rectangle, box, disk, ring, half-ring, spherical-shell");
}

// Checks every field the kind uses; returns the area/volume of the exact shape.
double validate(const ShapeSpec& s, int dim) {
  if (dim != 2 && dim != 3) bad("dim", std::to_string(dim), "2 or 3");
  if (shape_dim(s.kind) != dim)
    bad("kind", "'" + s.kind + "'", "a " + std::to_string(dim) + "D shape (it is " +
                                        std::to_string(shape_dim(s.kind)) + "D)");
  if (!s.center.empty() && s.center.size() != static_cast<std::size_t>(dim))
    bad("center", std::to_string(s.center.size()) + " entries", std::to_string(dim) + " entries");
  for (double c : s.center)
    if (!std::isfinite(c)) bad("center", fmt(c), "finite coordinates");
  require_positive("element_size", s.element_size);
  double measure = 0.0;
  if (s.kind == "rectangle" || s.kind == "box") {
    if (s.size.size() != static_cast<std::size_t>(dim))
      bad("size", std::to_string(s.size.size()) + " entries", std::to_string(dim) + " entries");
    measure = 1.0;
    for (std::size_t i = 0; i < s.size.size(); ++i) {
      require_positive("size[" + std::to_string(i) + "]", s.size[i]);
      measure *= s.size[i];
    }
  } else {
    require_positive("outer_radius", s.outer_radius);
    const double R = s.outer_radius, r = s.inner_radius;
    if (s.kind == "disk") {
      measure = kPi * R * R;
    } else {
      require_positive("inner_radius", r);
      if (r >= R) bad("inner_radius", fmt(r), "< outer_radius = " + fmt(R));
      measure = s.kind == "spherical-shell" ? 4.0 / 3.0 * kPi * (R * R * R - r * r * r)
                                            : kPi * (R * R - r * r);
      if (s.kind == "half-ring") measure *= 0.5;
    }
  }
  const double cells_estimate = measure / std::pow(s.element_size, dim) * (dim == 2 ? 2.3 : 6.0);
  if (cells_estimate > 5e7)
    bad("element_size", fmt(s.element_size),
        "a larger value (about " + fmt(cells_estimate) + " cells would be generated)");
  return measure;
}

// One Gmsh session, finalized on scope exit even if meshing throws.
class GmshSession {
 public:
  GmshSession() {
    gmsh::initialize(0, nullptr, false);
    gmsh::option::setNumber("General.Terminal", 0);
    gmsh::option::setNumber("General.Verbosity", 0);
    gmsh::model::add("bfemp_shape");
  }
  ~GmshSession() {
    try {
      gmsh::finalize();
    } catch (...) {
    }
  }
  GmshSession(const GmshSession&) = delete;
  GmshSession& operator=(const GmshSession&) = delete;
};

void build_geometry(const ShapeSpec& s, const double c[3]) {
  namespace occ = gmsh::model::occ;
  gmsh::vectorpair out;
  std::vector<gmsh::vectorpair> out_map;
  const double R = s.outer_radius, r = s.inner_radius;
  if (s.kind == "rectangle") {
    occ::addRectangle(c[0] - s.size[0] / 2, c[1] - s.size[1] / 2, 0.0, s.size[0], s.size[1]);
  } else if (s.kind == "box") {
    occ::addBox(c[0] - s.size[0] / 2, c[1] - s.size[1] / 2, c[2] - s.size[2] / 2, s.size[0],
                s.size[1], s.size[2]);
  } else if (s.kind == "disk") {
    occ::addDisk(c[0], c[1], 0.0, R, R);
  } else if (s.kind == "ring" || s.kind == "half-ring") {
    const int outer = occ::addDisk(c[0], c[1], 0.0, R, R);
    const int inner = occ::addDisk(c[0], c[1], 0.0, r, r);
    occ::cut({{2, outer}}, {{2, inner}}, out, out_map);
    if (s.kind == "half-ring") {
      const int below = occ::addRectangle(c[0] - 2 * R, c[1] - 2 * R, 0.0, 4 * R, 2 * R);
      gmsh::vectorpair ring = out;
      occ::cut(ring, {{2, below}}, out, out_map);
    }
  } else if (s.kind == "spherical-shell") {
    const int outer = occ::addSphere(c[0], c[1], c[2], R);
    const int inner = occ::addSphere(c[0], c[1], c[2], r);
    occ::cut({{3, outer}}, {{3, inner}}, out, out_map);
  }
  occ::synchronize();
}

MeshData extract_mesh(int dim) {
  std::vector<std::size_t> node_tags, elem_tags, elem_nodes;
  std::vector<double> xyz, param;
  gmsh::model::mesh::getNodes(node_tags, xyz, param, -1, -1, false, false);
  gmsh::model::mesh::getElementsByType(dim == 2 ? 2 : 4, elem_tags, elem_nodes);
  MeshData mesh;
  mesh.dim = dim;
  mesh.coords.resize(node_tags.size() * dim);
  std::unordered_map<std::size_t, long long> index;
  index.reserve(node_tags.size());
  for (std::size_t i = 0; i < node_tags.size(); ++i) {
    index.emplace(node_tags[i], static_cast<long long>(i));
    for (int k = 0; k < dim; ++k) mesh.coords[i * dim + k] = xyz[3 * i + k];
  }
  mesh.cells.reserve(elem_nodes.size());
  for (std::size_t tag : elem_nodes) {
    const auto it = index.find(tag);
    if (it == index.end())
      throw std::runtime_error("Gmsh returned an element with unknown node tag " +
                               std::to_string(tag));
    mesh.cells.push_back(it->second);
  }
  return mesh;
}

std::string describe(const ShapeSpec& s) {
  return "shape '" + s.kind + "' (element_size " + fmt(s.element_size) + ")";
}

void add_node_sets(MeshData& mesh, const ShapeSpec& s, const double c[3]) {
  const int d = mesh.dim;
  const std::size_t n = mesh.num_nodes();
  auto select = [&](const std::string& name, auto&& on_set) {
    std::vector<long long>& set = mesh.node_sets[name];
    for (std::size_t i = 0; i < n; ++i)
      if (on_set(&mesh.coords[i * d])) set.push_back(static_cast<long long>(i));
  };
  if (s.kind == "rectangle" || s.kind == "box") {
    const double extent = *std::max_element(s.size.begin(), s.size.end());
    const double tol = 1e-9 * extent;
    const char* names[3][2] = {{"left", "right"}, {"bottom", "top"}, {"back", "front"}};
    for (int k = 0; k < d; ++k)
      for (int side = 0; side < 2; ++side) {
        const double plane = c[k] + (side == 0 ? -0.5 : 0.5) * s.size[k];
        select(names[k][side], [&](const double* x) { return std::abs(x[k] - plane) <= tol; });
      }
    return;
  }
  const double tol = 1e-9 * s.outer_radius;
  auto radius = [&](const double* x) {
    double r2 = 0.0;
    for (int k = 0; k < d; ++k) r2 += (x[k] - c[k]) * (x[k] - c[k]);
    return std::sqrt(r2);
  };
  select("outer", [&](const double* x) { return std::abs(radius(x) - s.outer_radius) <= tol; });
  if (s.kind == "disk") return;
  select("inner", [&](const double* x) { return std::abs(radius(x) - s.inner_radius) <= tol; });
  if (s.kind == "half-ring")
    select("feet", [&](const double* x) { return std::abs(x[1] - c[1]) <= tol; });
}

}  // namespace

MeshData mesh_shape(const ShapeSpec& spec, int dim) {
  validate(spec, dim);
  double c[3] = {0.0, 0.0, 0.0};
  for (std::size_t i = 0; i < spec.center.size(); ++i) c[i] = spec.center[i];

  MeshData mesh;
  try {
    GmshSession session;
    build_geometry(spec, c);
    gmsh::option::setNumber("General.NumThreads", 1);
    gmsh::option::setNumber("Mesh.MeshSizeMin", spec.element_size);
    gmsh::option::setNumber("Mesh.MeshSizeMax", spec.element_size);
    gmsh::option::setNumber("Mesh.MeshSizeFromCurvature", 0);
    gmsh::model::mesh::generate(dim);
    mesh = extract_mesh(dim);
  } catch (const std::exception& e) {
    throw std::runtime_error("Gmsh failed to mesh " + describe(spec) + ": " + e.what());
  } catch (const std::string& e) {
    throw std::runtime_error("Gmsh failed to mesh " + describe(spec) + ": " + e);
  } catch (...) {
    throw std::runtime_error("Gmsh failed to mesh " + describe(spec) + " (unknown error)");
  }
  if (mesh.num_cells() == 0)
    throw std::runtime_error("Gmsh produced no cells for " + describe(spec));
  finalize_mesh(mesh, describe(spec));
  add_node_sets(mesh, spec, c);
  return mesh;
}

}  // namespace bfemp
