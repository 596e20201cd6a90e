// Quasi-static equilibrium solve of one load step: NOX Newton with a line search on the Thyra
// ModelEvaluator route, Belos CG preconditioned by MueLu smoothed aggregation (3 DOFs per node, six
// rigid-body modes, coordinates) through Stratimikos. Every NOX, Belos and MueLu parameter can be set
// from the scene's "Solver" sublist; Sinew's defaults fill in the rest.
//
// All of NOX, Thyra, Stratimikos, Belos and MueLu stay inside src/solver/nonlinear_solver.cpp.
#pragma once

#include <sinew/algebra/system.hpp>
#include <sinew/core/section.hpp>
#include <sinew/solver/hessian_policy.hpp>
#include <sinew/solver/solve_report.hpp>

#include <Teuchos_ParameterList.hpp>

#include <functional>
#include <memory>
#include <string>

namespace sinew {

// The "Solver" section of a scene.
struct SolverParameters {
  enum class LineSearch { Backtrack, Polynomial, MoreThuente, FullStep };
  enum class Merit { Energy, Residual };
  enum class Forcing { Constant, Type1, Type2 };
  enum class Preconditioner { MueLu, None };
  enum class NearNullSpace { Reference, Current };
  enum class Rebuild { WhenNeeded, EveryStep };
  enum class Update { WhenNeeded, EveryNewtonIteration };
  enum class Inverted { Exact, PerPoint, WholeMesh };
  enum class ExactTerms { Never, AfterLongStep };
  double absolute_tolerance = 0.0, relative_tolerance = 0.0, linear_tolerance = 0.0, exact_below = 0.0, exact_within = 0.0;
  int max_iterations = 0, regroup_after = 0;
  LineSearch line_search = LineSearch::Backtrack;
  Merit merit = Merit::Energy;
  Forcing forcing = Forcing::Type2;
  Preconditioner preconditioner = Preconditioner::MueLu;
  NearNullSpace near_null_space = NearNullSpace::Reference;
  Rebuild rebuild = Rebuild::WhenNeeded;
  Update update = Update::WhenNeeded;
  Inverted inverted = Inverted::Exact;
  ExactTerms exact_terms = ExactTerms::AfterLongStep;
  double rebuild_factor = 0.0, update_factor = 0.0, max_step = 0.0, node_relaxation = 0.0;
  bool verbose = false;
  Teuchos::ParameterList nox, stratimikos;

