// Dynamics: the integrators' predictor, prescribed values and updates (driver/dynamics.hpp).
#include <sinew/driver/dynamics.hpp>

#include <Tpetra_CrsMatrix.hpp>
#include <Tpetra_Vector.hpp>

#include <cstdio>

namespace sinew {

Dynamics::Dynamics(Scene& scene) : scene_(scene), p_(scene.time()), end_time_(scene.time().end_time()) {
  System& sys = scene.system();
  inertia_ = std::make_shared<InertiaTerm>(sys, p_.lumped);
  sys.add_term(inertia_);
  v_ = sys.create_vector();
  predictor_ = sys.create_vector();
  scratch_ = sys.create_vector();
  acceleration_ = sys.create_vector();
  accelerated_ = sys.create_vector();
  scene.initial_velocity(*v_);
  if (p_.rayleigh_stiffness > 0.0) K_start_ = sys.create_mesh_matrix();
}

SolveReport Dynamics::begin(double t0, double t1, const Vector& u, Vector& trial) {
  System& sys = scene_.system();
  h_ = (t1 - t0) * end_time_;
  const bool midpoint = p_.integrator == TimeParameters::Integrator::ImplicitMidpoint;
  const double reach = midpoint ? 0.5 * h_ : h_;  // how far y lies from u_n, in time
  predictor_->update(1.0, u, reach, *v_, 0.0);
  trial.assign(*predictor_);
  scene_.predict_acceleration(t0, t1, u, trial, reach / h_);
  if (midpoint) {
    // y's prescribed values: the averages of u_n's (those at t0) and those at t1.
    scratch_->assign(u);
    scene_.apply_load(t1, *scratch_);
    auto y = trial.getLocalViewHost(Tpetra::Access::ReadWrite);
    auto a = u.getLocalViewHost(Tpetra::Access::ReadOnly);
    auto b = scratch_->getLocalViewHost(Tpetra::Access::ReadOnly);
    for (int d : sys.fixed_owned_dofs()) y(d, 0) = 0.5 * (a(d, 0) + b(d, 0));
    scratch_->assign(u);
    scene_.apply_load(0.5 * (t0 + t1), *scratch_);  // colliders and loads at the midpoint
  } else {
    scene_.apply_load(t1, trial);
  }
  // Where forces that do not depend on u accelerate the body (gravity, a body force), the free DOFs may
  // start reach^2 a further on (EnergyTerm::add_load_acceleration): a falling body is then in
  // equilibrium at its first guess, where u_n + reach v_n leaves the whole of M a to the first Newton
  // iteration (the squash's free fall: 2 iterations a substep, then none). Taken only where it lowers
  // the step's energy: a body resting on a collider is held there, not accelerated, and pushing its
  // contact into the collider cost each of the squash's resting substeps an iteration (1,460 Newton
  // iterations in its 480 substeps with the acceleration always, 1,291 without, 1,245 chosen).
  const bool accelerate = sys.load_acceleration(*acceleration_);
  if (accelerate) {
    accelerated_->assign(trial);
    const std::vector<char> fixed = sys.fixed_owned_mask();
    auto y = accelerated_->getLocalViewHost(Tpetra::Access::ReadWrite);
    auto a = acceleration_->getLocalViewHost(Tpetra::Access::ReadOnly);
    for (std::size_t i = 0; i < fixed.size(); ++i)
      if (!fixed[i]) y(i, 0) += reach * reach * a(i, 0);
  }
  if (K_start_) sys.elastic_hessian(u, *K_start_);
  inertia_->set_step(reach * reach, reach, *predictor_, u, p_.rayleigh_mass, K_start_.get(), p_.rayleigh_stiffness);
  if (accelerate) {
    const EvaluationTotals plain = sys.evaluate(trial, nullptr, nullptr), on = sys.evaluate(*accelerated_, nullptr, nullptr);
    if (on.energy_defined() && !(plain.energy_defined() && plain.energy <= on.energy)) trial.assign(*accelerated_);
  }
  return {};
}

void Dynamics::end(double, double, const Vector& y, Vector& u) {
  inertia_->off();
  if (p_.integrator == TimeParameters::Integrator::ImplicitMidpoint) {
    // u_(n+1) = 2 y - u_n; v_(n+1) = 2 (u_(n+1) - u_n) / h - v_n = 4 (y - u_n) / h - v_n
    v_->update(4.0 / h_, y, -4.0 / h_, u, -1.0);
    u.update(2.0, y, -1.0);
  } else {
    v_->update(1.0 / h_, y, -1.0 / h_, u, 0.0);
    u.assign(y);
  }
}

std::string Dynamics::describe(double load) const {
  char buf[48];
  std::snprintf(buf, sizeof buf, "t = %.6g s", time_of(load));
  return buf;
}

void Dynamics::record(StepRecord& rec) const {
  rec.time = time_of(rec.load);
  rec.kinetic = kinetic_energy();
}

std::vector<std::string> Dynamics::summary(const StepRecord& rec) const {
  // The mechanical energy: kinetic plus every term's share but inertia's (the step's incremental
  // potential, zero at the step's end state only for an undamped step).
  std::string parts;
  double total = rec.kinetic;
  for (const auto& [name, e] : rec.totals.shares) {
    if (std::string(name) == inertia_->name()) continue;
    char buf[96];
    std::snprintf(buf, sizeof buf, ", %s %.6g", name, e);
    parts += buf;
    total += e;
  }
  char buf[128];
  std::snprintf(buf, sizeof buf, "t = %.6g s: kinetic %.6g", rec.time, rec.kinetic);
  char tail[64];
  std::snprintf(tail, sizeof tail, " (total %.6g)", total);
  return {std::string(buf) + parts + tail};
}

}  // namespace sinew
