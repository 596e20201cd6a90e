// Element data computed once per mesh: quadrature weights times det(dX/dxi) and the shape-function
// gradients with respect to the reference coordinates X, in Kokkos Views the kernels read. The
// gradients are stored per point (1.5 kB per hex8: 466 bytes per DOF on a voxel mesh), or, for hex8
// meshes of parallelepipeds (voxels, lattices), as one inverse Jacobian per element (72 bytes) from
// which the kernels form dN/dX = dN/dxi J^-1 at each point (element_kernel.hpp).
#pragma once

#include <sinew/discretization/element_kernel.hpp>
#include <sinew/discretization/mesh.hpp>

namespace sinew {

struct ElementData {
  ElementType type = ElementType::Hex8;
  int npe = 8, nqp = 8;
  Kokkos::View<double***> dNdX;  // (element * nqp + q, node, dim), or empty
  Kokkos::View<double* [9]> Jinv;  // element: (dX/dxi)^-1 row-major, or empty
  Kokkos::View<double*> wdetJ;   // (element * nqp + q): weight * det(dX/dxi), the reference volume of the point
};

// How dN/dX is kept: per element where every element is affine (hex8 only), else per point; or per
// point always (for comparisons).
enum class GradientStorage { Automatic, PerPoint };

// Computes the element data of every local element. Throws InputError naming the element's global id
// when a quadrature point has a non-positive reference Jacobian (degenerate or inverted rest element);
// collective, so that every rank throws the same error.
ElementData compute_element_data(const Mesh& mesh, const Teuchos::Comm<int>& comm,
                                 GradientStorage storage = GradientStorage::Automatic);

// The geometry the kernels read, for a mesh and its element data.
ElementGeometry<Kokkos::DefaultExecutionSpace::memory_space> element_geometry(const Mesh& mesh, const ElementData& ed);

}  // namespace sinew
