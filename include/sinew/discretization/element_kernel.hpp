// The element loop, in the three named pieces of miniFE's perform_element_loop: gather (the element's
// DOF indices and displacements), compute (per quadrature point F = I + grad u, then the material's
// energy, PK1 and (projected) Hessian, contracted into the element's force and stiffness), and scatter
// (into a target's force vector and matrix rows). Kokkos only: no Trilinos type appears here, so the
// same kernel runs with Tpetra's local matrix on the host and with a plain Kokkos CSR on a device.
//
// A scatter target provides, for its memory space:
//   int owned_dofs;                            rows [0, owned_dofs) are this rank's
//   void add_force(int row, double value) const;                        atomically
//   void add_row(int row, const int* cols, int n, const double* values) const;   atomically
// Boundary conditions are not the kernel's business: it adds every contribution; the algebra layer
// eliminates Dirichlet rows and columns afterwards.
#pragma once

#include <sinew/discretization/shape_functions.hpp>
#include <sinew/materials/material.hpp>

#include <Kokkos_Core.hpp>

namespace sinew {

// Totals over owned elements. min_J is over quadrature points; inverted counts points with J <= 0;
// undefined counts points where the energy is +inf (Neo-Hookean with J <= 0), and then energy is +inf.
struct AssemblyTotals {
  double energy = 0.0, volume = 0.0, min_J = 0.0;
  long long inverted = 0, undefined = 0;

