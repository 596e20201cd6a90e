// Quasi-static load steps: the first guess and its predictors (driver/quasi_static.hpp).
#include <sinew/driver/quasi_static.hpp>
#include <sinew/solver/nonlinear_solver.hpp>

#include <Tpetra_Vector.hpp>

#include <cmath>
#include <cstdio>

namespace sinew {

SolveReport QuasiStatic::begin(double t0, double t, const Vector& u, Vector& trial) {
  const System& sys = scene_.system();
  SolveReport tangent;
  trial.assign(u);
  scene_.predict(t0, t, trial);
  scene_.apply_load(t, trial);
  const double span = t0 - at_.previous_load;
  const bool extrapolate = scene_.extrapolate() && at_.previous_load >= 0.0 && span > 1e-14;
  // The tangent where nothing extrapolates: from the second step on the extrapolation starts closer (the
  // 32 x 32 x 64 stretch's second step from the tangent: 5 Newton iterations, extrapolated: 3, although
  // the tangent's energy was the lower; the shipped rigs without contact: the same Newton counts, 23 and
  // 24, 43 and 42, with the predictor's CG on top). And at every step where a term bounds the guess's
  // path (the barrier contact's collision test): a skinning or extrapolated guess that folds a crease
  // is pulled back towards the last state, and the first Newton iterations then spread the bones'
  // motion through the flesh, each bounded again; the linearised step starts nearer (BCN's mocap jump:
  // 881 Newton iterations in 48 frames, max 179, against 568, max 40). Not with a term set up at the
  // last state (the springs: the linearisation knows only the pairs of the last state, so it can push
  // free nodes through a surface before the step's detection sees them; two blocks pressed together on
  // 2 ranks then ended in another contact state than on 1).
  const bool linearise = scene_.tangent_predictor() && at_equilibrium_ && (!extrapolate || sys.limits_steps()) && sys.linearisable();
  if (!extrapolate && !linearise) return tangent;
  // A candidate replaces the guess when its energy is defined and below the guess's (or the guess's is not).
  EvaluationTotals best = sys.evaluate(trial, nullptr, nullptr);
  const char* chosen = "the last state";
  auto consider = [&](const Vector& candidate, const char* name) {
    const EvaluationTotals e = sys.evaluate(candidate, nullptr, nullptr);
    if (e.energy_defined() && !(best.energy_defined() && best.energy <= e.energy)) {
      trial.assign(candidate);
      best = e;
      chosen = name;
    }
  };
  if (extrapolate) {
    auto candidate = sys.create_vector();
    // u + (t - t0) / (t0 - previous) (u - u_previous): exact for a displacement linear in the load.
    candidate->update(1.0 + (t - t0) / span, u, -(t - t0) / span, u_previous_, 0.0);
    scene_.apply_load(t, *candidate);
    consider(*candidate, "extrapolated");
  }
  if (linearise) {
    tangent = solver_.tangent(u, trial, best.energy_defined() ? best.energy : HUGE_VAL);
    if (tangent.converged()) chosen = "tangent";
    if (talk_) {
      std::printf("  predictor: %s (tangent: %d CG)\n", chosen, tangent.linear_iterations);
      std::fflush(stdout);
    }
  }
  return tangent;
}

void QuasiStatic::end(double t0, double, const Vector& y, Vector& u) {
  if (scene_.extrapolate()) {
    u_previous_.assign(u);
    at_.previous_load = t0;
  }
  u.assign(y);
}

std::string QuasiStatic::describe(double load) const {
  char buf[48];
  std::snprintf(buf, sizeof buf, "load %.4g", load);
  return buf;
}

}  // namespace sinew
