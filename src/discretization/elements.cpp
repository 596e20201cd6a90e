// Reference-element geometry: w det(dX/dxi) per quadrature point and dN/dX (per point, or per affine
// element through its inverse Jacobian), with a collective check
// that no rest element is degenerate or inverted.
#include <sinew/core/errors.hpp>
#include <sinew/core/small_matrix.hpp>
#include <sinew/discretization/elements.hpp>

#include <Teuchos_CommHelpers.hpp>

#include <limits>

namespace sinew {

namespace {

// dX/dxi of element e where the shape functions have the reference gradients dNdxi.
template <class E, class ConnView, class XView>
KOKKOS_INLINE_FUNCTION Mat3 reference_jacobian(const ConnView& conn, const XView& X, int e, const double (&dNdxi)[E::nodes][3]) {
  Mat3 J0 = Mat3::zero();
  for (int a = 0; a < E::nodes; ++a)
    for (int i = 0; i < 3; ++i)
      for (int d = 0; d < 3; ++d) J0(i, d) += X(conn(e, a), i) * dNdxi[a][d];
  return J0;
}

// (dX/dxi)^-1 from its determinant: the cofactor columns are f1 x f2, ..., so A^-1 = C^T / det.
KOKKOS_INLINE_FUNCTION Mat3 inverse(const Mat3& J0, double dJ) { return (1.0 / dJ) * transpose(cofactor(J0)); }

// Fills wdetJ of element type E and counts the elements whose map from the reference element is not
// affine (dX/dxi differs between points by more than round-off); returns the smallest local element
// with a bad point.
template <class E>
int fill_volumes(const Mesh& mesh, ElementData& ed, long long& not_affine) {
  auto X = mesh.X;
  auto conn = mesh.conn;
  auto wdetJ = ed.wdetJ;
  int bad = std::numeric_limits<int>::max();
  long long curved = 0;
  Kokkos::parallel_reduce(
      "sinew::element_volumes", Kokkos::RangePolicy<>(0, static_cast<int>(mesh.local_elements())),
      KOKKOS_LAMBDA(const int e, int& first_bad, long long& n_curved) {
        Mat3 J_first = Mat3::zero();
        double scale = 0.0, spread = 0.0;
        for (int q = 0; q < E::points; ++q) {
          double dNdxi[E::nodes][3];
          E::gradients(q, dNdxi);
          const Mat3 J0 = reference_jacobian<E>(conn, X, e, dNdxi);
          if (q == 0) J_first = J0;
          for (int i = 0; i < 3; ++i)
            for (int d = 0; d < 3; ++d) {
              const double v = J0(i, d) < 0.0 ? -J0(i, d) : J0(i, d);
              const double dv = J0(i, d) < J_first(i, d) ? J_first(i, d) - J0(i, d) : J0(i, d) - J_first(i, d);
              scale = v > scale ? v : scale;
              spread = dv > spread ? dv : spread;
            }
          const double dJ = det(J0);
          const std::size_t p = static_cast<std::size_t>(e) * E::points + q;
          wdetJ(p) = dJ > 0.0 ? E::weight(q) * dJ : 0.0;
          if (!(dJ > 0.0)) first_bad = e < first_bad ? e : first_bad;
        }
        if (spread > 1e-12 * scale) ++n_curved;
      },
      Kokkos::Min<int>(bad), curved);
  not_affine = curved;
  return bad;
}

// dN/dX per point (any element).
template <class E>
void fill_gradients(const Mesh& mesh, ElementData& ed) {
  auto X = mesh.X;
  auto conn = mesh.conn;
  auto dNdX = ed.dNdX;
  Kokkos::parallel_for(
      "sinew::element_gradients", Kokkos::RangePolicy<>(0, static_cast<int>(mesh.local_elements())), KOKKOS_LAMBDA(const int e) {
        for (int q = 0; q < E::points; ++q) {
          double dNdxi[E::nodes][3];
          E::gradients(q, dNdxi);
          const Mat3 J0 = reference_jacobian<E>(conn, X, e, dNdxi);
          const Mat3 Jinv = inverse(J0, det(J0));  // positive: fill_volumes checked every point
          const std::size_t p = static_cast<std::size_t>(e) * E::points + q;
          for (int a = 0; a < E::nodes; ++a)
            for (int j = 0; j < 3; ++j) {
              double v = 0.0;
              for (int d = 0; d < 3; ++d) v += dNdxi[a][d] * Jinv(d, j);
              dNdX(p, a, j) = v;
            }
        }
      });
}

// (dX/dxi)^-1 per element at the reference element's centre, for affine elements.
template <class E>
void fill_inverse_jacobians(const Mesh& mesh, ElementData& ed) {
  auto X = mesh.X;
  auto conn = mesh.conn;
  auto Jinv = ed.Jinv;
  Kokkos::parallel_for(
      "sinew::element_inverse_jacobians", Kokkos::RangePolicy<>(0, static_cast<int>(mesh.local_elements())), KOKKOS_LAMBDA(const int e) {
        const double centre[3] = {0.0, 0.0, 0.0};
        double dNdxi[E::nodes][3];
        E::gradients_at(centre, dNdxi);
        const Mat3 J0 = reference_jacobian<E>(conn, X, e, dNdxi);
        const Mat3 inv = inverse(J0, det(J0));
        for (int d = 0; d < 3; ++d)
          for (int j = 0; j < 3; ++j) Jinv(e, 3 * d + j) = inv(d, j);
      });
}

}  // namespace

ElementData compute_element_data(const Mesh& mesh, const Teuchos::Comm<int>& comm, GradientStorage storage) {
  ElementData ed;
  ed.type = mesh.type;
  ed.npe = nodes_per_element(mesh.type);
  ed.nqp = quadrature_points(mesh.type);
  const std::size_t ne = mesh.local_elements();
  ed.wdetJ = Kokkos::View<double*>("wdetJ", ne * ed.nqp);
  long long not_affine = 0;
  const bool hex = mesh.type == ElementType::Hex8;
  const int bad = hex ? fill_volumes<Hex8>(mesh, ed, not_affine) : fill_volumes<Tet4>(mesh, ed, not_affine);
  // Every rank must agree on the error: reduce the smallest bad global element id.
  const GlobalId none = std::numeric_limits<GlobalId>::max();
  const GlobalId local_bad = bad == std::numeric_limits<int>::max() ? none : mesh.element_label(bad);
  GlobalId global_bad = local_bad;
  Teuchos::reduceAll(comm, Teuchos::REDUCE_MIN, local_bad, Teuchos::outArg(global_bad));
  if (global_bad != none)
    throw InputError("Mesh: element " + std::to_string(global_bad) +
                         " has a non-positive rest volume (degenerate or inverted element)",
                     InputErrorKind::BadMesh);
  // hex8 on a rank whose elements are all parallelepipeds (voxels, lattices) keeps one inverse
  // Jacobian per element; everything else stores dN/dX per point.
  if (hex && not_affine == 0 && storage != GradientStorage::PerPoint) {
    ed.Jinv = Kokkos::View<double* [9]>("Jinv", ne);
    fill_inverse_jacobians<Hex8>(mesh, ed);
  } else {
    ed.dNdX = Kokkos::View<double***>("dNdX", ne * ed.nqp, ed.npe, 3);
    hex ? fill_gradients<Hex8>(mesh, ed) : fill_gradients<Tet4>(mesh, ed);
  }
  return ed;
}

ElementGeometry<Kokkos::DefaultExecutionSpace::memory_space> element_geometry(const Mesh& mesh, const ElementData& ed) {
  ElementGeometry<Kokkos::DefaultExecutionSpace::memory_space> g;
  g.conn = mesh.conn;
  g.dNdX = ed.dNdX;
  g.Jinv = ed.Jinv;
  g.wdetJ = ed.wdetJ;
  g.n_owned = static_cast<int>(mesh.n_owned_elements);
  return g;
}

}  // namespace sinew
