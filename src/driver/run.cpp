#include <sinew/core/errors.hpp>
#include <sinew/driver/info.hpp>
#include <sinew/driver/run.hpp>
#include <sinew/driver/signals.hpp>
#include <sinew/io/output.hpp>
#include <sinew/materials/parameters.hpp>
#include <sinew/scenes/scene.hpp>
#include <sinew/solver/nonlinear_solver.hpp>

#include <Teuchos_CommHelpers.hpp>
#include <Teuchos_ParameterList.hpp>
#include <Teuchos_TimeMonitor.hpp>
#include <Tpetra_Core.hpp>
#include <Tpetra_Vector.hpp>

#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <iostream>

namespace sinew {

namespace {
const Teuchos::ParameterList& sublist_or_empty(const Teuchos::ParameterList& p, const char* name) {
  static const Teuchos::ParameterList empty;
  return p.isSublist(name) ? p.sublist(name) : empty;
}
}  // namespace

Simulation::Simulation(const SceneConfig& config, const RunOptions& options, Teuchos::RCP<const Teuchos::Comm<int>> comm)
    : config_(config), opt_(options) {
  if (comm.is_null()) comm = Tpetra::getDefaultComm();
  scene_ = std::make_unique<Scene>(config_, comm);
  solver_ = std::make_unique<NonlinearSolver>(scene_->system(), sublist_or_empty(*config_.params, "Solver"));
  u_ = scene_->system().create_vector();
  int restart_step = -1;
  if (!opt_.restart_file.empty()) {
    const auto c = Output::read_checkpoint(opt_.restart_file, *scene_, *u_);
    restart_step = c.step;
    first_step_ = c.step + 1;
    start_load_ = c.load;
  }
  out_ = std::make_unique<Output>(sublist_or_empty(*config_.params, "Output"), *scene_, config_.file, restart_step);
  // Signals are checked collectively, so that every rank stops at the same point.
  solver_->set_interrupt([comm] {
    int s = pending_signal(), any = 0;
    Teuchos::reduceAll(*comm, Teuchos::REDUCE_MAX, s, Teuchos::outArg(any));
    return any != 0;
  });
}

Simulation::~Simulation() = default;

int Simulation::run() {
  ElasticSystem& sys = scene_->system();
  Scene& scene = *scene_;
  Output& out = *out_;
  NonlinearSolver& solver = *solver_;
  Vector& u = *u_;
  auto comm = sys.comm();
  const bool root = comm->getRank() == 0;
  const bool talk = root && !opt_.quiet;
  const auto t_start = std::chrono::steady_clock::now();
  auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count(); };
  const std::size_t prescribed = sys.global_fixed_dofs();  // collective: outside the rank-0 block
  if (talk) {
    std::printf("Sinew: scene '%s' (%s), %s, %d MPI rank%s\n", scene.name().c_str(), config_.file.c_str(),
                execution_space_summary().c_str(), comm->getSize(), comm->getSize() > 1 ? "s" : "");
    std::printf("  mesh: %lld %s elements, %lld nodes, %lld DOFs (%zu prescribed)\n",
                static_cast<long long>(sys.mesh().global_elements), to_string(sys.mesh().type).c_str(),
                static_cast<long long>(sys.mesh().global_nodes), 3LL * sys.mesh().global_nodes, prescribed);
    std::printf("  material: %s\n", describe(config_.material).c_str());
    std::printf("  %d load step%s; converged when |F| < %g; results in %s\n", scene.steps(), scene.steps() > 1 ? "s" : "",
                solver.absolute_tolerance(), out.directory().c_str());
    std::fflush(stdout);
  }
  const double V0 = sys.reference_volume();
  if (first_step_ == 1) {
    out.write_mesh();
    scene.initial_state(u);
    out.write_step(0, 0.0, u);
  } else if (talk) {
    std::printf("  restarting after step %d (load %.4g) from %s\n", first_step_ - 1, start_load_, opt_.restart_file.c_str());
  }
  auto stop_signal = [&] {
    int s = pending_signal(), any = 0;
    Teuchos::reduceAll(*comm, Teuchos::REDUCE_MAX, s, Teuchos::outArg(any));
    return any;
  };