  template <class V>
  void visit(V& v) {
    v.entry("Absolute tolerance", absolute_tolerance, 0.0,
            "converged when the L2 norm of the force residual is below this (the paper's test; 0: 1e-2, or a millionth "
            "of a cell's force scale (mu_L + lambda_L) h^2 where that is larger: a body modelled in centimetres)",
            Range::non_negative());
    v.entry("Relative tolerance", relative_tolerance, 0.0,
            "also converged when the residual norm falls below this times the step's first (0: off)",
            Range::closed_open(0.0, 1.0));
    // 150, not 50: a cut does not help where a crease snaps through (an inverted point turning back
    // at BCN_Epileptic's knee with the barrier: six cuts of 50 iterations each failed from the same
    // state, one attempt of 80 passed; the whole clip 1,185 Newton iterations, max 108).
    v.entry("Maximum iterations", max_iterations, 150, "Newton iterations per load step", Range::closed(1, 1e6));
    // Default 5, measured on BCN_Epileptic's clip with self contact (docs/performance.md): against 0,
    // steps 31-36 from a checkpoint 214 Newton iterations where 0 failed at step 33; 2, 3, 4, 10 and 15
    // gave 657, 419, 223, 417 and 530.
    v.entry("Regroup after", regroup_after, 5,
            "a solve not converged after this many Newton iterations stops for the terms to set themselves up "
            "again at its state (self contact: samples that slid past their frozen targets into the body get "
            "springs; the tractions wait for a converged state) and goes on, up to 'Maximum iterations' in "
            "all (0: never)",
            Range::closed(0, 1e6));
    v.choice("Line search", line_search, LineSearch::Backtrack,
             Choices<LineSearch>{{"backtrack", LineSearch::Backtrack},
                                 {"polynomial", LineSearch::Polynomial},
                                 {"more-thuente", LineSearch::MoreThuente},
                                 {"full-step", LineSearch::FullStep}},
             "line search along each Newton direction (backtrack: on the energy, with NOX's Backtrack settings)");
    // Default 2, measured against 1 (nonlinear_solver.cpp, EnergyBacktrack::extend): scramble 350 -> 201
    // Newton iterations, drop 48 -> 38, squash 1,535 -> 1,502, the crouch's steps 5-9 110 -> 92, the 30^3
    // twist's second step 160 -> 51, the corotational human's fourth 43 -> 27; no shipped scene more.
    v.entry("Maximum step", max_step, 2.0,
            "longest step along a Newton direction, in Newton steps, that the energy line search (backtrack, "
            "merit energy) tries when the full step lowers the energy by more than a quadratic would (the "
            "Hessian stiffer than the energy along the direction, as the PSD projection makes it near "
            "inverted or strongly compressed points): the step goes on to the energy's minimum along the "
            "direction, up to this (1: never beyond the Newton step)",
            Range::closed(1.0, 1e3));
    // Default 0.02, measured against 0 (System::relax_nodes; docs/performance.md), same end states:
    // the 48k-cell human's crouch 119-122 -> 95 Newton iterations (135-151 -> 108-110 s), its 4-step
    // start 19 -> 16, rig mocap 53 -> 40, twist 28 -> 24, scramble 201 -> 170, voxel arm 78 -> 71,
    // arm 77 -> 76 (CG 591 -> 683), stretch 36 -> 36.
    v.entry("Node relaxation", node_relaxation, 0.02,
            "after each step the energy line search accepts (Line search backtrack, merit energy), the free "
            "nodes whose force holds at least this share of |F|^2, and their neighbours, are moved one at a "
            "time to lower the energy of their elements, the rest held (a nonlinear Gauss-Seidel pass; kept "
            "when the total energy falls): the few nodes that hold a residual near a crease no longer cut "
            "every Newton step. Not with inertia, not at the nodes of contact springs (nor on the surface "
            "with colliders), not next to an inverted point, never inverting one, and not while more than "
            "0.1% of the points are inverted (0: off)",
            Range::closed_open(0.0, 1.0));
    v.choice("Line search merit", merit, Merit::Energy, Choices<Merit>{{"energy", Merit::Energy}, {"residual", Merit::Residual}},
             "what the line search decreases: the total energy, or 0.5 |F|^2");
    v.entry("Linear tolerance", linear_tolerance, 1e-4,
            "relative CG tolerance of each Newton step with a constant forcing term, and the tightest an "
            "Eisenstat-Walker one asks for",
            Range::open(0.0, 1.0));
    // Default type 2 (tolerances in [Linear tolerance, 1e-2]), measured against constant 1e-4 on 1 rank x
    // 2 threads, same end states: twist 5.1 -> 3.4 s, arm 6.3 -> 4.6, voxel arm 12.0 -> 8.4, arm with
    // contact 17.4 -> 11.3, stretch 66.4 -> 59.3, squash 31.1 -> 27.6, the 48k-cell rig human 124.6 ->
    // 68.3 (CG per Newton 24.4 -> 13.9); Newton iterations: -13% (human) to +15% (stretch).
    v.choice("Forcing term", forcing, Forcing::Type2,
             Choices<Forcing>{{"constant", Forcing::Constant}, {"type 1", Forcing::Type1}, {"type 2", Forcing::Type2}},
             "CG tolerance per Newton step: constant ('Linear tolerance'), or Eisenstat-Walker type 1 or 2 (0.01 "
             "while the residual falls slowly, down to 'Linear tolerance' as Newton converges; an exact-Hessian step "
             "that would stop CG within a digit above the convergence threshold solves to half the threshold)");
    v.choice("Preconditioner", preconditioner, Preconditioner::MueLu,
             Choices<Preconditioner>{{"muelu", Preconditioner::MueLu}, {"none", Preconditioner::None}}, "CG preconditioner");
    v.choice("Near-null space", near_null_space, NearNullSpace::Reference,
             Choices<NearNullSpace>{{"reference", NearNullSpace::Reference}, {"current", NearNullSpace::Current}},
             "MueLu's rigid-body modes and coordinates: of the reference configuration, or of the last "
             "converged state (used at each MueLu setup from scratch, see 'Preconditioner rebuild')");
    v.choice("Preconditioner rebuild", rebuild, Rebuild::WhenNeeded,
             Choices<Rebuild>{{"when needed", Rebuild::WhenNeeded}, {"every step", Rebuild::EveryStep}},
             "when MueLu's hierarchy is set up from scratch: at every load step, or only when a step's CG "
             "iterations per Newton iteration grow past 'Rebuild factor' times those of the first step after "
             "the last setup (and after a failed step); in between, each Newton iteration reuses the "
             "prolongators (MueLu 'reuse: type')");
    v.entry("Rebuild factor", rebuild_factor, 1.5, "see 'Preconditioner rebuild'", Range::closed(1.0, 1e6));
    // Default 'when needed', measured against 'every Newton iteration' (nonlinear_solver.cpp,
    // PreconditionerLag; docs/performance.md).
    v.choice("Preconditioner update", update, Update::WhenNeeded,
             Choices<Update>{{"when needed", Update::WhenNeeded}, {"every Newton iteration", Update::EveryNewtonIteration}},
             "between setups from scratch: update the preconditioner for every Newton iteration's Jacobian "
             "(MueLu's Galerkin products and smoothers on the kept prolongators), or keep it, across Newton "
             "iterations and load steps, until a linear solve needs more than 'Update factor' times the CG "
             "iterations per digit of the first solve after the last update, or fails, or gives a direction "
             "that does not descend");
    v.entry("Update factor", update_factor, 1.5, "see 'Preconditioner update'", Range::closed(1.0, 1e6));
    // Default 0.01, measured: 15^3 twist 19 + 32 -> 15 + 15 Newton iterations and 15.0 -> 7.9 s; 16x16x32
    // stretch 78.7 -> 28.7 s; same end states (the projection only changes the path, not the solution).
    v.entry("Exact Hessian below", exact_below, 0.01,
            "use the unprojected Hessian once |F| < this times the step's first |F| and nothing is inverted "
            "(0: always project); a solve that fails after using it is redone with projection",
            Range::closed_open(0.0, 1.0));
    // Default 1000, measured on the rig corpus (docs/performance.md): the relative rule alone leaves a step
    // whose first |F| was small projected down to a fraction of it, where projected Newton creeps (on the
    // corpus' logs, below 1000 times the tolerance an exact iteration lowered |F| by 0.44-0.58 decades,
    // a projected one by 0.14-0.26; above it, no more); the corpus 5,414 -> 5,004 Newton iterations (its
    // quasi-static runs -13.5%), 5,186 with 100; no shipped scene takes more.
    v.entry("Exact Hessian within", exact_within, 1000.0,
            "also use the unprojected Hessian (as 'Exact Hessian below' does) once |F| is below this many times "
            "the |F| that ends the solve, however small the step's first |F| was (0: the relative rule only)",
            Range::non_negative());
    // Default exact (with the retry after a failed exact step, hessian_policy.hpp), measured against per
    // point: scramble 444 -> 391 Newton iterations (both back to rest); the 48k-cell human's crouch,
    // steps 5 and 6 (85-143 points inverted at a crease): 43 -> 33 and over 80 -> 16; twist, drop,
    // arm, voxel arm, arm with contact, squash and stretch unchanged (nothing inverts there).
    v.choice("Inverted points", inverted, Inverted::Exact,
             Choices<Inverted>{{"exact", Inverted::Exact}, {"per point", Inverted::PerPoint}, {"whole mesh", Inverted::WholeMesh}},
             "when the exact Hessian is due ('Exact Hessian below') and at most 1% of the points are inverted: "
             "exact at the inverted points too (a direction that does not descend falls back to projection), "
             "per point (exact where J > 0, the law's projection where J <= 0: Newton then converges linearly, "
             "0.85 per iteration with 85 inverted points on the 48k-cell human), or whole mesh (projected "
             "everywhere while any point is inverted)");
    // Default 'after a long step', measured against 'never' (hessian_policy.hpp; docs/performance.md).
    v.choice("Exact term Hessians", exact_terms, ExactTerms::AfterLongStep,
             Choices<ExactTerms>{{"never", ExactTerms::Never}, {"after a long step", ExactTerms::AfterLongStep}},
             "while the exact Hessian is in use: after an exact step that the energy line search lengthened past "
             "1.2 Newton steps (the energy softer along it than the Hessian says), also the other terms' "
             "unprojected Hessians (a contact barrier's pairs: their PSD projection stiffens the directions along "
             "which surfaces slide on each other), until a direction from them fails, which goes back to the "
             "terms' projections for the rest of the solve; or never");
    v.entry("Verbose", verbose, false, "print NOX's own iteration output");
    v.raw("NOX", nox, "raw NOX parameters laid over Sinew's defaults");
    v.raw("Stratimikos", stratimikos, "raw Stratimikos (Belos, MueLu) parameters laid over Sinew's defaults");
  }
};

// The names NOX and Stratimikos give the choices above.
inline const char* nox_name(SolverParameters::LineSearch l) {
  using L = SolverParameters::LineSearch;
  return l == L::Backtrack ? "Backtrack" : l == L::Polynomial ? "Polynomial" : l == L::MoreThuente ? "More'-Thuente" : "Full Step";
}
inline const char* nox_name(SolverParameters::Forcing f) {
  using F = SolverParameters::Forcing;
  return f == F::Constant ? "Constant" : f == F::Type1 ? "Type 1" : "Type 2";
}
inline const char* stratimikos_name(SolverParameters::Preconditioner p) {
  return p == SolverParameters::Preconditioner::MueLu ? "MueLu" : "None";
}

class NonlinearSolver {
 public:
  // Throws InputError when NOX, Belos or MueLu reject their parameters.
  NonlinearSolver(System& system, const SolverParameters& params);
  ~NonlinearSolver();

