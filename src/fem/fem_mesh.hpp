#pragma once
// All FEM bodies of a scene concatenated into one simplex mesh on Kokkos
// Views: connectivity, rest shape (inverse edge matrices, volumes), lumped
// masses and per-element materials. Built once; read by the kernels.
// Element e's F = sum_a x_a grad N_a^T with grad N_a from the rest shape.
#include <string>
#include <vector>

#include "core/types.hpp"
#include "kernels/deformation_energy.hpp"
#include "core/mesh_data.hpp"
#include "materials/material.hpp"

namespace bfemp {

template <int dim>
struct FemMesh {
  static constexpr int nv = dim + 1;  // vertices per simplex
  // Elements as deformation stencils: nodes = connectivity, g = rest
  // shape-function gradients, volume = rest volume.
  DeformationStencils<dim, nv> elements;
  Kokkos::View<double*, MemSpace> node_mass;      // lumped, per node
  Kokkos::View<double*, MemSpace> rest_position;  // node-interleaved, n*dim

  // Host bookkeeping per body (node and element ranges, names).
  struct BodyRange { std::string name; LO first_node, num_nodes, first_cell, num_cells; };
  std::vector<BodyRange> bodies;

  LO num_nodes() const { return static_cast<LO>(node_mass.extent(0)); }
  LO num_cells() const { return elements.size(); }
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
