// Reference-element geometry: w det(dX/dxi) (and, if asked, dN/dX) per quadrature point, with a collective check
// that no rest element is degenerate or inverted.
#include <sinew/core/errors.hpp>
#include <sinew/core/small_matrix.hpp>
#include <sinew/discretization/elements.hpp>

#include <Teuchos_CommHelpers.hpp>

#include <limits>

namespace sinew {

namespace {

// Fills wdetJ (and dNdX when it is allocated) of element type E; returns the smallest local element
// with a bad point.
template <class E>
int fill(const Mesh& mesh, ElementData& ed) {
  const bool store = ed.dNdX.extent(0) > 0;
  auto X = mesh.X;
  auto conn = mesh.conn;
  auto dNdX = ed.dNdX;
  auto wdetJ = ed.wdetJ;
  int bad = std::numeric_limits<int>::max();
  Kokkos::parallel_reduce(
      "sinew::element_data", Kokkos::RangePolicy<>(0, static_cast<int>(mesh.local_elements())),
      KOKKOS_LAMBDA(const int e, int& first_bad) {
        for (int q = 0; q < E::points; ++q) {
          double dN[E::nodes][3];
          const double dJ = reference_gradients<E>(conn, X, e, q, dN);
          const std::size_t p = static_cast<std::size_t>(e) * E::points + q;
          if (!(dJ > 0.0)) {
            first_bad = e < first_bad ? e : first_bad;
            wdetJ(p) = 0.0;
            continue;
          }
          wdetJ(p) = E::weight(q) * dJ;
          if (store)
            for (int a = 0; a < E::nodes; ++a)
              for (int j = 0; j < 3; ++j) dNdX(p, a, j) = dN[a][j];
        }
      },
      Kokkos::Min<int>(bad));
  return bad;
}

}  // namespace

ElementData compute_element_data(const Mesh& mesh, const Teuchos::Comm<int>& comm, bool store_gradients) {
  ElementData ed;
  ed.type = mesh.type;
  ed.npe = nodes_per_element(mesh.type);
  ed.nqp = quadrature_points(mesh.type);
  const std::size_t ne = mesh.local_elements();
  if (store_gradients) ed.dNdX = Kokkos::View<double***>("dNdX", ne * ed.nqp, ed.npe, 3);
  ed.wdetJ = Kokkos::View<double*>("wdetJ", ne * ed.nqp);
  const int bad = mesh.type == ElementType::Hex8 ? fill<Hex8>(mesh, ed) : fill<Tet4>(mesh, ed);
  // Every rank must agree on the error: reduce the smallest bad global element id.
  const GlobalId none = std::numeric_limits<GlobalId>::max();
  const GlobalId local_bad = bad == std::numeric_limits<int>::max() ? none : mesh.element_label(bad);
  GlobalId global_bad = local_bad;
  Teuchos::reduceAll(comm, Teuchos::REDUCE_MIN, local_bad, Teuchos::outArg(global_bad));
  if (global_bad != none)
    throw InputError("Mesh: element " + std::to_string(global_bad) +
                         " has a non-positive rest volume (degenerate or inverted element)",
                     InputErrorKind::BadMesh);
  return ed;
}

ElementGeometry<Kokkos::DefaultExecutionSpace::memory_space> element_geometry(const Mesh& mesh, const ElementData& ed) {
  ElementGeometry<Kokkos::DefaultExecutionSpace::memory_space> g;
  g.conn = mesh.conn;
  g.dNdX = ed.dNdX;
  g.X = mesh.X;
  g.wdetJ = ed.wdetJ;
  g.n_owned = static_cast<int>(mesh.n_owned_elements);
  return g;
}

}  // namespace sinew
