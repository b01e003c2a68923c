#pragma once
// The FEM boundary as the contact primitives of paper Eqs. 31-32. Facets are
// the simplex faces that belong to one element only (edges in 2D, triangles
// in 3D). The max over facets of Eq. 30 is replaced by a sum with duplicate
// compensation (Li et al.):
//   2D: + b(point-edge) per boundary edge, - (eta_k - 1) b(point-point) per
//       boundary node k (eta_k = boundary edges at k);
//   3D: + b(point-triangle) per boundary triangle, - (eta_e - 1)
//       b(point-edge) per boundary edge (eta_e = boundary triangles at e),
//       + c_v b(point-point) per boundary node with
//       c_v = 1 - T_v + sum_{e at v} (eta_e - 1) (T_v: triangles at v),
//       which is 1 on a closed surface and 0 at the rim of an open one.
// Primitives with a zero coefficient are dropped. Node ids are FEM node ids,
// which are also system node ids (the FEM nodes come first).
#include <Kokkos_Core.hpp>

#include "fem/fem_mesh.hpp"

namespace bfemp {

template <int dim>
struct BoundaryPrimitives {
  // Vertices of primitive j: nodes(j, 0 .. count(j)-1); unused slots repeat
  // nodes(j, 0) so that bounding boxes can loop over all dim slots.
  Kokkos::View<LO* [dim], MemSpace> nodes;
  Kokkos::View<int*, MemSpace> count;      // 1 point, 2 edge, 3 triangle
  Kokkos::View<double*, MemSpace> coef;    // +1 facets; compensation terms
  Kokkos::View<int*, MemSpace> body;       // FEM body index
  LO num_facets = 0;                       // primitives with count == dim
  LO size() const { return static_cast<LO>(count.extent(0)); }
};

template <int dim>
BoundaryPrimitives<dim> boundary_primitives(const FemMesh<dim>& mesh);

}  // namespace bfemp