  // Solves force(u) = 0 starting from u (its Dirichlet entries hold the prescribed values, which stay).
  // Never throws for a failed solve: linear-solver breakdowns, line-search failures and non-finite
  // values are reported in the SolveReport's status.
  // `reference`: the residual 'Exact Hessian below' is relative to (0: this solve's first). A later
  // solve of the same load step (another contact round) passes the step's first: it starts near
  // equilibrium, where the exact Hessian is due at once, and would otherwise wait for its own residual
  // to fall a hundredfold under projection, which converges linearly.
  // `budget` > 0: stop after that many Newton iterations (at most 'Maximum iterations'), status
  // MaxIterations, with u where they left it, to be continued by another call (a contact regroup in
  // between); such a stop is not redone with projection as a failed solve is.
  SolveReport solve(Vector& u, const std::function<void(const NewtonIterate&)>& progress = {}, double reference = 0.0,
                    int budget = 0);

  // The tangent predictor of a load step: from the equilibrium u0 (of the last load), the linearised
  // response to trial (the step's guess: the new prescribed values, free nodes where a rig's skinning
  // put them or at u0). With d = trial - u0, trial becomes trial + du, K_ff(u0) du = -(f_f(u0) +
  // K(u0) d), K the projected Hessian; one CG solve to 10 x 'Linear tolerance' on the solver's own
  // preconditioner (which the step's Newton iterations then update as usual). A boundary layer that a
  // jump of the prescribed nodes would crush is spread over the body instead. Taken (status Converged)
  // when its energy is defined and below energy_to_beat; otherwise trial is as it was. Counts CG
  // iterations, preconditioner setups and times in the report (no Newton iterations).
  SolveReport tangent(const Vector& u0, Vector& trial, double energy_to_beat);

  double absolute_tolerance() const;

  // Called after every Newton iteration (collectively); returning true stops the solve with status
  // Interrupted.
  void set_interrupt(std::function<bool()> interrupt);

 private:
  SolveReport solve_once(Vector& u, const std::function<void(const NewtonIterate&)>& progress, HessianPolicy policy,
                         double reference, int max_iterations);
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sinew
