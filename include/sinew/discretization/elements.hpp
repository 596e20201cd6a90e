// Element data computed once per mesh: shape-function gradients with respect to the reference
// coordinates X and quadrature weights times det(dX/dxi), in Kokkos Views the kernels read.
#pragma once

#include <sinew/discretization/element_kernel.hpp>
#include <sinew/discretization/mesh.hpp>

namespace sinew {

struct ElementData {
  ElementType type = ElementType::Hex8;
  int npe = 8, nqp = 8;
  Kokkos::View<double***> dNdX;  // (element * nqp + q, node, dim)
  Kokkos::View<double*> wdetJ;   // (element * nqp + q): weight * det(dX/dxi), the reference volume of the point
};

// Computes the element data of every local element. Throws InputError naming the element's global id
// when a quadrature point has a non-positive reference Jacobian (degenerate or inverted rest element);
// collective, so that every rank throws the same error.
ElementData compute_element_data(const Mesh& mesh, const Teuchos::Comm<int>& comm);

// The geometry the kernels read, for a mesh and its element data.
ElementGeometry<Kokkos::DefaultExecutionSpace::memory_space> element_geometry(const Mesh& mesh, const ElementData& ed);

}  // namespace sinew
