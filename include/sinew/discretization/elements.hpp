// Reference-element data: shape-function gradients with respect to the reference coordinates X and
// quadrature weights times det(dX/dxi), precomputed once per mesh into Kokkos Views.
//   hex8: trilinear, 2x2x2 Gauss points at +-1/sqrt(3) (the paper's eight-point quadrature, Sec. 6)
//   tet4: linear, one point
#pragma once

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

// Hex8 shape functions in [-1, 1]^3, VTK node order.
KOKKOS_INLINE_FUNCTION void hex8_shape_gradients(const double xi[3], double dN[8][3]) {
  const double s[8][3] = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1},
                          {-1, -1, 1},  {1, -1, 1},  {1, 1, 1},  {-1, 1, 1}};
  for (int a = 0; a < 8; ++a) {
    const double f0 = 1 + s[a][0] * xi[0], f1 = 1 + s[a][1] * xi[1], f2 = 1 + s[a][2] * xi[2];
    dN[a][0] = 0.125 * s[a][0] * f1 * f2;
    dN[a][1] = 0.125 * f0 * s[a][1] * f2;
    dN[a][2] = 0.125 * f0 * f1 * s[a][2];
  }
}

KOKKOS_INLINE_FUNCTION void hex8_shape_values(const double xi[3], double N[8]) {
  const double s[8][3] = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1},
                          {-1, -1, 1},  {1, -1, 1},  {1, 1, 1},  {-1, 1, 1}};
  for (int a = 0; a < 8; ++a) N[a] = 0.125 * (1 + s[a][0] * xi[0]) * (1 + s[a][1] * xi[1]) * (1 + s[a][2] * xi[2]);
}

KOKKOS_INLINE_FUNCTION void hex8_gauss_point(int q, double xi[3]) {
  const double g = 0.57735026918962576451;  // 1/sqrt(3)
  xi[0] = (q & 1) ? g : -g;
  xi[1] = (q & 2) ? g : -g;
  xi[2] = (q & 4) ? g : -g;
}

}  // namespace sinew
