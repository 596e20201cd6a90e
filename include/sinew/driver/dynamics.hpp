// The state and the updates of an implicit time integration (scenes/time.hpp) around the solver's
// minimization of E(y) + E_inertia(y) (algebra/terms/inertia.hpp):
//   backward Euler     y = u_(n+1); predictor u_n + h v_n;   v_(n+1) = (u_(n+1) - u_n) / h
//   implicit midpoint  y = (u_n + u_(n+1)) / 2, solved as a backward-Euler half step from the predictor
//                      u_n + h/2 v_n; then u_(n+1) = 2 y - u_n and v_(n+1) = 2 (u_(n+1) - u_n) / h - v_n.
//                      Its prescribed values at y are the averages of those at t_n and t_(n+1), so that
//                      u_(n+1) meets them exactly. Second order; it conserves linear and angular momentum
//                      for any symmetric mass matrix, and energy for a quadratic energy.
#pragma once

#include <sinew/algebra/terms/inertia.hpp>
#include <sinew/driver/stepper.hpp>
#include <sinew/scenes/scene.hpp>

namespace sinew {

class Dynamics final : public Stepper {
 public:
  // Adds the inertia term to the scene's system.
  explicit Dynamics(Scene& scene);

  Vector* velocity() override { return v_.get(); }
  double time_of(double load) const override { return load * end_time_; }
  // Collective: 1/2 v^T M v.
  double kinetic_energy() const { return inertia_->kinetic_energy(*v_); }

  // Sets up the step from load t0 to t1 at state u and writes the solve's first guess (with its
  // prescribed values) into trial. Leaves the scene's colliders and loads at the step's y.
  SolveReport begin(double t0, double t1, const Vector& u, Vector& trial) override;
  // After a converged solve for y: u and the velocity to the step's end.
  void end(double t0, double t1, const Vector& y, Vector& u) override;
  std::string describe(double load) const override;
  const char* cut_name() const override { return "time step"; }
  // The time and kinetic energy at the step's end; the mechanical energy's line.
  void record(StepRecord& rec) const override;
  std::vector<std::string> summary(const StepRecord& rec) const override;

 private:
  Scene& scene_;
  TimeParameters p_;
  double end_time_ = 1.0, h_ = 0.0;
  std::shared_ptr<InertiaTerm> inertia_;
  Teuchos::RCP<Vector> v_, predictor_, scratch_;
  Teuchos::RCP<Vector> acceleration_, accelerated_;  // the loads' acceleration; the guess moved by it
  Teuchos::RCP<CrsMatrix> K_start_;  // for stiffness-proportional damping
};

}  // namespace sinew
