#pragma once
// Sparsity of the node-interleaved DOF system: every DOF couples with every
// DOF of the nodes it shares an element with. Built once per mesh.
#include <Teuchos_RCP.hpp>

#include "fem/fem_mesh.hpp"
#include "solver/tpetra_types.hpp"

namespace bfemp {

// Graph on `dof_map` (1 rank: column map == row map, local ids == DOF ids).
template <int dim>
Teuchos::RCP<const Graph> build_dof_graph(const FemMesh<dim>& mesh,
                                          const Teuchos::RCP<const Map>& dof_map);

}  // namespace bfemp
