#pragma once
// All FEM bodies of a scene concatenated into one simplex mesh on Kokkos
// Views: connectivity, rest shape (inverse edge matrices, volumes), lumped
// masses and per-element materials. Built once; read by the kernels.
#include <string>
#include <vector>

#include "core/types.hpp"
#include "io/mesh_data.hpp"
#include "materials/material.hpp"

namespace bfemp {

template <int dim>
struct FemMesh {
  static constexpr int nv = dim + 1;  // vertices per simplex
  Kokkos::View<LO* [nv], MemSpace> cells;
  Kokkos::View<double* [dim][dim], MemSpace> Dm_inv;  // inverse rest edge matrix
  Kokkos::View<double*, MemSpace> rest_volume;
  Kokkos::View<int*, MemSpace> material;               // index into `materials`
  Kokkos::View<MaterialParams*, MemSpace> materials;
  Kokkos::View<double*, MemSpace> node_mass;           // lumped, per node
  Kokkos::View<double*, MemSpace> rest_position;       // node-interleaved, n*dim

  // Host bookkeeping per body (node and element ranges, names).
  struct BodyRange { std::string name; LO first_node, num_nodes, first_cell, num_cells; };
  std::vector<BodyRange> bodies;

  LO num_nodes() const { return static_cast<LO>(node_mass.extent(0)); }
  LO num_cells() const { return static_cast<LO>(cells.extent(0)); }
};

struct FemBodyInput {
  std::string name;
  MeshData mesh;
  int material_index = 0;
};

// Concatenates the bodies; throws std::invalid_argument naming the body and
// element if a rest element is inverted or degenerate.
template <int dim>
FemMesh<dim> build_fem_mesh(const std::vector<FemBodyInput>& bodies,
                            const std::vector<MaterialParams>& materials);

}  // namespace bfemp
