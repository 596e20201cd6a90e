// InertiaTerm (terms/inertia.hpp).
#include <sinew/algebra/system.hpp>
#include <sinew/algebra/terms/inertia.hpp>

#include <Teuchos_CommHelpers.hpp>
#include <Tpetra_CrsMatrix.hpp>
#include <Tpetra_Vector.hpp>

namespace sinew {

namespace {

// out(r, :) += s A(r, :) for the owned rows r (A's pattern lies within out's).
template <class Out>
void add_scaled(const CrsMatrix& A, double s, int owned, Out& out) {
  auto local = A.getLocalMatrixHost();
  std::vector<int> cols;
  std::vector<double> vals;
  for (int r = 0; r < owned; ++r) {
    const auto row = local.row(r);
    cols.resize(row.length);
    vals.resize(row.length);
    for (int k = 0; k < row.length; ++k) {
      cols[k] = row.colidx(k);
      vals[k] = s * row.value(k);
    }
    out.sumIntoValues(r, cols.data(), row.length, vals.data(), true, true);
  }
}

}  // namespace

static_assert(Kokkos::SpaceAccessibility<Kokkos::HostSpace, DeviceMemory>::accessible,
              "the inertia term runs on the host: it needs host-accessible vectors and matrices");

InertiaTerm::InertiaTerm(const System& system, bool lumped) : system_(system), lumped_(lumped) {
  if (!lumped_) M_ = system.mass_matrix(false);
  for (auto* v : {&predictor_, &start_, &d_, &Md_, &e_, &De_}) *v = system.create_vector();
}

void InertiaTerm::set_step(double c, double c_damping, const Vector& predictor, const Vector& start, double alpha,
                           const CrsMatrix* K_start, double beta) {
  c_ = c;
  c_damping_ = c_damping;
  alpha_ = alpha;
  beta_ = beta;
  K_start_ = beta > 0.0 ? K_start : nullptr;
  predictor_->assign(predictor);
  start_->assign(start);
  active_ = true;
}

void InertiaTerm::apply_mass(const Vector& x, Vector& Mx) const {
  if (!lumped_) return M_->apply(x, Mx);
  const auto& m = system_.nodal_mass();
  auto xv = x.getLocalViewHost(Tpetra::Access::ReadOnly);
  auto y = Mx.getLocalViewHost(Tpetra::Access::OverwriteAll);
  for (std::size_t n = 0; n < m.size(); ++n)
    for (int c = 0; c < 3; ++c) y(3 * n + c, 0) = m[n] * xv(3 * n + c, 0);
}

double InertiaTerm::kinetic_energy(const Vector& v) const {
  Vector Mv(v.getMap());
  apply_mass(v, Mv);
  return 0.5 * v.dot(Mv);
}

void InertiaTerm::add(const TermInput& in, TermOutput& out) const {
  if (!active_) return;
  const int owned = out.owned_dofs;
  {
    auto p = predictor_->getLocalViewHost(Tpetra::Access::ReadOnly);
    auto s = start_->getLocalViewHost(Tpetra::Access::ReadOnly);
    auto d = d_->getLocalViewHost(Tpetra::Access::OverwriteAll);
    auto e = e_->getLocalViewHost(Tpetra::Access::OverwriteAll);
    for (int r = 0; r < owned; ++r) {
      d(r, 0) = in.u(r) - p(r, 0);  // the first columns are the owned DOFs
      e(r, 0) = in.u(r) - s(r, 0);
    }
  }
  apply_mass(*d_, *Md_);
  const bool damped = alpha_ > 0.0 || K_start_;
  if (damped) {
    apply_mass(*e_, *De_);
    De_->scale(alpha_);
    if (K_start_) {
      Vector Ke(e_->getMap());
      K_start_->apply(*e_, Ke);
      De_->update(beta_, Ke, 1.0);
    }
  }
  double energy = 0.0;
  {
    auto d = d_->getLocalViewHost(Tpetra::Access::ReadOnly);
    auto Md = Md_->getLocalViewHost(Tpetra::Access::ReadOnly);
    auto e = e_->getLocalViewHost(Tpetra::Access::ReadOnly);
    auto De = De_->getLocalViewHost(Tpetra::Access::ReadOnly);
    for (int r = 0; r < owned; ++r) {
      energy += 0.5 * d(r, 0) * Md(r, 0) / c_;
      if (damped) energy += 0.5 * e(r, 0) * De(r, 0) / c_damping_;
      if (in.want_force) out.force(r) += Md(r, 0) / c_ + (damped ? De(r, 0) / c_damping_ : 0.0);
    }
  }
  if (in.want_matrix) {
    // M / c + (alpha M + beta K_n) / c_d into the rows this rank owns; both matrices live on the mesh's
    // graph, whose column indices are the first ones of the current graph.
    const double sm = 1.0 / c_ + (damped ? alpha_ / c_damping_ : 0.0);
    if (lumped_) {
      const auto& m = system_.nodal_mass();
      for (int r = 0; r < owned; ++r) {
        const double v = sm * m[r / 3];
        out.matrix.sumIntoValues(r, &r, 1, &v, true, true);
      }
    } else {
      add_scaled(*M_, sm, owned, out.matrix);
    }
    if (K_start_) add_scaled(*K_start_, beta_ / c_damping_, owned, out.matrix);
  }
  out.energy += energy;
}

}  // namespace sinew
