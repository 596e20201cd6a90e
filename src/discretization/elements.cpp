#include <sinew/core/errors.hpp>
#include <sinew/core/small_matrix.hpp>
#include <sinew/discretization/elements.hpp>

#include <Teuchos_CommHelpers.hpp>

#include <limits>

namespace sinew {

namespace {

// Inverse of a 3x3 matrix with its determinant; the caller checks det > 0.
KOKKOS_INLINE_FUNCTION Mat3 inverse(const Mat3& A, double d) {
  const Mat3 C = cofactor(A);  // columns: f1 x f2, f2 x f0, f0 x f1 => A^{-1} = C^T / det
  return (1.0 / d) * transpose(C);
}

}  // namespace

ElementData compute_element_data(const Mesh& mesh, const Teuchos::Comm<int>& comm) {
  ElementData ed;
  ed.type = mesh.type;
  ed.npe = nodes_per_element(mesh.type);
  ed.nqp = quadrature_points(mesh.type);
  const int ne = static_cast<int>(mesh.local_elements());
  const int npe = ed.npe, nqp = ed.nqp;
  ed.dNdX = Kokkos::View<double***>("dNdX", static_cast<std::size_t>(ne) * nqp, npe, 3);
  ed.wdetJ = Kokkos::View<double*>("wdetJ", static_cast<std::size_t>(ne) * nqp);
  auto X = mesh.X;
  auto conn = mesh.conn;
  auto dNdX = ed.dNdX;
  auto wdetJ = ed.wdetJ;
  const bool hex = mesh.type == ElementType::Hex8;
  // Smallest det(dX/dxi) and the first local element where it is not positive.
  int bad = std::numeric_limits<int>::max();
  Kokkos::parallel_reduce(
      "sinew::element_data", Kokkos::RangePolicy<>(0, ne),
      KOKKOS_LAMBDA(const int e, int& first_bad) {
        for (int q = 0; q < nqp; ++q) {
          double dNdxi[8][3];
          double w;
          if (hex) {
            double xi[3];
            hex8_gauss_point(q, xi);
            hex8_shape_gradients(xi, dNdxi);
            w = 1.0;
          } else {
            // Barycentric tet: N0 = 1 - xi - eta - zeta; reference volume 1/6.
            const double g[4][3] = {{-1, -1, -1}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
            for (int a = 0; a < 4; ++a)
              for (int d = 0; d < 3; ++d) dNdxi[a][d] = g[a][d];
            w = 1.0 / 6.0;
          }
          Mat3 J0 = Mat3::zero();  // dX/dxi
          for (int a = 0; a < npe; ++a)
            for (int i = 0; i < 3; ++i)
              for (int d = 0; d < 3; ++d) J0(i, d) += X(conn(e, a), i) * dNdxi[a][d];
          const double dJ = det(J0);
          const std::size_t p = static_cast<std::size_t>(e) * nqp + q;
          if (!(dJ > 0.0)) {
            first_bad = e < first_bad ? e : first_bad;
            wdetJ(p) = 0.0;
            continue;
          }
          const Mat3 Jinv = inverse(J0, dJ);
          wdetJ(p) = w * dJ;
          for (int a = 0; a < npe; ++a)
            for (int j = 0; j < 3; ++j) {
              double s = 0.0;
              for (int d = 0; d < 3; ++d) s += dNdxi[a][d] * Jinv(d, j);
              dNdX(p, a, j) = s;
            }
        }
      },
      Kokkos::Min<int>(bad));
  // Every rank must agree on the error: reduce the smallest bad global element id.
  GlobalId local_bad = bad == std::numeric_limits<int>::max() ? std::numeric_limits<GlobalId>::max() : mesh.element_gid[bad];
  GlobalId global_bad = local_bad;
  Teuchos::reduceAll(comm, Teuchos::REDUCE_MIN, local_bad, Teuchos::outArg(global_bad));
  if (global_bad != std::numeric_limits<GlobalId>::max())
    throw InputError("Mesh: element " + std::to_string(global_bad) +
                     " has a non-positive rest volume (degenerate or inverted element)",
                     InputErrorKind::BadMesh);
  return ed;
}

}  // namespace sinew
