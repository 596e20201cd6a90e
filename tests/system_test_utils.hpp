// Helpers for tests on a System: lattice boxes, displacement fields, dense copies of small distributed
// matrices and their smallest eigenvalue (LAPACK).
#pragma once

#include "tpetra_test_utils.hpp"

#include <sinew/algebra/system.hpp>
#include <sinew/core/hash.hpp>

#include <Teuchos_CommHelpers.hpp>
#include <Teuchos_LAPACK.hpp>
#include <Tpetra_CrsMatrix.hpp>
#include <Tpetra_Import.hpp>
#include <Tpetra_Vector.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace sinew::test {

inline MeshSpec box(int n, ElementType t = ElementType::Hex8, int nz = -1) {
  MeshSpec s;
  s.element = t;
  s.cells = {n, n, nz > 0 ? nz : n};
  s.lower = {0.0, 0.0, 0.0};
  s.upper = {1.0, 0.8, 1.2};
  return s;
}

// Sets u from a function of the reference position and component, on owned DOFs.
template <class Fn>
inline void set_displacement(const System& sys, Vector& u, Fn&& fn) {
  auto X = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys.mesh().X);
  auto v = u.getLocalViewHost(Tpetra::Access::OverwriteAll);
  for (std::size_t n = 0; n < sys.mesh().n_owned_nodes; ++n) {
    const std::array<double, 3> x{X(n, 0), X(n, 1), X(n, 2)};
    for (int c = 0; c < 3; ++c) v(3 * n + c, 0) = fn(x, c, sys.mesh().node_gid[n]);
  }
}

// Per global DOF (on every rank): whether it is a Dirichlet DOF of sys.
inline std::vector<char> fixed_flags(const System& sys) {
  Vector f(sys.owned_dofs());
  f.putScalar(0.0);
  {
    auto v = f.getLocalViewHost(Tpetra::Access::ReadWrite);
    for (int d : sys.fixed_owned_dofs()) v(d, 0) = 1.0;
  }
  const auto all = gather(f);
  std::vector<char> fixed(all.size(), 0);
  for (std::size_t i = 0; i < all.size(); ++i) fixed[i] = all[i] != 0.0;
  return fixed;
}

// Deterministic pseudo-random number in [-1, 1] from a node id and component (same on every rank).
inline double hash_unit(long long gid, int c, int salt = 0) { return 2.0 * unit_hash(gid, c, salt + 1) - 1.0; }

// Dense copy of a distributed matrix on every rank (small test matrices only), via columns K e_j.
inline std::vector<std::vector<double>> dense(const CrsMatrix& K) {
  const std::size_t n = K.getGlobalNumRows();
  std::vector<std::vector<double>> D(n, std::vector<double>(n));
  Vector e(K.getDomainMap()), col(K.getRangeMap());
  for (std::size_t j = 0; j < n; ++j) {
    e.putScalar(0.0);
    if (K.getDomainMap()->isNodeGlobalElement(static_cast<GO>(j))) e.replaceGlobalValue(static_cast<GO>(j), 1.0);
    K.apply(e, col);
    const auto c = gather(col);
    for (std::size_t i = 0; i < n; ++i) D[i][j] = c[i];
  }
  return D;
}

inline double max_abs(const std::vector<std::vector<double>>& A) {
  double m = 0.0;
  for (const auto& r : A)
    for (double x : r) m = std::max(m, std::fabs(x));
  return m;
}

// What a term reads and adds into for a state u alone: u imported onto the System's column map (into
// uc, which must outlive the call) and this rank's owned rows.
inline void term_call(const System& sys, const Vector& u, Vector& uc, TermInput& in, TermOutput& out) {
  uc.doImport(u, Import(sys.owned_dofs(), sys.column_dofs()), Tpetra::INSERT);
  auto uv = uc.getLocalViewDevice(Tpetra::Access::ReadOnly);
  in.u = Kokkos::subview(uv, Kokkos::ALL(), 0);
  out.owned_dofs = static_cast<int>(sys.owned_dofs()->getNodeNumElements());
}

