#pragma once
// Reader for Gmsh MSH 4.1 ASCII meshes (plain parser, does not use libgmsh).
#include <string>

#include "core/mesh_data.hpp"

namespace bfemp {

// Reads the simplex cells of dimension `dim` from a Gmsh MSH 4.1 ASCII file:
// 3-node triangles (element type 2) for dim = 2, 4-node tetrahedra (type 4) for
// dim = 3; every other element type only contributes to node sets. For dim = 2
// the z coordinate is dropped.
//
// Sections read: $MeshFormat, $PhysicalNames, $Entities, $Nodes, $Elements;
// any other $Section ... $EndSection is skipped. Every physical group (of any
// dimension) becomes a node set named after its $PhysicalNames entry, or
// "physical_<dim>_<tag>" when it has no name; its nodes are those of all the
// elements on the entities carrying that physical tag.
//
// The result satisfies the MeshData invariants (see finalize_mesh): positive
// orientation, compact numbering of the nodes used by cells, sorted sets.
//
// Throws std::invalid_argument for dim not 2/3, std::runtime_error naming the
// file (and line) for: unreadable file, other MSH versions or binary files
// ("expected MSH 4.1 ASCII"), malformed or truncated sections, unknown node
// tags, no cells of the requested type, degenerate cells.
MeshData read_gmsh_msh4(const std::string& path, int dim);

}  // namespace bfemp
