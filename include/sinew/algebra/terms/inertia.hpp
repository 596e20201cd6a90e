// Inertia as a term of the energy an implicit time step minimizes (the incremental potential of
// optimization time integrators, after Kane et al. 2000 and Gast et al. 2015): with the step's state
// y (the end state for backward Euler, the midpoint for implicit midpoint), its predictor y~, the last
// state u_n and Rayleigh damping D = alpha M + beta K_n (K_n the elastic Hessian at the step's start),
//
//   E_inertia(y) = 1/(2 c) (y - y~)^T M (y - y~) + 1/(2 c_d) (y - u_n)^T D (y - u_n),
//
// so that minimizing E(y) + E_inertia(y) is the integrator's equation of motion, and NOX, the energy
// line search, the PSD projection and MueLu work as for a quasi-static step (the term's Hessian
// M / c + D / c_d is PSD and only adds to the diagonal of the projected elastic one).
//   backward Euler:    c = h^2,     c_d = h,     y~ = u_n + h v_n
//   implicit midpoint: c = h^2 / 4, c_d = h / 2, y~ = u_n + h/2 v_n
// (see driver/dynamics.hpp for the updates). M is lumped (the nodal masses) or consistent.
#pragma once

#include <sinew/algebra/energy_term.hpp>

namespace sinew {

class System;

class InertiaTerm final : public EnergyTerm {
 public:
  // Collective (makes the mass matrix when consistent).
  InertiaTerm(const System& system, bool lumped);

  const char* name() const override { return "inertia"; }
  void add(const TermInput& in, TermOutput& out) const override;

  // The step's constants (collective when beta > 0: K_n is applied). K_n must be on the mesh graph
  // (System::create_mesh_matrix) and outlive the step; it is ignored when beta is 0.
  void set_step(double c, double c_damping, const Vector& predictor, const Vector& start, double alpha,
                const CrsMatrix* K_start, double beta);
  // No inertia (between dynamic steps, or a quasi-static run): the term adds nothing.
  void off() { active_ = false; }
  // After a failed solve: no inertia until the next set_step.
  void abandon_step() override { off(); }

  // 1/2 v^T M v over all ranks (collective).
  double kinetic_energy(const Vector& v) const;
  // M x (owned DOFs).
  void apply_mass(const Vector& x, Vector& Mx) const;

 private:
  const System& system_;
  bool lumped_ = true, active_ = false;
  Teuchos::RCP<CrsMatrix> M_;  // consistent
  double c_ = 1.0, c_damping_ = 1.0, alpha_ = 0.0, beta_ = 0.0;
  const CrsMatrix* K_start_ = nullptr;
  Teuchos::RCP<Vector> predictor_, start_, d_, Md_, e_, De_;
};

}  // namespace sinew
