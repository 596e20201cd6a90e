// Distribution of a mesh read by one rank over all ranks:
//   1. rank 0 scatters the elements in blocks of the file order, and the nodes' data (coordinates,
//      tags, groups) in blocks of node ids, to a "directory" rank per block;
//   2. Zoltan2's multi-jagged partitioner assigns elements to ranks by their centroids, and elements
//      move to their ranks;
//   3. each node is owned by the lowest rank that has an element around it (the directory decides),
//      and every rank receives the ghost elements its owned nodes need (the total element loop of
//      Tpetra's finite-element examples: assembly needs no communication);
//   4. every rank fetches the coordinates, tags and groups of its nodes from the directory.
// After it, no rank holds the whole mesh; rank 0 held it only while reading.
#pragma once

#include <sinew/discretization/mesh.hpp>
#include <sinew/discretization/mesh_file.hpp>

namespace sinew {

// Collective. `file` is read on rank 0 only (and emptied there); other ranks pass an empty one.
Mesh distribute_mesh(MeshFile&& file, const Teuchos::Comm<int>& comm);

}  // namespace sinew