  KOKKOS_INLINE_FUNCTION void add(const AssemblyTotals& b) {
    energy += b.energy;
    volume += b.volume;
    min_J = b.min_J < min_J ? b.min_J : min_J;
    inverted += b.inverted;
    undefined += b.undefined;
  }
};

// What every kernel reads about the elements: computed once per mesh (see elements.hpp).
template <class MemorySpace>
struct ElementGeometry {
  Kokkos::View<const int**, MemorySpace> conn;      // element x node: local node index
  Kokkos::View<const double***, MemorySpace> dNdX;  // (element * points + q, node, dim)
  Kokkos::View<const double*, MemorySpace> wdetJ;   // (element * points + q): reference volume of the point
  int n_owned = 0;                                  // elements [0, n_owned) are owned, the rest ghosts
};

// Optional per-element outputs: volume averages of the energy density and of J (owned elements).
template <class MemorySpace>
struct ElementFields {
  Kokkos::View<double*, MemorySpace> psi, J;
  KOKKOS_INLINE_FUNCTION bool wanted() const { return psi.extent(0) > 0; }
};

// One element's contribution.
template <class Element>
struct ElementResult {
  static constexpr int ndof = 3 * Element::nodes;
  AssemblyTotals totals;
  double psi_avg = 0.0, J_avg = 0.0;
  double f[ndof];
  double K[ndof][ndof];
};

// ---- gather -------------------------------------------------------------------------------------
template <class Element, class MemorySpace>
KOKKOS_INLINE_FUNCTION void gather(const ElementGeometry<MemorySpace>& g, const Kokkos::View<const double*, MemorySpace>& u,
                                   int e, int dof[3 * Element::nodes], double ue[3 * Element::nodes]) {
  for (int a = 0; a < Element::nodes; ++a)
    for (int i = 0; i < 3; ++i) {
      dof[3 * a + i] = 3 * g.conn(e, a) + i;
      ue[3 * a + i] = u(dof[3 * a + i]);
    }
}

// ---- compute: one quadrature point's contributions ----------------------------------------------
// f_ai += w (P_iJ dN_a/dX_J - N_a b_i): internal force minus the body force (per reference volume).
template <int NPE>
KOKKOS_INLINE_FUNCTION void add_point_force(double* f, const Mat3& P, const double dN[NPE][3], const double N[NPE],
                                            double w, const double body[3]) {
  for (int a = 0; a < NPE; ++a)
    for (int i = 0; i < 3; ++i) {
      double s = 0.0;
      for (int J = 0; J < 3; ++J) s += P(i, J) * dN[a][J];
      f[3 * a + i] += w * (s - N[a] * body[i]);
    }
}

// K_(ai)(bj) += w dN_a,J H_(iJ)(jL) dN_b,L, the chain rule of dF/du through vec(F) (Eq. 17): first
// G = H contracted with dN_b, then dN_a contracted with G.
template <int NPE>
KOKKOS_INLINE_FUNCTION void add_point_stiffness(double (*K)[3 * NPE], const Mat9& H, const double dN[NPE][3], double w) {
  constexpr int NDOF = 3 * NPE;
  double G[9][NDOF];
  for (int r = 0; r < 9; ++r)
    for (int b = 0; b < NPE; ++b)
      for (int j = 0; j < 3; ++j) {
        double s = 0.0;
        for (int L = 0; L < 3; ++L) s += H(r, j + 3 * L) * dN[b][L];
        G[r][3 * b + j] = s;
      }
  for (int a = 0; a < NPE; ++a)
    for (int i = 0; i < 3; ++i) {
      double* Krow = K[3 * a + i];
      const double w0 = w * dN[a][0], w1 = w * dN[a][1], w2 = w * dN[a][2];
      const double* G0 = G[i];
      const double* G1 = G[i + 3];
      const double* G2 = G[i + 6];
      for (int c = 0; c < NDOF; ++c) Krow[c] += w0 * G0[c] + w1 * G1[c] + w2 * G2[c];
    }
}

// ---- compute: the whole element --------------------------------------------------------------------
template <class Element, class Model, class MemorySpace>
KOKKOS_INLINE_FUNCTION void compute_element(const Model& model, Projection projection,
                                            const ElementGeometry<MemorySpace>& g, int e,
                                            const double ue[3 * Element::nodes], const double body[3], bool want_force,
                                            bool want_matrix, ElementResult<Element>& r) {
  constexpr int NPE = Element::nodes, NDOF = 3 * NPE;
  r.totals.energy = r.totals.volume = 0.0;
  r.totals.min_J = HUGE_VAL;
  r.totals.inverted = r.totals.undefined = 0;
  for (int k = 0; k < NDOF; ++k) r.f[k] = 0.0;
  if (want_matrix)
    for (int a = 0; a < NDOF; ++a)
      for (int c = 0; c < NDOF; ++c) r.K[a][c] = 0.0;
  double psi_sum = 0.0, J_sum = 0.0, w_sum = 0.0;
  for (int q = 0; q < Element::points; ++q) {
    const std::size_t p = static_cast<std::size_t>(e) * Element::points + q;
    const double w = g.wdetJ(p);
    double dN[NPE][3];
    for (int a = 0; a < NPE; ++a)
      for (int J = 0; J < 3; ++J) dN[a][J] = g.dNdX(p, a, J);
    Mat3 F = Mat3::identity();
    for (int a = 0; a < NPE; ++a)
      for (int J = 0; J < 3; ++J)
        for (int i = 0; i < 3; ++i) F(i, J) += ue[3 * a + i] * dN[a][J];
    const double Jdet = det(F);
    // An undefined energy (Neo-Hookean inverted) is +inf to every merit function: such a state must
    // never look acceptable.
    const bool defined = model.defined(F);
    const double psi = defined ? model.energy(F) : HUGE_VAL;
    double N[NPE];
    Element::values(q, N);
    double body_work = 0.0;
    for (int a = 0; a < NPE; ++a)
      for (int i = 0; i < 3; ++i) body_work += N[a] * body[i] * ue[3 * a + i];
    r.totals.energy += w * (psi - body_work);
    r.totals.volume += w * Jdet;
    r.totals.min_J = Jdet < r.totals.min_J ? Jdet : r.totals.min_J;
    if (!(Jdet > 0.0)) ++r.totals.inverted;
    if (!defined) ++r.totals.undefined;
    psi_sum += w * psi;
    J_sum += w * Jdet;
    w_sum += w;
    if (want_force) add_point_force<NPE>(r.f, model.pk1(F), dN, N, w, body);
    if (want_matrix) add_point_stiffness<NPE>(r.K, model.projected_hessian(F, projection), dN, w);
  }
  r.psi_avg = psi_sum / w_sum;
  r.J_avg = J_sum / w_sum;
}

// ---- scatter -----------------------------------------------------------------------------------
// Owned rows only: with the total element loop every owned row sees all of its elements on this rank.
template <class Element, class Target>
KOKKOS_INLINE_FUNCTION void scatter(const Target& target, const int dof[3 * Element::nodes],
                                    const ElementResult<Element>& r, bool want_force, bool want_matrix) {
  constexpr int NDOF = 3 * Element::nodes;
  for (int a = 0; a < NDOF; ++a) {
    const int row = dof[a];
    if (row >= target.owned_dofs) continue;
    if (want_force) target.add_force(row, r.f[a]);
    if (want_matrix) target.add_row(row, dof, NDOF, r.K[a]);
  }
}

// A scatter target over any local CRS matrix with KokkosSparse's sumIntoValues (Tpetra's local matrix,
// or LocalCsr on a device) and a force view.
template <class LocalMatrix, class ForceView>
struct CrsTarget {
  using memory_space = typename ForceView::memory_space;
  LocalMatrix matrix;
  ForceView force;
  int owned_dofs = 0;
  KOKKOS_INLINE_FUNCTION void add_force(int row, double value) const { Kokkos::atomic_add(&force(row), value); }
  KOKKOS_INLINE_FUNCTION void add_row(int row, const int* cols, int n, const double* values) const {
    matrix.sumIntoValues(row, cols, n, values, true, true);
  }
};

// The element loop over a list of local elements (those of one material), reducing the owned
// elements' totals. Each element: gather, compute, fields, scatter.
template <class Element, class Model, class Target>
struct ElementLoop {
  using memory_space = typename Target::memory_space;
  using value_type = AssemblyTotals;
  Model model;
  Projection projection = Projection::Clamp;
  ElementGeometry<memory_space> geometry;
  Kokkos::View<const int*, memory_space> elements;  // local element ids to visit
  Kokkos::View<const double*, memory_space> u;      // overlap DOFs: 3 * local node + component
  double body[3] = {0.0, 0.0, 0.0};                  // body force per reference volume
  Target target;
  bool want_force = false, want_matrix = false;
  ElementFields<memory_space> fields;

