// The mesh of a scene: a lattice built by every rank, or a file read by rank 0 and distributed.
#include <sinew/core/collective.hpp>
#include <sinew/discretization/mesh_file.hpp>
#include <sinew/discretization/partition.hpp>
#include <sinew/discretization/rig_file.hpp>
#include <sinew/discretization/triangle_surface.hpp>

namespace sinew {

Mesh build_scene_mesh(const MeshParameters& p, const Teuchos::Comm<int>& comm) {
  if (p.type == MeshType::Box || p.type == MeshType::Cylinder) return build_mesh(lattice_spec(p), comm);
  MeshFile file;
  std::shared_ptr<EmbeddedSurface> skin;
  if (has_skin(p.type)) {  // rank 0 fills the surface with cells, then it is distributed like a file
    collectively(raw_comm(comm), [&] {
      if (comm.getRank() != 0) return;
      TriangleSurface surface;
      if (p.type == MeshType::Rig) {
        const RigFile rig = read_rig_file(p.rig);
        const RigClip* clip = p.rig_rest_time >= 0.0 ? rig.clip(p.rig_rest_clip) : nullptr;
        if (p.rig_rest_time >= 0.0 && !clip) throw InputError(p.rig + ": no clip '" + p.rig_rest_clip + "' for the rest pose");
        if (clip) check_rest_time(*clip, p.rig_rest_time, p.rig);
        surface = rig_surface(rig, p.rig_meshes, clip, p.rig_rest_time);
      } else {
        surface = read_triangle_surface(p.surface);
      }
      Lattice lattice = voxelize(surface, p.cell_size, p.type == MeshType::Rig ? InsideRule::Winding : InsideRule::Parity);
      long long far = 0;
      skin = std::make_shared<EmbeddedSurface>(embed(surface, lattice, p.type == MeshType::Rig ? &far : nullptr));
      if (far > 0)
        lattice.mesh.notes.push_back(std::to_string(far) + " of " + std::to_string(surface.vertices.size()) +
                                     " skin vertices lie more than two cells from the lattice (parts thinner than a cell); "
                                     "each follows the cell of the nearest placed vertex along the skin, extrapolated");
      file = std::move(lattice.mesh);
    });
    Mesh mesh = distribute_mesh(std::move(file), comm);
    mesh.embedded = skin;
    mesh.has_embedded = true;
    return mesh;
  }
  // Only rank 0 reads; its failure (a missing or broken file) must reach the others, which would
  // otherwise wait for the distribution forever.
  collectively(raw_comm(comm), [&] {
    if (comm.getRank() == 0) file = read_mesh_file(p.file);
  });
  return distribute_mesh(std::move(file), comm);
}

}  // namespace sinew
