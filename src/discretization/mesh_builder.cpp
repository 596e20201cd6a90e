// The mesh of a scene: a lattice built by every rank, or a file read by rank 0 and distributed.
#include <sinew/core/collective.hpp>
#include <sinew/discretization/mesh_file.hpp>
#include <sinew/discretization/partition.hpp>

namespace sinew {

Mesh build_scene_mesh(const MeshParameters& p, const Teuchos::Comm<int>& comm) {
  if (p.type != "file") return build_mesh(lattice_spec(p), comm);
  MeshFile file;
  // Only rank 0 reads; its failure (a missing or broken file) must reach the others, which would
  // otherwise wait for the distribution forever.
  collectively(raw_comm(comm), [&] {
    if (comm.getRank() == 0) file = read_mesh_file(p.file);
  });
  return distribute_mesh(std::move(file), comm);
}

}  // namespace sinew
