// The load-step loop: each step is solved from the previous state with its prescribed motion, cut in
// half on failure; progress lines, the log, step files and checkpoints follow every converged step.
#include <sinew/core/errors.hpp>
#include <sinew/core/exit_codes.hpp>
#include <sinew/discretization/rig_file.hpp>
#include <sinew/driver/dynamics.hpp>
#include <sinew/driver/quasi_static.hpp>
#include <sinew/driver/info.hpp>
#include <sinew/driver/run.hpp>
#include <sinew/driver/signals.hpp>
#include <sinew/io/output.hpp>
#include <sinew/scenes/scene.hpp>
#include <sinew/scenes/skeleton.hpp>
#include <sinew/solver/nonlinear_solver.hpp>

#include <Teuchos_CommHelpers.hpp>
#include <Teuchos_TimeMonitor.hpp>
#include <Tpetra_Core.hpp>
#include <Tpetra_Vector.hpp>

#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>

namespace sinew {

namespace {

double wall_seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// "1h02m", "3m05s", "12.3s"
std::string duration(double s) {
  char buf[32];
  if (s >= 3600.0)
    std::snprintf(buf, sizeof buf, "%dh%02dm", static_cast<int>(s / 3600.0), static_cast<int>(std::fmod(s, 3600.0) / 60.0));
  else if (s >= 60.0)
    std::snprintf(buf, sizeof buf, "%dm%02ds", static_cast<int>(s / 60.0), static_cast<int>(std::fmod(s, 60.0)));
  else
    std::snprintf(buf, sizeof buf, "%.1fs", s);
  return buf;
}

// ", rounds 0.12" when the terms' rounds between solves (contact detection) took time.
std::string rounds_time(const StepRecord& rec) {
  if (rec.seconds_rounds == 0.0) return "";
  char buf[64];
  std::snprintf(buf, sizeof buf, ", rounds %.2f", rec.seconds_rounds);
  return buf;
}

// Two attempts' Newton residuals agree to 4 digits, iteration by iteration.
bool same_path(const std::vector<double>& a, const std::vector<double>& b) {
  if (a.empty() || a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (!(std::fabs(a[i] - b[i]) <= 1e-4 * std::max(std::fabs(a[i]), std::fabs(b[i])))) return false;
  return true;
}

}  // namespace

Simulation::Simulation(const SceneConfig& config, const RunOptions& options, Teuchos::RCP<const Teuchos::Comm<int>> comm)
    : config_(config), opt_(options), comm_(comm.is_null() ? Tpetra::getDefaultComm() : comm) {
  scene_ = std::make_unique<Scene>(config_.scene(), comm_);
  solver_ = std::make_unique<NonlinearSolver>(scene_->system(), config_.params.solver);
  talk_ = comm_->getRank() == 0 && !opt_.quiet;
  u_ = scene_->system().create_vector();
  u_previous_ = scene_->system().create_vector();
  if (scene_->dynamic())
    stepper_ = std::make_unique<Dynamics>(*scene_);
  else
    stepper_ = std::make_unique<QuasiStatic>(*scene_, *solver_, at_, *u_previous_, at_equilibrium_, talk_, config_.params.time.frame_rate);
  // The sections that define the problem solved (not Solver or Output, which a restart may change).
  const auto& p = config_.params;
  Output::Physics physics{{"Mesh", section_fingerprint(p.mesh)},
                          {"Material", section_fingerprint(p.material)},
                          {"Loading", section_fingerprint(p.loading)},
                          {"Skeleton", section_fingerprint(p.skeleton)},
                          {"Time", section_fingerprint(p.time)}};
  p.terms.for_each([&](const char* section, const auto& params) { physics.push_back({section, section_fingerprint(params)}); });
  int restart_step = -1;
  if (!opt_.restart_file.empty()) {
    Output::TermStates states;
    at_ = Output::read_checkpoint(opt_.restart_file, scene_->system(), scene_->steps(), *u_, u_previous_.get(),
                                  stepper_->velocity(), opt_.restart_anyway ? nullptr : &physics, &states);
    scene_->system().load_states(states);
    restart_step = at_.step;
  }
  OutputParameters output = config_.params.output;
  if (scene_->dynamic()) output.every *= scene_->time().substeps;  // Output/Every counts frames
  out_ = std::make_unique<Output>(output, scene_->system(), scene_->name(), scene_->steps(), restart_step);
  out_->set_physics(physics);
  // A rigged character: the file's own linear-blend skin posed at the clip's time of each written
  // step, beside the simulated skin: the same meshes, with the simulated skin's triangles (the lattice
  // carries the skin as voxelized; rank 0, which calls this, holds it).
  const Skeleton& skeleton = scene_->skeleton();
  const Mesh& mesh = scene_->system().mesh();
  if (p.mesh.type == MeshType::Rig && skeleton.rig() && p.mesh.rig == p.skeleton.rig)
    out_->add_surface_sequence("lbs", [&skeleton, &mesh, meshes = p.mesh.rig_meshes](double load, std::vector<double>& x,
                                                                                     std::vector<std::array<int, 3>>& triangles) {
      x.clear();
      for (const auto& v : rig_surface(*skeleton.rig(), meshes, skeleton.rig_pose(load)).vertices) x.insert(x.end(), v.begin(), v.end());
      triangles = mesh.embedded->triangles;
    });
  // The skin's caches: frames at the clip's times for a rig, at the run's times for dynamics, else one
  // load step a frame; a rig's nodes animated beside the skin.
  const double frame_rate = p.time.frame_rate;
  if (skeleton.rig())
    out_->set_frame_clock([&skeleton](double load) { return skeleton.rig_seconds(load); }, frame_rate);
  else
    out_->set_frame_clock([s = stepper_.get()](double load) { return s->time_of(load); }, frame_rate);
  if (skeleton.rig() && out_->skin_caches()) {
    SkinRig rig;
    for (const RigNode& node : skeleton.rig()->nodes) {
      rig.names.push_back(node.name);
      rig.parents.push_back(node.parent);
    }
    rig.pose = [&skeleton](double load) { return skeleton.rig_pose(load); };
    out_->set_skin_rig(std::move(rig));
  }
  // Signals are checked collectively, so that every rank stops at the same point.
  auto comm_copy = comm_;
  stop_check_ = [comm_copy] {
    int s = pending_signal(), any = 0;
    Teuchos::reduceAll(*comm_copy, Teuchos::REDUCE_MAX, s, Teuchos::outArg(any));
    return any;
  };
  // Tests stop a run after a given step exactly as SIGTERM would, without racing a signal against a
  // fast run (tests/restart_layout_test.sh).
  if (const char* after = std::getenv("SINEW_STOP_AFTER_STEP")) {
    const int k = std::atoi(after);
    stop_check_ = [this, k, check = stop_check_] { return at_.step >= k ? SIGTERM : check(); };
  }
  solver_->set_interrupt([this] { return (stop_signal_ = stop_check_()) != 0; });
}

Simulation::~Simulation() = default;

const Vector* Simulation::velocity() const { return stepper_->velocity(); }

void Simulation::set_stop_check(std::function<int()> check) { stop_check_ = std::move(check); }

void Simulation::set_initial(const Vector& u, const Vector* velocity) {
  if (!opt_.restart_file.empty()) throw std::logic_error("Simulation::set_initial: not with a restart");
  u_->assign(u);
  if (velocity && stepper_->velocity()) stepper_->velocity()->assign(*velocity);
  initial_given_ = true;
}

void Simulation::print_header() const {
  const System& sys = scene_->system();
  const std::size_t prescribed = sys.global_fixed_dofs();  // collective: outside the rank-0 block
  // A dynamic rig: do the bones outrun the flesh's shear waves? (collective; only for a header that is
  // printed: --quiet is the same on every rank)
  const TimeParameters& time = config_.params.time;
  Skeleton::PeakSpeed bones;
  if (!opt_.quiet && time.dynamic() && !config_.params.skeleton.rig.empty())
    bones = scene_->skeleton().peak_speed(sys.mesh(), *comm_, time.steps(), time.end_time());
  if (!talk_) return;
  std::printf("Sinew: scene '%s' (%s), %s, %d MPI rank%s\n", scene_->name().c_str(), config_.file.c_str(),
              execution_space_summary().c_str(), comm_->getSize(), comm_->getSize() > 1 ? "s" : "");
  std::printf("  mesh: %lld %s elements, %lld nodes, %lld DOFs (%zu prescribed)\n",
              static_cast<long long>(sys.mesh().global_elements), to_string(sys.mesh().type).c_str(),
              static_cast<long long>(sys.mesh().global_nodes), 3LL * sys.mesh().global_nodes, prescribed);
  for (const auto& note : sys.mesh().notes) std::printf("  mesh note: %s\n", note.c_str());
  for (const auto& term : sys.terms())
    for (const auto& note : term->notes()) std::printf("  %s note: %s\n", term->name(), note.c_str());
  std::printf("  material: %s\n", describe(sys.material()).c_str());
  if (!config_.params.skeleton.rig.empty()) {
    const Skeleton& sk = scene_->skeleton();
    std::printf("  skeleton: %s; %s bones; motion made rigid to %.1e\n", sk.joint_summary().c_str(),
                config_.params.skeleton.attachment_word(), sk.nonrigid());
  }
  if (bones.speed > 0.0) {
    // Flesh follows its bones by shear waves. Where the bones move faster than those travel, a layer of
    // flesh lags behind however the solver does: FBX/huesitos.fbx (5.4 m across, E = 2e4) has bones at
    // 29 m/s against waves at 2.6 m/s, and with inertia 139 inverted points by frame 4 (1,528 by frame
    // 21 without contact). Not a verdict: the FBX bar's bones reach 3.6 times its waves' speed and it
    // runs clean (docs/performance.md), so the numbers are printed for the user to weigh.
    const MaterialSpec& m = sys.material();
    std::printf("  bones: up to %.3g m/s ('%s', frame %d) and %.3g m/s^2; shear waves in the flesh: %.3g m/s (sqrt(mu_L / density))\n",
                bones.speed, bones.bone.c_str(), (bones.sample + time.substeps - 1) / time.substeps, bones.acceleration,
                std::sqrt(m.mu_L / m.density));
  }
  if (scene_->run_up_steps() > 0 && at_.step == 0 && at_.load == 0.0)
    std::printf("  run-up: %d step%s from the rest pose to load 0 (a bone turns by up to %.0f degrees)\n", scene_->run_up_steps(),
                scene_->run_up_steps() == 1 ? "" : "s", scene_->skeleton().largest_start_rotation() * 180.0 / M_PI);
  std::printf("  %d load step%s; converged when |F| < %g; results in %s\n", scene_->steps(), scene_->steps() > 1 ? "s" : "",
              solver_->absolute_tolerance(), out_->directory().c_str());
  if (at_.step > 0 || at_.load > 0.0)
    std::printf("  restarting after step %d at load %.6g from %s\n", at_.step, at_.load, opt_.restart_file.c_str());
  for (const auto& note : at_.notes) std::printf("  restart note: %s\n", note.c_str());
  std::fflush(stdout);
}

Simulation::StepOutcome Simulation::advance(int k, StepRecord& rec) {
  Scene& scene = *scene_;
  const int n = scene.steps();
  const double target = static_cast<double>(k) / n;
  // A restart inside a cut step continues with the increment and cuts it had.
  double dt = at_.increment > 0.0 ? at_.increment : target - at_.load;
  rec.cuts = at_.cuts;
  auto trial = scene.system().create_vector();
  bool first_attempt = true;
  // The Newton residuals of this attempt, and of the last failed one from the same state: a cut that
  // repeats them (to 4 digits) shows that the trouble does not depend on the load, so cutting again
  // would only repeat it (a character's contact found inside at rest did so through 6 cuts).
  std::vector<double> residuals, failed_before;
  double failed_from = -1.0;
  while (at_.load < target - 1e-14) {
    const double t = std::min(at_.load + dt, target);
    SolveReport predicted;  // the tangent predictor's solve, when there is one
    scene.system().begin_step(StepStart{at_.load, t, u_.get(), first_attempt && rec.cuts == 0});
    first_attempt = false;
    predicted = stepper_->begin(at_.load, t, *u_, *trial);
    rec.first_guess = admit_guess(*trial);
    if (talk_) {
      const double now = wall_seconds(), done = at_.load - start_load_, elapsed = now - started_;
      // The pace of the last two steps, not of the whole run: steps grow as a motion creases the
      // flesh (a character's steps went from 12 s to over 100 s while an average promised a minute).
      if (pace_.empty() || pace_.back().first < at_.load) pace_.emplace_back(at_.load, now);
      const auto& from = pace_[pace_.size() >= 3 ? pace_.size() - 3 : 0];
      std::string eta;
      if (done > 1e-12 && elapsed > 1.0 && at_.load - from.first > 1e-12)
        eta = ", ~" + duration((now - from.second) / (at_.load - from.first) * (1.0 - at_.load)) + " left";
      std::printf("step %d/%d  %s%s%s%s  (%s elapsed%s)\n", k, n, stepper_->describe(t).c_str(),
                  rec.cuts ? "  (after cutting the " : "", rec.cuts ? stepper_->cut_name() : "", rec.cuts ? ")" : "",
                  duration(elapsed).c_str(), eta.c_str());
      std::fflush(stdout);
    }
    residuals.clear();
    const SolveReport r = solve(*trial, newton_progress(k, t, residuals), rec);
    rec.solve.accumulate(predicted);
    rec.solve.accumulate(r);
    if (rec.solve.initial_residual == 0.0) rec.solve.initial_residual = r.initial_residual;
    rec.solve.final_residual = r.final_residual;
    if (r.converged()) {
      stepper_->end(at_.load, t, *trial, *u_);
      scene.system().end_step(*u_);
      at_.load = t;
      at_.increment = t < target - 1e-14 ? dt : 0.0;
      at_equilibrium_ = true;
      continue;
    }
    // Interrupted: the terms keep the state this attempt started from, which the checkpoint records.
    if (r.status == SolveStatus::Interrupted) return StepOutcome::Stopped;
    scene.system().abandon_step();
    if (talk_) std::printf("  step did not converge: %s\n", r.reason().c_str());
    if (failed_from == at_.load && same_path(residuals, failed_before)) {
      if (comm_->getRank() == 0)
        std::fprintf(stderr,
                     "sinew: step %d did not converge, and cutting the %s made no difference: the attempt after cut %d "
                     "repeated the one before it (%zu Newton iterations, the same residuals to 4 digits), so the "
                     "trouble does not depend on the load (%s); the last converged state (load %.6g) is in %s\n",
                     k, stepper_->cut_name(), rec.cuts, residuals.size(), r.reason().c_str(), at_.load, out_->directory().c_str());
      return StepOutcome::Failed;
    }
    failed_from = at_.load;
    failed_before = residuals;
    if (rec.cuts >= scene.max_cuts()) {
      if (comm_->getRank() == 0)
        std::fprintf(stderr,
                     "sinew: step %d did not converge after %d cut%s of the load increment (%s); the last converged "
                     "state (load %.6g) is in %s\n",
                     k, rec.cuts, rec.cuts == 1 ? "" : "s", r.reason().c_str(), at_.load, out_->directory().c_str());
      return StepOutcome::Failed;
    }
    ++rec.cuts;
    dt *= 0.5;
    at_.increment = dt;
    at_.cuts = rec.cuts;
  }
  return StepOutcome::Done;
}

std::function<void(const NewtonIterate&)> Simulation::newton_progress(int step, double t, std::vector<double>& residuals) {
  return [this, step, t, &residuals](const NewtonIterate& it) {
    residuals.push_back(it.residual);
    out_->log_newton(step, t, it);
    if (!talk_) return;
    char du[32] = "", bound[32] = "";
    if (std::isfinite(it.direction_max)) std::snprintf(du, sizeof du, "  |du| %.2e", it.direction_max);
    if (std::isfinite(it.step_bound)) std::snprintf(bound, sizeof bound, " (bound %.3g)", it.step_bound);
    std::printf("  newton %3d  |F| = %.3e  CG %4d  step %.3g%s%s%s\n", it.iteration, it.residual, it.linear_iterations, it.step, bound, du,
                it.exact_terms ? "  (exact Hessian, every term)" : it.exact_hessian ? "  (exact Hessian)" : "");
    std::fflush(stdout);
  };
}

Simulation::StepOutcome Simulation::run_up() {
  // Quasi-static steps (no inertia: a dynamic run's time has not started) that carry the bones from the
  // rest pose to their pose at load 0, cut in half on failure; the state reached is the run's start.
  Scene& scene = *scene_;
  const int R = scene.run_up_steps();
  if (R == 0) return StepOutcome::Done;
  auto trial = scene.system().create_vector();
  double s = 0.0, ds = 1.0 / R;
  int cuts = 0, step = 0;
  std::vector<double> residuals, failed_before;
  while (s < 1.0 - 1e-14) {
    const double s1 = std::min(1.0, s + ds);
    trial->assign(*u_);
    scene.predict_run_up(s, s1, *trial);
    scene.set_run_up(s1);
    scene.system().begin_step(StepStart{0.0, 0.0, u_.get(), true});
    scene.apply_load(0.0, *trial);
    admit_guess(*trial);
    if (talk_) {
      std::printf("run-up %d/%d  the bones %.3g of the way from the rest pose%s\n", ++step, R, s1, cuts ? "  (after a cut)" : "");
      std::fflush(stdout);
    }
    residuals.clear();
    StepRecord rec;
    const SolveReport r = solve(*trial, newton_progress(0, 0.0, residuals), rec);
    if (r.converged()) {
      scene.system().end_step(*trial);
      u_->assign(*trial);
      s = s1;
      failed_before.clear();
      if (talk_) {
        std::printf("  converged: %d Newton, %d CG; %.2f s\n", r.newton_iterations, r.linear_iterations, r.seconds_total);
        std::fflush(stdout);
      }
      continue;
    }
    scene.system().abandon_step();
    scene.set_run_up(s);
    if (r.status == SolveStatus::Interrupted) return StepOutcome::Stopped;
    if (cuts >= scene.max_cuts() || same_path(residuals, failed_before)) {
      if (comm_->getRank() == 0)
        std::fprintf(stderr,
                     "sinew: the run-up from the rest pose to load 0 did not converge %.3g of the way, after %d cut%s (%s); "
                     "give the rest pose nearer the clip's start ('Rest time') or more 'Run-up steps'\n",
                     s1, cuts, cuts == 1 ? "" : "s", r.reason().c_str());
      return StepOutcome::Failed;
    }
    failed_before = residuals;
    ++cuts;
    ds *= 0.5;
  }
  return StepOutcome::Done;
}

double Simulation::admit_guess(Vector& trial) {
  // A contact barrier admits no guess whose path from the last state passes a surface point through a
  // face (System::admit_guess): the skinning guess of a crease is pulled back towards the last state.
  const double taken = scene_->system().admit_guess(*u_, trial);
  if (talk_ && taken < 1.0) {
    std::printf("  first guess: %.3g of the way (the rest would pass the surface through itself)\n", taken);
    std::fflush(stdout);
  }
  return taken;
}

SolveReport Simulation::solve(Vector& trial, const std::function<void(const NewtonIterate&)>& progress,
                              StepRecord& rec) {
  System& sys = scene_->system();
  SolveReport sum;
  double first_residual = 0.0;
  // Round 0 sets the terms up at the first guess (contact pairs); after each converged solve the terms
  // look at its state again, and the step ends when none asks for another solve.
  for (int round = 0;; ++round) {
    const auto start = std::chrono::steady_clock::now();
    const System::Round terms = sys.round(trial, round);
    // Counted where a term has rounds (it reports them), so that a scene without shows none.
    if (!terms.lines.empty()) rec.seconds_rounds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    rec.pattern_changes += terms.pattern_changed;
    if (talk_) {
      for (const auto& line : terms.lines) std::printf("  %s\n", line.c_str());
      std::fflush(stdout);
    }
    if (round > 0 && !terms.again) break;  // round 0 always solves
    // A later round's solve starts near equilibrium: its exact Hessian is due relative to the step's
    // first residual (NonlinearSolver::solve). Where a term can regroup (self contact), a solve that has
    // not converged after 'Regroup after' Newton iterations stops for them to look at its state again
    // (a sample that slid past its frozen target into the body gets its spring within the solve, not
    // after it: BCN's crease slid for 40 iterations), then goes on, within 'Maximum iterations' in all.
    // (Stopping the stops after two regroups in a row that changed nothing measured worse: BCN's clip
    // 3,161 Newton iterations against 2,216 and 2,415 without, on 2 threads.)
    const SolverParameters& sp = config_.params.solver;
    const bool regroup = sp.regroup_after > 0 && sys.regroups();
    int used = 0;
    for (int chunk = 0;; ++chunk) {
      const int budget = regroup && sp.max_iterations - used > sp.regroup_after ? sp.regroup_after : sp.max_iterations - used;
      SolveReport r = solver_->solve(trial, progress, first_residual, budget);
      if (round == 0 && chunk == 0) first_residual = r.initial_residual;
      used += r.newton_iterations;
      if (round > 0 || chunk > 0) r.accumulate(sum);
      sum = r;
      sum.max_iterations = sp.max_iterations;  // what a failure reports: the round's limit, not a chunk's
      if (r.status != SolveStatus::MaxIterations || used >= sp.max_iterations) break;
      const auto t0 = std::chrono::steady_clock::now();
      const System::Round again = sys.regroup(trial);
      rec.seconds_rounds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      rec.pattern_changes += again.pattern_changed;
      if (talk_)
        for (const auto& line : again.lines) std::printf("  %s\n", line.c_str());
    }
    if (!sum.converged()) break;
  }
  return sum;
}

void Simulation::write_step(int step, double load) {
  Output::NodeFields fields;
  if (const Vector* velocity = stepper_->velocity()) {
    auto v = velocity->getLocalViewHost(Tpetra::Access::ReadOnly);
    fields.emplace_back("velocity", std::vector<double>(v.data(), v.data() + 3 * scene_->system().mesh().n_owned_nodes));
  }
  for (auto& f : scene_->system().node_fields(*u_)) fields.emplace_back(f.name, std::move(f.values));
  out_->write_step(step, load, *u_, fields, scene_->system().term_element_fields());
}

void Simulation::checkpoint() {
  out_->write_checkpoint(at_, *u_, u_previous_.get(), stepper_->velocity(), scene_->system().save_states());
}

void Simulation::print_step(const StepRecord& rec) const {
  if (!talk_) return;
  // Linear solves repeated within their Newton iteration because a kept preconditioner had aged
  // (PreconditionerLag).
  std::string redone = rec.solve.retried_solves > 0 ? ", " + std::to_string(rec.solve.retried_solves) + " CG retried" : "";
  // Exact solves over their CG budget (ExactSolveBudget), solved again projected within their iteration.
  if (rec.solve.exact_over_budget > 0) redone += ", " + std::to_string(rec.solve.exact_over_budget) + " exact over CG budget";
  // Nodes the relaxation after Newton steps moved ('Solver/Node relaxation').
  const std::string relaxed = rec.solve.relaxed_nodes > 0 ? " (" + std::to_string(rec.solve.relaxed_nodes) + " nodes relaxed)" : "";
  std::printf("  converged: %d Newton%s, %d CG; volume %+.3f%%, min J %.3g, %lld inverted points; "
              "%.2f s (assembly %.2f, preconditioner %.2f in %d update%s%s, CG %.2f, line search %.2f%s)\n",
              rec.solve.newton_iterations, relaxed.c_str(), rec.solve.linear_iterations, 100.0 * (rec.volume_ratio - 1.0), rec.totals.min_J,
              rec.totals.inverted, rec.solve.seconds_total + rec.seconds_rounds, rec.solve.seconds_assembly,
              rec.solve.seconds_preconditioner, rec.solve.preconditioner_updates, rec.solve.preconditioner_updates == 1 ? "" : "s",
              redone.c_str(), rec.solve.seconds_linear, rec.solve.seconds_line_search, rounds_time(rec).c_str());
  for (const auto& line : stepper_->summary(rec)) std::printf("  %s\n", line.c_str());
  for (const auto& line : summary_) std::printf("  %s\n", line.c_str());
  std::fflush(stdout);
}

void Simulation::print_summary() const {
  struct rusage ru {};
  getrusage(RUSAGE_SELF, &ru);
  double peak_mb = static_cast<double>(ru.ru_maxrss) / 1024.0, max_mb = 0.0;  // ru_maxrss is in kB on Linux
  Teuchos::reduceAll(*comm_, Teuchos::REDUCE_MAX, peak_mb, Teuchos::outArg(max_mb));
  const auto& mesh = scene_->system().mesh();
  const std::string caches = out_->skin_cache_summary();
  if (talk_ && !caches.empty()) std::printf("%s\n", caches.c_str());
  if (talk_)
    std::printf("done in %.1f s; peak memory %.0f MB per rank (%.0f bytes per DOF); results in %s\n", wall_seconds() - started_,
                max_mb, max_mb * 1048576.0 * comm_->getSize() / (3.0 * mesh.global_nodes), out_->directory().c_str());
  if (std::getenv("SINEW_TIMERS")) Teuchos::TimeMonitor::summarize();
}

int Simulation::run() {
  System& sys = scene_->system();
  Scene& scene = *scene_;
  Output& out = *out_;
  Vector& u = *u_;
  started_ = wall_seconds();
  start_load_ = at_.load;
  print_header();
  const double V0 = sys.reference_volume();
  out.write_mesh();  // on restart, only where no mesh file on disk has this run's row order
  at_equilibrium_ = !opt_.restart_file.empty() ||
                    (!initial_given_ && config_.params.loading.initial == LoadingParameters::Initial::Rest);
  if (opt_.restart_file.empty()) {
    if (!initial_given_) scene.initial_state(u);
    const StepOutcome outcome = run_up();
    if (outcome != StepOutcome::Done) {
      // Nothing of the run has happened: the state where the run-up stopped, and no checkpoint (a
      // restart would start without the bones' run-up).
      write_step(0, 0.0);
      out.finish();
      if (outcome == StepOutcome::Stopped) {
        if (comm_->getRank() == 0) std::fprintf(stderr, "sinew: stopped by signal %d during the run-up\n", stop_signal_);
        return signal_exit_code(stop_signal_);
      }
      return code(ExitCode::NoConvergence);
    }
    write_step(0, 0.0);
  }
  const int n = scene.steps();
  for (int k = at_.step + 1; k <= n; ++k) {
    StepRecord rec;
    rec.step = k;
    rec.load = static_cast<double>(k) / n;
    const StepOutcome outcome = advance(k, rec);
    if (outcome == StepOutcome::Failed) {
      // The last converged state, restartable (e.g. with other solver settings), then its fields.
      if (out.checkpoint_every() > 0) checkpoint();
      write_step(k, at_.load);
      out.finish();
      return code(ExitCode::NoConvergence);
    }
    if (outcome == StepOutcome::Stopped) {
      // Interrupted inside step k: checkpoint exactly where the load path stands (possibly inside a cut
      // step), so that a restart continues the same run.
      checkpoint();
      out.finish();
      if (comm_->getRank() == 0)
        std::fprintf(stderr, "sinew: stopped by signal %d during step %d (load %.6g); checkpoint in %s\n", stop_signal_, k,
                     at_.load, out.checkpoint_file().c_str());
      return signal_exit_code(stop_signal_);
    }
    at_ = LoadState{k, rec.load, 0.0, 0, at_.previous_load, {}};
    rec.totals = sys.evaluate(u, nullptr, nullptr);
    rec.volume_ratio = rec.totals.volume / V0;
    stepper_->record(rec);
    rec.term_values = sys.log_values(rec.totals);
    summary_ = sys.summary(rec.totals);
    out.log(rec);
    records_.push_back(rec);
    if (observer_) observer_(rec, u);
    // The checkpoint first: a step file that cannot be written must not cost the converged state.
    const bool checkpoint_due = out.checkpoint_every() > 0 && (k % out.checkpoint_every() == 0 || k == n);
    if (checkpoint_due) checkpoint();
    if (k % out.every() == 0 || k == n) write_step(k, rec.load);
    print_step(rec);
    if (k < n && (stop_signal_ = stop_check_()) != 0) {
      if (!checkpoint_due) checkpoint();
      out.finish();
      if (comm_->getRank() == 0)
        std::fprintf(stderr, "sinew: stopped by signal %d after step %d; checkpoint in %s\n", stop_signal_, k,
                     out.checkpoint_file().c_str());
      return signal_exit_code(stop_signal_);
    }
  }
  out.finish();
  print_summary();
  return code(ExitCode::Success);
}

int run_scene(const SceneConfig& config, const RunOptions& opt) {
  const bool root = Tpetra::getDefaultComm()->getRank() == 0;
  return run_guarded("sinew", root, [&] {
    Simulation sim(config, opt);
    return sim.run();
  });
}

}  // namespace sinew
