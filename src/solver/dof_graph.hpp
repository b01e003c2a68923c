#pragma once
// Sparsity of the node-interleaved DOF system from node couplings: DOF
// (a, c) couples with every DOF of node b for each coupled node pair (a, b).
#include <Teuchos_RCP.hpp>
#include <vector>

#include "solver/tpetra_types.hpp"

namespace bfemp {

// `keys` holds a * n_nodes + b for coupled nodes (any order, duplicates
// allowed; consumed: sorted and deduplicated in place). Every node couples
// with itself. Column map == row map == dof_map: local column ids are the
// local DOF ids. `domain_range` (default dof_map) is the one-to-one map the
// graph is completed with: an overlap (ghosted) dof_map needs the owned one.
template <int dim>
Teuchos::RCP<const Graph> build_dof_graph(std::vector<long long>& keys, LO n_nodes,
                                          const Teuchos::RCP<const Map>& dof_map,
                                          Teuchos::RCP<const Map> domain_range = Teuchos::null);

}  // namespace bfemp
