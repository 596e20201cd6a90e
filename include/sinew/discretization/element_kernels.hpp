// The element kernel: per quadrature point F = I + grad u, then the element's energy, internal force and
// (projected) stiffness, scattered into Tpetra's local force vector and matrix with atomics.
//
// Templated on the material model (a plain struct, so each model gets its own instantiation and no
// virtual call or switch runs inside the kernel), the element's node and point counts, and the
// execution space. Heavy: include only in the assembly translation units.
#pragma once

#include <sinew/discretization/elements.hpp>
#include <sinew/materials/material.hpp>

#include <Kokkos_Core.hpp>

namespace sinew {

// Totals over owned elements. min_J is over quadrature points; inverted counts points with J <= 0;
// undefined counts points where the energy is +inf (Neo-Hookean with J <= 0).
struct AssemblyTotals {
  double energy = 0.0, volume = 0.0, min_J = 0.0;
  long long inverted = 0, undefined = 0;
};

// Everything a kernel reads and writes, independent of the material model.
template <class LocalMatrix>
struct AssemblyViews {
  Kokkos::View<const int**> conn;
  Kokkos::View<const double***> dNdX;
  Kokkos::View<const double*> wdetJ;
  Kokkos::View<const double*> u;       // overlap DOFs, 3 * local node + component
  Kokkos::View<const char*> fixed;     // overlap DOFs: 1 where a Dirichlet condition holds
  Kokkos::View<double*> force;         // owned DOFs (empty: not wanted)
  LocalMatrix matrix;                  // (not used unless want_matrix)
  bool want_matrix = false;
  Kokkos::View<double*> elem_psi;      // owned elements: volume-averaged energy density (optional)
  Kokkos::View<double*> elem_J;        // owned elements: volume-averaged J (optional)
  int n_owned_elements = 0;
  int n_owned_dofs = 0;
  double body[3] = {0.0, 0.0, 0.0};    // body force per reference volume
  Projection projection = Projection::Clamp;
};

template <class Model, int NPE, int NQP, class LocalMatrix>
struct ElasticKernel {
  using value_type = AssemblyTotals;
  static constexpr int NDOF = 3 * NPE;
  Model model;
  AssemblyViews<LocalMatrix> v;

  KOKKOS_INLINE_FUNCTION void init(value_type& t) const {
    t.energy = 0.0;
    t.volume = 0.0;
    t.min_J = HUGE_VAL;
    t.inverted = 0;
    t.undefined = 0;
  }
  KOKKOS_INLINE_FUNCTION void join(value_type& a, const value_type& b) const {
    a.energy += b.energy;
    a.volume += b.volume;
    a.min_J = b.min_J < a.min_J ? b.min_J : a.min_J;
    a.inverted += b.inverted;
    a.undefined += b.undefined;
  }
  KOKKOS_INLINE_FUNCTION void join(volatile value_type& a, const volatile value_type& b) const {
    a.energy += b.energy;
    a.volume += b.volume;
    a.min_J = b.min_J < a.min_J ? b.min_J : a.min_J;
    a.inverted += b.inverted;
    a.undefined += b.undefined;
  }

  KOKKOS_INLINE_FUNCTION static void shape_values(int q, double N[NPE]) {
    if constexpr (NPE == 8) {
      double xi[3];
      hex8_gauss_point(q, xi);
      hex8_shape_values(xi, N);
    } else {
      for (int a = 0; a < NPE; ++a) N[a] = 1.0 / NPE;
    }
  }

