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
//   template <int NPE> void add_node_rows(const int* dof, int a, const double (*K)[3 * NPE]) const;
//                                  the three rows of element node a
//   bool atomic;                   whether adds must be atomic (false: the caller guarantees that no
//                                  two concurrent work items share a row; see ElementLoop::chunks)
// Boundary conditions are not the kernel's business: it adds every contribution; the algebra layer
// eliminates Dirichlet rows and columns afterwards.
#pragma once

#include <sinew/discretization/shape_functions.hpp>
#include <sinew/materials/material.hpp>
#include <sinew/materials/mean_dilatation.hpp>

#include <Kokkos_Core.hpp>

#include <type_traits>
#include <utility>

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

// What every kernel reads about the elements (see elements.hpp). The shape-function gradients dN/dX
// are stored per point (dNdX), or for affine elements formed at each point from one inverse Jacobian
// per element (Jinv, when dNdX is empty).
template <class MemorySpace>
struct ElementGeometry {
  Kokkos::View<const int**, MemorySpace> conn;       // element x node: local node index
  Kokkos::View<const double***, MemorySpace> dNdX;   // (element * points + q, node, dim), or empty
  Kokkos::View<const double* [9], MemorySpace> Jinv;  // element: (dX/dxi)^-1 row-major, or empty
  Kokkos::View<const double*, MemorySpace> wdetJ;    // (element * points + q): reference volume of the point
  int n_owned = 0;                                   // elements [0, n_owned) are owned, the rest ghosts
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
// f_ai += w P_iJ dN_a/dX_J: the internal force (external loads are a term of their own,
// algebra/terms/external_force.hpp).
template <int NPE>
KOKKOS_INLINE_FUNCTION void add_point_force(double* f, const Mat3& P, const double dN[NPE][3], double w) {
  for (int a = 0; a < NPE; ++a)
    for (int i = 0; i < 3; ++i) {
      double s = 0.0;
      for (int J = 0; J < 3; ++J) s += P(i, J) * dN[a][J];
      f[3 * a + i] += w * s;
    }
}

// G_(r)(bj) = H_(r)(jL) dN_b,L: the point's Hessian contracted with the shape-function gradients, the
// first half of K_(ai)(bj) = w dN_a,J H_(iJ)(jL) dN_b,L (the chain rule of dF/du through vec(F), Eq. 17).
template <int NPE>
KOKKOS_INLINE_FUNCTION void stiffness_factor(double (*G)[3 * NPE], const Mat9& H, const double dN[NPE][3]) {
  for (int r = 0; r < 9; ++r)
    for (int b = 0; b < NPE; ++b)
      for (int j = 0; j < 3; ++j) {
        double s = 0.0;
        for (int L = 0; L < 3; ++L) s += H(r, j + 3 * L) * dN[b][L];
        G[r][3 * b + j] = s;
      }
}

// Row (a, i) of the point's stiffness, columns c >= first: K_(ai)(c) = w (dN_a,0 G_(i)(c) + dN_a,1
// G_(i+3)(c) + dN_a,2 G_(i+6)(c)).
template <int NPE>
KOKKOS_INLINE_FUNCTION void add_stiffness_row(double* Krow, const double (*G)[3 * NPE], const double dNa[3], int i, double w,
                                              int first = 0) {
  const double w0 = w * dNa[0], w1 = w * dNa[1], w2 = w * dNa[2];
  const double* G0 = G[i];
  const double* G1 = G[i + 3];
  const double* G2 = G[i + 6];
  for (int c = first; c < 3 * NPE; ++c) Krow[c] += w0 * G0[c] + w1 * G1[c] + w2 * G2[c];
}

// The point's stiffness into the upper triangle of K (columns c >= row): H is symmetric, so K is, and
// half the contraction suffices; compute_element mirrors the triangle once per element.
template <int NPE>
KOKKOS_INLINE_FUNCTION void add_point_stiffness(double (*K)[3 * NPE], const Mat9& H, const double dN[NPE][3], double w) {
  double G[9][3 * NPE];
  stiffness_factor<NPE>(G, H, dN);
  for (int a = 0; a < NPE; ++a)
    for (int i = 0; i < 3; ++i) add_stiffness_row<NPE>(K[3 * a + i], G, dN[a], i, w, 3 * a + i);
}

// What one quadrature point of one element knows: its weight, shape-function gradients, F, J and the
// energy density (+inf where undefined, so that no merit function can accept such a state).
template <class Element>
struct PointState {
  static constexpr int NPE = Element::nodes;
  double w = 0.0, J = 0.0, psi = 0.0;
  bool defined = true;
  double dN[NPE][3];
  Mat3 F;
};

template <class Element, class Model, class MemorySpace>
KOKKOS_INLINE_FUNCTION void evaluate_point(const Model& model, const ElementGeometry<MemorySpace>& g, int e, int q,
                                           const double ue[3 * Element::nodes], PointState<Element>& s) {
  constexpr int NPE = Element::nodes;
  const std::size_t p = static_cast<std::size_t>(e) * Element::points + q;
  s.w = g.wdetJ(p);
  if (g.dNdX.extent(0) > 0) {
    for (int a = 0; a < NPE; ++a)
      for (int J = 0; J < 3; ++J) s.dN[a][J] = g.dNdX(p, a, J);
  } else {
    double dNdxi[NPE][3];
    Element::gradients(q, dNdxi);
    for (int a = 0; a < NPE; ++a)
      for (int J = 0; J < 3; ++J)
        s.dN[a][J] = dNdxi[a][0] * g.Jinv(e, J) + dNdxi[a][1] * g.Jinv(e, 3 + J) + dNdxi[a][2] * g.Jinv(e, 6 + J);
  }
  s.F = Mat3::identity();
  for (int a = 0; a < NPE; ++a)
    for (int J = 0; J < 3; ++J)
      for (int i = 0; i < 3; ++i) s.F(i, J) += ue[3 * a + i] * s.dN[a][J];
  s.J = det(s.F);
  s.defined = model.defined(s.F);
  s.psi = s.defined ? model.energy(s.F) : HUGE_VAL;
}

// Adds one point to a totals record.
template <class Element>
KOKKOS_INLINE_FUNCTION void add_point_totals(AssemblyTotals& t, const PointState<Element>& s) {
  t.energy += s.w * s.psi;
  t.volume += s.w * s.J;
  t.min_J = s.J < t.min_J ? s.J : t.min_J;
  if (!(s.J > 0.0)) ++t.inverted;
  if (!s.defined) ++t.undefined;
}

// ---- compute: the whole element --------------------------------------------------------------------
template <class Element>
KOKKOS_INLINE_FUNCTION void clear_result(bool want_matrix, ElementResult<Element>& r) {
  constexpr int NDOF = 3 * Element::nodes;
  r.totals.energy = r.totals.volume = 0.0;
  r.totals.min_J = HUGE_VAL;
  r.totals.inverted = r.totals.undefined = 0;
  for (int k = 0; k < NDOF; ++k) r.f[k] = 0.0;
  if (want_matrix)
    for (int a = 0; a < NDOF; ++a)
      for (int c = 0; c < NDOF; ++c) r.K[a][c] = 0.0;
}

// The element stiffness is accumulated in its upper triangle (it is symmetric): mirror it once.
template <class Element>
KOKKOS_INLINE_FUNCTION void mirror_stiffness(ElementResult<Element>& r) {
  constexpr int NDOF = 3 * Element::nodes;
  for (int a = 1; a < NDOF; ++a)
    for (int c = 0; c < a; ++c) r.K[a][c] = r.K[c][a];
}

// The element with its law's volume term on the mean dilatation (mean_dilatation.hpp): a first pass
// over the points for Jbar, a second for the energy, force and stiffness with the volume factor at Jbar,
// and the element's rank-one volume stiffness (s lambda / V) b b^T, b_(ai) = sum_q w_q cof(F_q)_iJ dN_a,J,
// s = `share` of the volume term on the mean (the rest stays at the points).
template <class Element, class Law, class MemorySpace>
KOKKOS_INLINE_FUNCTION void compute_element_mean_dilatation(const Law& law, Projection projection,
                                                            const ElementGeometry<MemorySpace>& g, int e,
                                                            const double ue[3 * Element::nodes], bool want_force,
                                                            bool want_matrix, ElementResult<Element>& r,
                                                            double share) {
  constexpr int NPE = Element::nodes, NDOF = 3 * NPE;
  clear_result(want_matrix, r);
  PointState<Element> s[Element::points];
  double V = 0.0, JV = 0.0;
  for (int q = 0; q < Element::points; ++q) {
    evaluate_point<Element>(law, g, e, q, ue, s[q]);
    V += s[q].w;
    JV += s[q].w * s[q].J;
  }
  MeanDilatationPoint<Law> point;
  point.law = law;
  point.Jbar = JV / V;
  point.share = share;
  double b[NDOF];
  for (int k = 0; k < NDOF; ++k) b[k] = 0.0;
  for (int q = 0; q < Element::points; ++q) {
    PointState<Element>& p = s[q];
    // evaluate_point gave the law's whole energy density: keep its deviatoric part.
    if (p.defined) p.psi = point.deviatoric(p.psi, p.J);
    add_point_totals(r.totals, p);
    if (want_force) add_point_force<NPE>(r.f, point.pk1(p.F), p.dN, p.w);
    if (want_matrix) {
      add_point_stiffness<NPE>(r.K, point.projected_hessian(p.F, point_projection(projection, p.J)), p.dN, p.w);
      add_point_force<NPE>(b, cofactor(p.F), p.dN, p.w);
    }
  }
  r.totals.energy += point.element_energy(V);
  if (want_matrix) {
    const double k = share * law.volume_term().lambda / V;
    for (int a = 0; a < NDOF; ++a)
      for (int c = a; c < NDOF; ++c) r.K[a][c] += k * b[a] * b[c];
    mirror_stiffness(r);
  }
  r.psi_avg = r.totals.energy / V;
  r.J_avg = point.Jbar;
}

// `mean_dilatation`: the share of the law's volume term on the element's mean dilatation, 0 for none
// (laws with a volume term only; the parameters refuse it for the others, and here it is ignored for them).
template <class Element, class Model, class MemorySpace>
KOKKOS_INLINE_FUNCTION void compute_element(const Model& model, Projection projection,
                                            const ElementGeometry<MemorySpace>& g, int e,
                                            const double ue[3 * Element::nodes], bool want_force,
                                            bool want_matrix, ElementResult<Element>& r, double mean_dilatation = 0.0) {
  if constexpr (has_volume_term<Model>::value) {
    if (mean_dilatation > 0.0)
      return compute_element_mean_dilatation<Element>(model, projection, g, e, ue, want_force, want_matrix, r, mean_dilatation);
  }
  constexpr int NPE = Element::nodes;
  clear_result(want_matrix, r);
  double psi_sum = 0.0, J_sum = 0.0, w_sum = 0.0;
  for (int q = 0; q < Element::points; ++q) {
    PointState<Element> s;
    evaluate_point<Element>(model, g, e, q, ue, s);
    add_point_totals(r.totals, s);
    psi_sum += s.w * s.psi;
    J_sum += s.w * s.J;
    w_sum += s.w;
    if (want_force) add_point_force<NPE>(r.f, model.pk1(s.F), s.dN, s.w);
    if (want_matrix) add_point_stiffness<NPE>(r.K, model.projected_hessian(s.F, point_projection(projection, s.J)), s.dN, s.w);
  }
  if (want_matrix) mirror_stiffness(r);
  r.psi_avg = psi_sum / w_sum;
  r.J_avg = J_sum / w_sum;
}

// ---- scatter -----------------------------------------------------------------------------------
// Owned rows only: with the total element loop every owned row sees all of its elements on this rank.
template <class Element, class Target>
KOKKOS_INLINE_FUNCTION void scatter(const Target& target, const int dof[3 * Element::nodes],
                                    const ElementResult<Element>& r, bool want_force, bool want_matrix) {
  for (int a = 0; a < Element::nodes; ++a) {
    const int row = dof[3 * a];  // a node's three rows are owned together
    if (row >= target.owned_dofs) continue;
    if (want_force)
      for (int i = 0; i < 3; ++i) target.add_force(row + i, r.f[3 * a + i]);
    if (want_matrix) target.template add_node_rows<Element::nodes>(dof, a, r.K);
  }
}

// The CRS arrays of a local matrix: KokkosSparse's CrsMatrix (Tpetra's local matrix) keeps them in
// `graph`, LocalCsr as members.
template <class M, class = void>
struct HasCsrGraph : std::false_type {};
template <class M>
struct HasCsrGraph<M, std::void_t<decltype(std::declval<const M&>().graph.row_map)>> : std::true_type {};
template <class M>
KOKKOS_INLINE_FUNCTION const auto& csr_row_map(const M& m) {
  if constexpr (HasCsrGraph<M>::value)
    return m.graph.row_map;
  else
    return m.row_map;
}
template <class M>
KOKKOS_INLINE_FUNCTION const auto& csr_entries(const M& m) {
  if constexpr (HasCsrGraph<M>::value)
    return m.graph.entries;
  else
    return m.entries;
}

// A scatter target over any local CRS matrix with KokkosSparse's sumIntoValues (Tpetra's local matrix,
// or LocalCsr on a device) and a force view.
template <class LocalMatrix, class ForceView>
struct CrsTarget {
  using memory_space = typename ForceView::memory_space;
  LocalMatrix matrix;
  ForceView force;
  int owned_dofs = 0;
  // Atomic adds cost a compare-and-swap loop each on the host (a quarter of a hex8 element's time, 576
  // per element); the coloured element loop turns them off.
  bool atomic = true;
  KOKKOS_INLINE_FUNCTION void add(double& to, double value) const {
    if (atomic)
      Kokkos::atomic_add(&to, value);
    else
      to += value;
  }
  KOKKOS_INLINE_FUNCTION void add_force(int row, double value) const { add(force(row), value); }
  KOKKOS_INLINE_FUNCTION void add_row(int row, const int* cols, int n, const double* values) const {
    matrix.sumIntoValues(row, cols, n, values, true, atomic);
  }

