// Reference elements: node count, quadrature, shape-function values and gradients in reference
// coordinates. Kokkos-only (no Trilinos types), so the element kernels compile for a device.
//   Hex8: trilinear on [-1, 1]^3, VTK node order, 2x2x2 Gauss points at +-1/sqrt(3) (the paper's
//         eight-point quadrature, Sec. 6), weight 1 each.
//   Tet4: linear on the unit tetrahedron (N0 = 1 - xi - eta - zeta), one point at the centroid,
//         weight 1/6 (the reference volume).
#pragma once

#include <Kokkos_Macros.hpp>

namespace sinew {

struct Hex8 {
  static constexpr int nodes = 8, points = 8;
  static constexpr const char* name = "hex8";

  KOKKOS_INLINE_FUNCTION static void point(int q, double xi[3]) {
    const double g = 0.57735026918962576451;  // 1/sqrt(3)
    xi[0] = (q & 1) ? g : -g;
    xi[1] = (q & 2) ? g : -g;
    xi[2] = (q & 4) ? g : -g;
  }
  KOKKOS_INLINE_FUNCTION static double weight(int) { return 1.0; }
  // Sign of node a's reference coordinate along axis d.
  KOKKOS_INLINE_FUNCTION static double corner(int a, int d) {
    const int bits[8] = {0, 1, 3, 2, 4, 5, 7, 6};  // VTK order: (x, y) goes round the face, then z
    return (bits[a] >> d) & 1 ? 1.0 : -1.0;
  }
  KOKKOS_INLINE_FUNCTION static void values_at(const double xi[3], double N[8]) {
    for (int a = 0; a < 8; ++a)
      N[a] = 0.125 * (1 + corner(a, 0) * xi[0]) * (1 + corner(a, 1) * xi[1]) * (1 + corner(a, 2) * xi[2]);
  }
  KOKKOS_INLINE_FUNCTION static void gradients_at(const double xi[3], double dN[8][3]) {
    for (int a = 0; a < 8; ++a) {
      const double s0 = corner(a, 0), s1 = corner(a, 1), s2 = corner(a, 2);
      const double f0 = 1 + s0 * xi[0], f1 = 1 + s1 * xi[1], f2 = 1 + s2 * xi[2];
      dN[a][0] = 0.125 * s0 * f1 * f2;
      dN[a][1] = 0.125 * f0 * s1 * f2;
      dN[a][2] = 0.125 * f0 * f1 * s2;
    }
  }
  KOKKOS_INLINE_FUNCTION static void values(int q, double N[8]) {
    double xi[3];
    point(q, xi);
    values_at(xi, N);
  }
  KOKKOS_INLINE_FUNCTION static void gradients(int q, double dN[8][3]) {
    double xi[3];
    point(q, xi);
    gradients_at(xi, dN);
  }
};

struct Tet4 {
  static constexpr int nodes = 4, points = 1;
  static constexpr const char* name = "tet4";

  KOKKOS_INLINE_FUNCTION static double weight(int) { return 1.0 / 6.0; }
  KOKKOS_INLINE_FUNCTION static void values(int, double N[4]) {
    for (int a = 0; a < 4; ++a) N[a] = 0.25;
  }
  KOKKOS_INLINE_FUNCTION static void gradients(int, double dN[4][3]) {
    const double g[4][3] = {{-1, -1, -1}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    for (int a = 0; a < 4; ++a)
      for (int d = 0; d < 3; ++d) dN[a][d] = g[a][d];
  }
};

}  // namespace sinew