  KOKKOS_INLINE_FUNCTION void init(value_type& t) const {
    t = AssemblyTotals();
    t.min_J = HUGE_VAL;
  }
  KOKKOS_INLINE_FUNCTION void join(value_type& a, const value_type& b) const { a.add(b); }
#if KOKKOS_VERSION < 40000
  KOKKOS_INLINE_FUNCTION void join(volatile value_type& a, const volatile value_type& b) const {
    a.energy += b.energy;
    a.volume += b.volume;
    a.min_J = b.min_J < a.min_J ? b.min_J : a.min_J;
    a.inverted += b.inverted;
    a.undefined += b.undefined;
  }
#endif

  KOKKOS_INLINE_FUNCTION void operator()(const int i, value_type& totals) const {
    constexpr int NDOF = 3 * Element::nodes;
    const int e = elements(i);
    int dof[NDOF];
    double ue[NDOF];
    gather<Element>(geometry, u, e, dof, ue);
    ElementResult<Element> r;
    compute_element<Element>(model, projection, geometry, e, ue, body, want_force, want_matrix, r);
    if (e < geometry.n_owned) {
      totals.add(r.totals);
      if (fields.wanted()) {
        fields.psi(e) = r.psi_avg;
        fields.J(e) = r.J_avg;
      }
    }
    scatter<Element>(target, dof, r, want_force, want_matrix);
  }
};

}  // namespace sinew