  // Element node a's three rows (dof[3a] + i) at the columns of all the element's nodes. System's graph
  // (build_graph) couples whole nodes: every row lists, for each node m it touches, 3m, 3m+1, 3m+2,
  // sorted, and a node's three rows list the same nodes. So one binary search over the node starts of
  // row 3a finds node b's slot k, and block (a, b) is at row_map(3a+i) + 3k + j: one search per node
  // pair instead of one per entry (64 instead of 576 for hex8). Each slot is checked before it is
  // written; a row that does not hold whole nodes (another pattern) takes sumIntoValues.
  template <int NPE>
  KOKKOS_INLINE_FUNCTION void add_node_rows(const int* dof, int a, const double (*K)[3 * NPE]) const {
    const auto& rows = csr_row_map(matrix);
    const auto& cols = csr_entries(matrix);
    const int row0 = dof[3 * a];
    const int begin0 = static_cast<int>(rows(row0)), length0 = static_cast<int>(rows(row0 + 1)) - begin0;
    for (int b = 0; b < NPE; ++b) {
      const int c0 = dof[3 * b];
      int k = -1;
      if (length0 % 3 == 0) {
        int lo = 0, hi = length0 / 3;
        while (lo < hi) {
          const int mid = (lo + hi) / 2;
          if (cols(begin0 + 3 * mid) < c0)
            lo = mid + 1;
          else
            hi = mid;
        }
        k = lo;
      }
      for (int i = 0; i < 3; ++i) {
        const double* v = &K[3 * a + i][3 * b];
        const int begin = static_cast<int>(rows(row0 + i)), end = static_cast<int>(rows(row0 + i + 1));
        const int p = begin + 3 * k;
        if (k >= 0 && p + 2 < end && cols(p) == c0 && cols(p + 2) == c0 + 2) {
          add(matrix.values(p), v[0]);
          add(matrix.values(p + 1), v[1]);
          add(matrix.values(p + 2), v[2]);
        } else {
          add_row(row0 + i, &dof[3 * b], 3, v);
        }
      }
    }
  }
};

// The reduction both element loops share: totals over owned elements, min_J starting at +inf.
struct TotalsReduction {
  using value_type = AssemblyTotals;
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
};

// The element loop over a list of local elements (those of one material), reducing the owned
// elements' totals. Each element: gather, compute, fields, scatter.
template <class Element, class Model, class Target>
struct ElementLoop : TotalsReduction {
  using memory_space = typename Target::memory_space;
  Model model;
  Projection projection = Projection::Clamp;
  ElementGeometry<memory_space> geometry;
  Kokkos::View<const int*, memory_space> elements;  // local element ids to visit
  Kokkos::View<const double*, memory_space> u;      // overlap DOFs: 3 * local node + component
  Target target;
  bool want_force = false, want_matrix = false;
  double mean_dilatation = 0.0;  // the share of the law's volume term on the element's mean dilatation
  ElementFields<memory_space> fields;
  // Coloured chunks (discretization/colouring.hpp), or empty: one element per work item, atomic adds.
  // Work item i is chunk chunk_first + i, the elements elements(chunks(c)) .. elements(chunks(c + 1) - 1),
  // visited in order by one thread; the launch covers chunks of one colour, which share no node, so
  // the target may add without atomics.
  Kokkos::View<const int*, memory_space> chunks;
  int chunk_first = 0;

