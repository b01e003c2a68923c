#pragma once
// Simplex meshes of simple shapes, generated with the Gmsh C++ API
// (OpenCASCADE kernel). Each call runs its own Gmsh session
// (gmsh::initialize ... gmsh::finalize), so calls may be repeated in one
// process; they are not thread-safe and must not overlap with any other use of
// the Gmsh API in the same process.
#include <string>
#include <vector>

#include "core/mesh_data.hpp"

namespace bfemp {

struct ShapeSpec {
  // "rectangle" (2D), "box" (3D), "disk" (2D), "ring" (2D annulus),
  // "half-ring" (2D, the part of the annulus with y >= center[1]),
  // "spherical-shell" (3D).
  std::string kind;
  // dim entries; empty means the origin.
  std::vector<double> center;
  // rectangle: [width, height]; box: [a, b, c] along x, y, z. Unused otherwise.
  std::vector<double> size;
  double inner_radius = 0.0;  // ring, half-ring, spherical-shell
  double outer_radius = 0.0;  // disk, ring, half-ring, spherical-shell
  // Target edge length (Mesh.MeshSizeMin = Mesh.MeshSizeMax). 2D meshes have
  // a mean edge of ~1.0 h; Gmsh's 3D Delaunay gives a mean of ~1.15-1.3 h.
  double element_size = 0.0;
};

// Meshes `spec` with triangles (dim = 2) or tetrahedra (dim = 3); the result
// satisfies the MeshData invariants. Node sets (found by coordinate, tolerance
// 1e-9 times the shape's extent):
//   rectangle/box: "left"/"right" (x = min/max), "bottom"/"top" (y = min/max),
//                  and for box "back"/"front" (z = min/max);
//   disk: "outer"; ring, spherical-shell: "inner", "outer" (by radius);
//   half-ring: "inner", "outer", "feet" (nodes on y = center[1]).
// Throws std::invalid_argument naming the field for: unknown kind, kind not
// matching dim, center of wrong length, size of wrong length or non-positive
// entries, non-positive radii or element_size, inner_radius >= outer_radius,
// or an element_size so small that the mesh would exceed ~5e7 cells.
// Throws std::runtime_error if Gmsh fails.
MeshData mesh_shape(const ShapeSpec& spec, int dim);

}  // namespace bfemp
