#pragma once
// An FEM mesh cut into the ranks of a communicator, and one rank's piece.
//
// Elements: recursive coordinate bisection (Zoltan2 "rcb") of the element
// centroids at rest, unit weights: equal element counts per rank and compact
// pieces, so a piece's boundary (the ghost layer) grows like its surface.
// Fewer elements than ranks (RCB cannot cut them): element e on rank e, and
// the other ranks own no element and no node, yet take part in every
// collective step.
// Nodes: a node is owned by the lowest rank holding an element that touches
// it (a node of no element: rank 0). A rank's local nodes are its owned nodes
// in ascending global id, then its ghosts (the other nodes of its elements)
// in ascending global id: the order DofSpace::set_partition expects.
//
// Every rank passes the same (replicated) mesh; the result is the same on all
// ranks except `elements`, `nodes` and `n_owned`. One rank: everything local,
// no ghosts, nodes in their global order.
#include <vector>

#include "core/types.hpp"
#include "fem/fem_mesh.hpp"
#include <Teuchos_Comm.hpp>
#include <Teuchos_RCP.hpp>

namespace bfemp {

struct FemPartition {
  std::vector<int> element_rank;  // rank of every element of the mesh
  std::vector<LO> elements;       // this rank's elements (global ids, ascending)
  std::vector<GO> nodes;          // this rank's local nodes (global ids): owned, then ghosts
  LO n_owned = 0;
};

template <int dim>
FemPartition partition_fem_mesh(const FemMesh<dim>& mesh, const Teuchos::RCP<const Teuchos::Comm<int>>& comm);

// The rank's piece: its elements with node ids renumbered to local ones,
// rest positions and (global) lumped masses of its local nodes. Bodies are
// not carried (their ranges are global).
template <int dim>
FemMesh<dim> local_fem_mesh(const FemMesh<dim>& mesh, const FemPartition& part);

}  // namespace bfemp