  KOKKOS_INLINE_FUNCTION void operator()(const int i, value_type& totals) const {
    if (chunks.extent(0) == 0) {
      element(elements(i), totals);
      return;
    }
    for (int k = chunks(chunk_first + i); k < chunks(chunk_first + i + 1); ++k) element(elements(k), totals);
  }

  KOKKOS_INLINE_FUNCTION void element(const int e, value_type& totals) const {
    constexpr int NDOF = 3 * Element::nodes;
    int dof[NDOF];
    double ue[NDOF];
    gather<Element>(geometry, u, e, dof, ue);
    ElementResult<Element> r;
    compute_element<Element>(model, projection, geometry, e, ue, want_force, want_matrix, r, mean_dilatation);
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

// The same element loop split per quadrature point, the GPU-shaped alternative: work item (element,
// point) computes its point's force and stiffness and scatters each stiffness row as soon as it is
// made, so it never holds the 24x24 element matrix (on a GPU: fewer registers, 8x the parallelism of
// hex8, 8x the atomic adds). Totals are the same sums in another order; per-element fields are not
// offered (output uses ElementLoop).
template <class Element, class Model, class Target>
struct PointLoop : TotalsReduction {
  using memory_space = typename Target::memory_space;
  Model model;
  Projection projection = Projection::Clamp;
  ElementGeometry<memory_space> geometry;
  Kokkos::View<const int*, memory_space> elements;  // local element ids to visit
  Kokkos::View<const double*, memory_space> u;      // overlap DOFs: 3 * local node + component
  Target target;
  bool want_force = false, want_matrix = false;

  int work_items() const { return static_cast<int>(elements.extent(0)) * Element::points; }

  KOKKOS_INLINE_FUNCTION void operator()(const int item, value_type& totals) const {
    constexpr int NPE = Element::nodes, NDOF = 3 * NPE;
    const int e = elements(item / Element::points), q = item % Element::points;
    int dof[NDOF];
    double ue[NDOF];
    gather<Element>(geometry, u, e, dof, ue);
    PointState<Element> s;
    evaluate_point<Element>(model, geometry, e, q, ue, s);
    if (e < geometry.n_owned) add_point_totals(totals, s);
    if (want_force) {
      double f[NDOF];
      for (int k = 0; k < NDOF; ++k) f[k] = 0.0;
      add_point_force<NPE>(f, model.pk1(s.F), s.dN, s.w);
      for (int k = 0; k < NDOF; ++k)
        if (dof[k] < target.owned_dofs) target.add_force(dof[k], f[k]);
    }
    if (want_matrix) {
      double G[9][NDOF];
      stiffness_factor<NPE>(G, model.projected_hessian(s.F, point_projection(projection, s.J)), s.dN);
      for (int a = 0; a < NPE; ++a)
        for (int i = 0; i < 3; ++i) {
          const int row = dof[3 * a + i];
          if (row >= target.owned_dofs) continue;
          double Krow[NDOF];
          for (int c = 0; c < NDOF; ++c) Krow[c] = 0.0;
          add_stiffness_row<NPE>(Krow, G, s.dN[a], i, s.w);
          target.add_row(row, dof, NDOF, Krow);
        }
    }
  }
};

}  // namespace sinew
