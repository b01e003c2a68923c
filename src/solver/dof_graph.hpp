#pragma once
// Sparsity of the node-interleaved DOF system from node couplings: DOF
// (a, c) couples with every DOF of node b for each coupled node pair (a, b);
// row (a, c) holds node a's columns in node order, each as dim consecutive
// DOFs (SlipConstraints and the scatter tables rely on this layout).
#include <Teuchos_RCP.hpp>
#include <vector>

#include "kernels/node_graph.hpp"
#include "solver/energy_term.hpp"
#include "solver/tpetra_types.hpp"

namespace bfemp {

// From a node graph (NodeGraphBuilder::finish: rows sorted, no repeats, the
// diagonal present). Column map == row map == dof_map: local column ids are
// the local DOF ids. `domain_range` (default dof_map) is the one-to-one map
// the graph is completed with: an overlap (ghosted) dof_map needs the owned
// one. The expansion runs on ExecSpace.
template <int dim>
Teuchos::RCP<const Graph> build_dof_graph(const NodeGraphBuilder::RowMap& node_rows,
                                          const NodeGraphBuilder::Entries& node_cols,
                                          const Teuchos::RCP<const Map>& dof_map,
                                          Teuchos::RCP<const Map> domain_range = Teuchos::null);

// From the terms' couplings: add_couplings of every term twice (count, fill).
template <int dim>
Teuchos::RCP<const Graph> build_dof_graph(const std::vector<const EnergyTerm<dim>*>& terms, LO n_nodes,
                                          const Teuchos::RCP<const Map>& dof_map,
                                          Teuchos::RCP<const Map> domain_range = Teuchos::null);

}  // namespace bfemp