  KOKKOS_INLINE_FUNCTION void operator()(const int e, value_type& tot) const {
    const bool owned = e < v.n_owned_elements;
    int dof[NDOF];
    double ue[NDOF];
    for (int a = 0; a < NPE; ++a)
      for (int i = 0; i < 3; ++i) {
        dof[3 * a + i] = 3 * v.conn(e, a) + i;
        ue[3 * a + i] = v.u(dof[3 * a + i]);
      }
    const bool want_force = v.force.extent(0) > 0;
    double fe[NDOF];
    for (int k = 0; k < NDOF; ++k) fe[k] = 0.0;
    double Ke[NDOF][NDOF];
    if (v.want_matrix)
      for (int r = 0; r < NDOF; ++r)
        for (int c = 0; c < NDOF; ++c) Ke[r][c] = 0.0;
    double psi_sum = 0.0, J_sum = 0.0, w_sum = 0.0;

    for (int q = 0; q < NQP; ++q) {
      const std::size_t p = static_cast<std::size_t>(e) * NQP + q;
      const double w = v.wdetJ(p);
      double dN[NPE][3];
      for (int a = 0; a < NPE; ++a)
        for (int J = 0; J < 3; ++J) dN[a][J] = v.dNdX(p, a, J);
      Mat3 F = Mat3::identity();
      for (int a = 0; a < NPE; ++a)
        for (int J = 0; J < 3; ++J)
          for (int i = 0; i < 3; ++i) F(i, J) += ue[3 * a + i] * dN[a][J];
      const double Jdet = det(F);
      const bool defined = model.defined(F);
      const double psi = defined ? model.energy(F) : 0.0;
      double N[NPE];
      shape_values(q, N);
      double body_work = 0.0;
      for (int a = 0; a < NPE; ++a)
        for (int i = 0; i < 3; ++i) body_work += N[a] * v.body[i] * ue[3 * a + i];
      if (owned) {
        tot.energy += w * (psi - body_work);
        tot.volume += w * Jdet;
        tot.min_J = Jdet < tot.min_J ? Jdet : tot.min_J;
        if (!(Jdet > 0.0)) ++tot.inverted;
        if (!defined) ++tot.undefined;
      }
      psi_sum += w * psi;
      J_sum += w * Jdet;
      w_sum += w;
      if (want_force) {
        const Mat3 P = model.pk1(F);
        for (int a = 0; a < NPE; ++a)
          for (int i = 0; i < 3; ++i) {
            double s = 0.0;
            for (int J = 0; J < 3; ++J) s += P(i, J) * dN[a][J];
            fe[3 * a + i] += w * (s - N[a] * v.body[i]);
          }
      }
      if (v.want_matrix) {
        const Mat9 H = model.projected_hessian(F, v.projection);
        // G[(iJ)][(b j)] = sum_L H[i+3J][j+3L] dN_b,L ;  K[(a i)][(b j)] += w sum_J dN_a,J G[(iJ)][(b j)]
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
            double* Krow = Ke[3 * a + i];
            const double w0 = w * dN[a][0], w1 = w * dN[a][1], w2 = w * dN[a][2];
            const double* G0 = G[i];
            const double* G1 = G[i + 3];
            const double* G2 = G[i + 6];
            for (int c = 0; c < NDOF; ++c) Krow[c] += w0 * G0[c] + w1 * G1[c] + w2 * G2[c];
          }
      }
    }
    if (owned && v.elem_psi.extent(0) > 0) {
      v.elem_psi(e) = psi_sum / w_sum;
      v.elem_J(e) = J_sum / w_sum;
    }

    // Scatter into owned rows only; Dirichlet DOFs are eliminated symmetrically: their rows and
    // columns are dropped and the diagonal keeps the element's own diagonal entry (a positive scale
    // matching the stiffness, so CG sees a well-conditioned identity-like block there).
    for (int r = 0; r < NDOF; ++r) {
      const int row = dof[r];
      if (row >= v.n_owned_dofs) continue;
      const bool row_fixed = v.fixed(row) != 0;
      if (want_force && !row_fixed) Kokkos::atomic_add(&v.force(row), fe[r]);
      if (v.want_matrix) {
        double vals[NDOF];
        for (int c = 0; c < NDOF; ++c) {
          const bool col_fixed = v.fixed(dof[c]) != 0;
          vals[c] = (row_fixed || col_fixed) ? (dof[c] == row ? Ke[r][c] : 0.0) : Ke[r][c];
        }
        v.matrix.sumIntoValues(row, dof, NDOF, vals, true, true);
      }
    }
  }
};

}  // namespace sinew
