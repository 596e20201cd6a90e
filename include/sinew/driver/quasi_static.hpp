// Quasi-static load steps (Stepper): each step's first guess is the last state with the new prescribed
// values (and a rig's skinning, Scene::predict), or its linear extrapolation through the state before,
// or the tangent predictor (one CG solve of the body's linearised response), whichever has the lowest
// finite energy (Loading/Predictor); the solution is the new state.
#pragma once

#include <sinew/driver/stepper.hpp>
#include <sinew/scenes/scene.hpp>

namespace sinew {

class NonlinearSolver;

class QuasiStatic final : public Stepper {
 public:
  // at: the run's load state (its previous_load says where u_previous stands; the checkpoint keeps
  // both); at_equilibrium: whether the state is an equilibrium (where the tangent's linearisation holds).
  // All must outlive the stepper. talk: print the predictor's choice.
  QuasiStatic(Scene& scene, NonlinearSolver& solver, LoadState& at, Vector& u_previous, bool& at_equilibrium, bool talk,
              double frame_rate)
      : scene_(scene), solver_(solver), at_(at), u_previous_(u_previous), at_equilibrium_(at_equilibrium), talk_(talk),
        frame_rate_(frame_rate) {}

  SolveReport begin(double t0, double t1, const Vector& u, Vector& trial) override;
  void end(double t0, double t1, const Vector& y, Vector& u) override;
  std::string describe(double load) const override;
  const char* cut_name() const override { return "increment"; }
  // One load step a frame at Time/Frame rate.
  double time_of(double load) const override { return load * scene_.steps() / frame_rate_; }

 private:
  Scene& scene_;
  NonlinearSolver& solver_;
  LoadState& at_;
  Vector& u_previous_;
  bool& at_equilibrium_;
  bool talk_ = false;
  double frame_rate_ = 24.0;
};

}  // namespace sinew
