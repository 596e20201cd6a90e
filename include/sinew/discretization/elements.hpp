// Element data computed once per mesh: quadrature weights times det(dX/dxi) and, when asked, the
// shape-function gradients with respect to the reference coordinates X, in Kokkos Views the kernels
// read. Without stored gradients the kernels compute them per point from X (element_kernel.hpp).
#pragma once

#include <sinew/discretization/element_kernel.hpp>
#include <sinew/discretization/mesh.hpp>

namespace sinew {

struct ElementData {
  ElementType type = ElementType::Hex8;
  int npe = 8, nqp = 8;
  Kokkos::View<double***> dNdX;  // (element * nqp + q, node, dim); empty unless stored
  Kokkos::View<double*> wdetJ;   // (element * nqp + q): weight * det(dX/dxi), the reference volume of the point
};

// Computes the element data of every local element (dN/dX too with store_gradients). Throws InputError
// naming the element's global id when a quadrature point has a non-positive reference Jacobian
// (degenerate or inverted rest element); collective, so that every rank throws the same error.
ElementData compute_element_data(const Mesh& mesh, const Teuchos::Comm<int>& comm, bool store_gradients = false);

// The geometry the kernels read, for a mesh and its element data.
ElementGeometry<Kokkos::DefaultExecutionSpace::memory_space> element_geometry(const Mesh& mesh, const ElementData& ed);

}  // namespace sinew
