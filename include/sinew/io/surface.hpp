// The boundary surface of the mesh (discretization/boundary.hpp) as triangles for renderers (Blender,
// Houdini, Maya read OBJ), with per-vertex normals area-weighted in the current configuration. Rank 0
// gathers the surface (triangles once, vertex positions per write) and writes the file; its size grows
// with the surface, not the volume.
#pragma once

#include <sinew/algebra/system.hpp>

#include <map>
#include <string>
#include <vector>

namespace sinew {

class BoundarySurface {
 public:
  // Collective.
  BoundarySurface(const Mesh& mesh, const Teuchos::Comm<int>& comm);

  // Global counts (valid on every rank).
  long long triangles() const { return n_triangles_; }
  long long vertices() const { return n_vertices_; }

  // Collective: writes the deformed surface x = X + u (u on the owned nodes) as a Wavefront OBJ with
  // normals, aside and then renamed into place by rank 0; a failure is an error on every rank.
  void write_obj(const std::string& path, const Vector& u, const std::string& comment) const;

 private:
  const Mesh& mesh_;
  MPI_Comm comm_;
  bool root_ = false;
  std::vector<int> owned_vertices_;             // local owned nodes on the surface
  std::vector<int> counts_, offsets_;           // rank 0: vertices per rank
  std::vector<std::array<int, 3>> triangles_;   // rank 0: vertex indices in gathered order
  long long n_triangles_ = 0, n_vertices_ = 0;
};

// Writes a triangle surface as a Wavefront OBJ with area-weighted vertex normals (x: 3 per vertex),
// aside and then renamed into place. Throws std::runtime_error when the file cannot be written.
void write_obj_file(const std::string& path, const std::vector<double>& x, const std::vector<std::array<int, 3>>& triangles,
                    const std::string& comment);

// The surface a voxelized mesh was made from, carried along by the lattice (Mesh::embedded): each
// vertex moves with the displacement interpolated from its cell's eight nodes. Rank 0 gathers those
// nodes' displacements (a Tpetra import) and writes the OBJ.
class EmbeddedSkin {
 public:
  // Collective.
  EmbeddedSkin(const Mesh& mesh, const Teuchos::RCP<const Map>& owned_dofs);
  // Collective: rank 0 gets the deformed skin x (3 per vertex) and, with J given, det F at each vertex
  // from its cell's trilinear map (the volume change the skin sits in); other ranks get nothing.
  void deformed(const Vector& u, std::vector<double>& x, std::vector<double>* J = nullptr) const;
  // Collective.
  void write_obj(const std::string& path, const Vector& u, const std::string& comment) const;

 private:
  const Mesh& mesh_;
  Teuchos::RCP<const Map> gathered_;
  Teuchos::RCP<const Import> import_;
  std::map<GlobalId, int> slot_;  // rank 0: a node's place among the gathered ones
  std::vector<double> rest_nodes_;  // rank 0: the gathered nodes' reference coordinates, in slot order
};

}  // namespace sinew