  auto trial = sys.create_vector();
  double t_done = start_load_;
  const int n = scene.steps();
  for (int k = first_step_; k <= n; ++k) {
    const double target = static_cast<double>(k) / n;
    double dt = target - t_done;
    StepRecord rec;
    rec.step = k;
    rec.load = target;
    while (t_done < target - 1e-14) {
      const double t = std::min(t_done + dt, target);
      trial->assign(u);
      scene.apply_load(t, *trial);
      if (talk) {
        std::printf("step %d/%d  load %.4g%s\n", k, n, t, rec.cuts ? "  (after cutting the increment)" : "");
        std::fflush(stdout);
      }
      auto progress = [&](const NewtonIterate& it) {
        if (!talk) return;
        std::printf("  newton %3d  |F| = %.3e  CG %4d  step %.3g\n", it.iteration, it.residual, it.linear_iterations, it.step);
        std::fflush(stdout);
      };
      const SolveReport r = solver.solve(*trial, progress);
      rec.solve.accumulate(r);
      if (rec.solve.initial_residual == 0.0) rec.solve.initial_residual = r.initial_residual;
      rec.solve.final_residual = r.final_residual;
      if (r.converged) {
        u.assign(*trial);
        t_done = t;
        continue;
      }
      if (r.reason == "interrupted") break;
      if (talk) std::printf("  step did not converge: %s\n", r.reason.c_str());
      if (rec.cuts >= scene.max_cuts()) {
        if (root)
          std::fprintf(stderr,
                       "sinew: step %d did not converge after %d cut%s of the load increment (%s); the last converged "
                       "state (load %.6g) is in %s\n",
                       k, rec.cuts, rec.cuts == 1 ? "" : "s", r.reason.c_str(), t_done, out.directory().c_str());
        out.write_step(k, t_done, u);
        return kNoConvergence;
      }
      ++rec.cuts;
      dt *= 0.5;
    }
    if (const int sig = stop_signal(); sig != 0 && t_done < target - 1e-14) {
      // Interrupted inside step k: the checkpoint of step k-1 (written below at every step when
      // checkpoints are on) is the state to continue from; write it now in case they are off.
      if (k > first_step_ || first_step_ == 1) out.write_checkpoint(k - 1, static_cast<double>(k - 1) / n, u);
      if (root) std::fprintf(stderr, "sinew: stopped by signal %d during step %d; checkpoint of step %d in %s\n", sig, k, k - 1,
                             out.checkpoint_file().c_str());
      return 128 + sig;
    }
    rec.totals = sys.evaluate(u, nullptr, nullptr);
    rec.volume_ratio = rec.totals.volume / V0;
    out.log(rec);
    records_.push_back(rec);
    if (k % out.every() == 0 || k == n) out.write_step(k, target, u);
    if (out.checkpoint_every() > 0 && (k % out.checkpoint_every() == 0 || k == n)) out.write_checkpoint(k, target, u);
    if (talk) {
      std::printf("  converged: %d Newton, %d CG; volume %+.3f%%, min J %.3g, %lld inverted points; "
                  "%.2f s (assembly %.2f, preconditioner %.2f, CG %.2f, line search %.2f)\n",
                  rec.solve.newton_iterations, rec.solve.linear_iterations, 100.0 * (rec.volume_ratio - 1.0),
                  rec.totals.min_J, rec.totals.inverted, rec.solve.seconds_total, rec.solve.seconds_assembly,
                  rec.solve.seconds_preconditioner, rec.solve.seconds_linear, rec.solve.seconds_line_search);
      std::fflush(stdout);
    }
    if (const int sig = stop_signal(); sig != 0 && k < n) {
      if (out.checkpoint_every() == 0 || k % out.checkpoint_every() != 0) out.write_checkpoint(k, target, u);
      if (root) std::fprintf(stderr, "sinew: stopped by signal %d after step %d; checkpoint in %s\n", sig, k, out.checkpoint_file().c_str());
      return 128 + sig;
    }
  }
  struct rusage ru {};
  getrusage(RUSAGE_SELF, &ru);
  double peak_mb = static_cast<double>(ru.ru_maxrss) / 1024.0, max_mb = 0.0;  // ru_maxrss is in kB on Linux
  Teuchos::reduceAll(*comm, Teuchos::REDUCE_MAX, peak_mb, Teuchos::outArg(max_mb));
  if (talk)
    std::printf("done in %.1f s; peak memory %.0f MB per rank (%.0f bytes per DOF); results in %s\n", elapsed(), max_mb,
                max_mb * 1048576.0 * comm->getSize() / (3.0 * sys.mesh().global_nodes), out.directory().c_str());
  if (std::getenv("SINEW_TIMERS")) Teuchos::TimeMonitor::summarize();
  return kSuccess;
}

int run_scene(const SceneConfig& config, const RunOptions& opt) {
  const bool root = Tpetra::getDefaultComm()->getRank() == 0;
  try {
    Simulation sim(config, opt);
    return sim.run();
  } catch (const InputError& e) {
    if (root) std::fprintf(stderr, "sinew: input error [%s]: %s\n", to_string(e.kind), e.what());
    return kInputError;
  } catch (const std::exception& e) {
    if (root) std::fprintf(stderr, "sinew: error: %s\n", e.what());
    return kFailure;
  }
}

}  // namespace sinew