// One term's Hessian alone at u (no Dirichlet elimination), as a dense matrix.
inline std::vector<std::vector<double>> term_hessian(const System& sys, const EnergyTerm& term, const Vector& u,
                                                     bool exact_terms = false) {
  auto K = sys.create_matrix();
  Vector uc(sys.column_dofs());
  K->resumeFill();
  K->setAllToScalar(0.0);
  TermInput in;
  TermOutput out;
  term_call(sys, u, uc, in, out);
  in.want_matrix = true;
  in.exact_terms = exact_terms;
  out.matrix = K->getLocalMatrixDevice();
  term.add(in, out);
  K->fillComplete();
  return dense(*K);
}

// One term's energy alone at u (summed over ranks), and its gradient into f when given (collective).
inline double term_energy(const System& sys, const EnergyTerm& term, const Vector& u, Vector* f = nullptr) {
  Vector uc(sys.column_dofs());
  TermInput in;
  TermOutput out;
  term_call(sys, u, uc, in, out);
  if (f) {
    f->putScalar(0.0);
    in.want_force = true;
    out.force = Kokkos::subview(f->getLocalViewDevice(Tpetra::Access::ReadWrite), Kokkos::ALL(), 0);
  }
  term.add(in, out);
  double all = 0.0;
  Teuchos::reduceAll(*sys.comm(), Teuchos::REDUCE_SUM, out.energy, Teuchos::outArg(all));
  return all;
}

// A term's derivatives at u along d against central differences of step h (collective): the directional
// derivative f.d and the energy's difference dE; the largest |H d - (f(u + h d) - f(u - h d)) / 2h| and
// the largest entry of that difference (scale); H's smallest eigenvalue and largest entry.
struct TermDerivativeCheck {
  double dE = 0.0, f_dot_d = 0.0, err = 0.0, scale = 0.0, min_eigenvalue = 0.0, max_entry = 0.0;
};
inline double min_eigenvalue(const std::vector<std::vector<double>>& A);
inline TermDerivativeCheck check_term_derivatives(const System& sys, const EnergyTerm& term, const Vector& u, const Vector& d,
                                                  double h = 1e-6, bool exact_terms = false) {
  TermDerivativeCheck r;
  auto f = sys.create_vector(), fp = sys.create_vector(), fm = sys.create_vector();
  auto up = sys.create_vector(), um = sys.create_vector();
  term_energy(sys, term, u, f.get());
  up->update(1.0, u, h, d, 0.0);
  um->update(1.0, u, -h, d, 0.0);
  r.dE = (term_energy(sys, term, *up, fp.get()) - term_energy(sys, term, *um, fm.get())) / (2.0 * h);
  r.f_dot_d = f->dot(d);
  const auto H = term_hessian(sys, term, u, exact_terms);
  const auto dg = gather(d), fpg = gather(*fp), fmg = gather(*fm);
  for (std::size_t row = 0; row < H.size(); ++row) {
    double Hd = 0.0;
    for (std::size_t c = 0; c < H.size(); ++c) Hd += H[row][c] * dg[c];
    const double fd = (fpg[row] - fmg[row]) / (2.0 * h);
    r.err = std::max(r.err, std::fabs(Hd - fd));
    r.scale = std::max(r.scale, std::fabs(fd));
  }
  r.min_eigenvalue = min_eigenvalue(H);
  r.max_entry = max_abs(H);
  return r;
}

// Smallest eigenvalue of a dense symmetric matrix (LAPACK).
inline double min_eigenvalue(const std::vector<std::vector<double>>& A) {
  const int n = static_cast<int>(A.size());
  std::vector<double> a(n * n), w(n), work(64 * n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) a[i + n * j] = 0.5 * (A[i][j] + A[j][i]);
  int info = 0;
  Teuchos::LAPACK<int, double>().SYEV('N', 'U', n, a.data(), n, w.data(), work.data(), 64 * n, &info);
  EXPECT_EQ(info, 0);
  return w[0];
}

}  // namespace sinew::test
