#pragma once
// Regular sampling of material points inside a shape. Candidate points are the
// sub-cell centres of the lattice dx * Z^dim aligned with the origin
// (0,...,0): with s = ppc^(1/dim) points per axis and cell, the points are
// x_d = (m_d + 1/2) dx / s for integer m_d, so particles of every body line up
// with the same background grid (grid_covering in kernels/mpm/grid.hpp uses the same
// lattice). Each kept point represents its sub-cell: volume0 = dx^dim / ppc,
// mass = density * volume0, v = 0, F = I, C = 0.
#include <functional>
#include <string>
#include <vector>

#include "core/mesh_data.hpp"
#include "kernels/mpm/particles.hpp"

namespace bfemp {

struct SamplingShape {
  // "box"        2D rectangle or 3D box: center, size (dim extents > 0);
  //              "rectangle" is accepted as a 2D synonym;
  // "disk"       2D, "sphere" 3D: center, outer_radius;
  // "ring"       2D annulus: center, inner_radius < outer_radius;
  // "half-ring"  2D, the part of the ring with y > center[1];
  // "mesh"       the closed region covered by the simplices of *mesh
  //              (mesh->dim == dim; a point in any cell, faces included);
  // "sdf"        inside where sdf(x) < 0; center and size give the bounding
  //              box that is scanned (the shape must lie inside it).
  // Analytic shapes keep points strictly inside (a point exactly on the
  // boundary is dropped).
  std::string kind;
  std::vector<double> center;  // dim entries; empty means the origin
  std::vector<double> size;    // box, sdf: full extents along each axis
  double inner_radius = 0.0;   // ring, half-ring
  double outer_radius = 0.0;   // disk, sphere, ring, half-ring
  const MeshData* mesh = nullptr;               // mesh (not owned)
  std::function<double(const double*)> sdf;     // sdf: x has dim entries
};

// Samples `shape` with ppc particles per full cell of side dx; every particle
// gets body_id and material_id. ppc must be 1, 4, 9 or 16 in 2D and 1, 8 or 27
// in 3D. Throws std::invalid_argument naming the field and its value for an
// unknown kind or one not available in dim, a center/size of the wrong length,
// non-positive or non-finite dx, density, sizes or radii, inner_radius >=
// outer_radius, a missing mesh/sdf, negative ids, a dx so small that more than
// 1e8 candidate points would be tested, and an empty result ("shape 'ring'
// with dx 0.1 produced no particles ...").
template <int dim>
Particles<dim> sample_particles(const SamplingShape& shape, double dx, int ppc, double density,
                                int body_id, int material_id);

// Rows [first, first + count) of sample_particles' result, in its order
// (count < 0: to the end), without holding the others: the shape's lattice
// is scanned whole and only the range is kept, so that each MPI rank can
// sample its own id block of a body. Throws as sample_particles does, and
// for a range that does not lie inside [0, count_particles).
template <int dim>
Particles<dim> sample_particles(const SamplingShape& shape, double dx, int ppc, double density, int body_id,
                                int material_id, long long first, long long count);

// The number of particles sample_particles keeps (the same checks of shape,
// dx and ppc, the empty result included); nothing is allocated but the
// inside flags of a mesh shape.
template <int dim>
long long count_particles(const SamplingShape& shape, double dx, int ppc);

// Whether two shapes sampled with the same dx and ppc hold a particle at the
// same place (every body is sampled on one lattice, whose points are h = dx /
// ppc^(1/dim) apart, so particles of two bodies are either at one point or at
// least h apart). On true, x (dim entries) is the first shared point, x
// fastest. Scans only the intersection of the two shapes' lattices.
template <int dim>
bool first_shared_point(const SamplingShape& a, const SamplingShape& b, double dx, int ppc, double* x);

// The first pair a < b of the shapes (in that order: a, then b) that share a
// point, the point in x; false if none. Each shape's lattice is made once,
// and a mesh shape's inside flags only for a pair whose lattices meet.
template <int dim>
bool first_overlapping_pair(const std::vector<SamplingShape>& shapes, double dx, int ppc, int& a, int& b, double* x);

// Exact area (2D) or volume (3D) of the shape: analytic for box, disk,
// sphere, ring and half-ring, total_measure(*mesh) for mesh, NaN for sdf.
// Expects a shape that sample_particles accepts.
double sampling_shape_measure(const SamplingShape& shape, int dim);

// One line for the run log, e.g.
//   "shape 'disk': 3132 particles (dx 0.02, ppc 4), volume 0.3132 (shape 0.31416, -0.31%),
//    mass 313.2"
// (the shape measure is left out for kind "sdf").
template <int dim>
std::string sampling_report(const SamplingShape& shape, const Particles<dim>& particles, double dx,
                            int ppc);

}  // namespace bfemp
