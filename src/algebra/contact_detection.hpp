// What contact.cpp and contact_barrier.cpp share of ContactTerm's detection.
#pragma once

#include <sinew/algebra/system.hpp>
#include <sinew/algebra/terms/contact.hpp>

#include <Tpetra_Import.hpp>
#include <Tpetra_Vector.hpp>

namespace sinew {

using geom::Vec;

// The current positions a detection reads: of the local nodes (owned and ghost), and of every surface
// vertex (replicated).
struct ContactTerm::Positions {
  Kokkos::View<double* [3]>::HostMirror X;
  Vector overlap;
  decltype(std::declval<Vector&>().getLocalViewHost(Tpetra::Access::ReadOnly)) uh;
  std::vector<Vec> surface;
  Positions(const System& system, const Vector& u)
      : X(Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), system.mesh().X)), overlap(system.overlap_dofs()) {
    overlap.doImport(u, Import(system.owned_dofs(), system.overlap_dofs()), Tpetra::INSERT);
    uh = overlap.getLocalViewHost(Tpetra::Access::ReadOnly);
  }
  Vec node(int n) const { return Vec{X(n, 0) + uh(3 * n, 0), X(n, 1) + uh(3 * n + 1, 0), X(n, 2) + uh(3 * n + 2, 0)}; }
};

// A pair a detection considers before choosing.
struct ContactTerm::Candidate {
  int vertex, kind;  // kind 0: inside (reference map), 1: kept from the last pass, 2: proximity
  int triangle;
  double beta[3], normal[3], d2;
  int refined;
  double lambda;
};

// A tree of the surface triangles' boxes at positions x.
inline geom::AabbTree triangle_tree(const SurfaceMesh& s, const std::vector<Vec>& x) {
  std::vector<geom::Box> boxes(s.triangles.size());
  for (std::size_t t = 0; t < s.triangles.size(); ++t)
    for (int m : s.triangles[t]) boxes[t].add(x[m]);
  return geom::AabbTree(boxes);
}

}  // namespace sinew
