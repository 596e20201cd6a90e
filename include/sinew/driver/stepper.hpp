// How a step's solve starts and what its solution makes of the state, for the step loop (run.cpp),
// which names neither kind: quasi-static load steps with their predictors (quasi_static.hpp) or an
// implicit time integrator (dynamics.hpp).
#pragma once

#include <sinew/algebra/tpetra_types.hpp>
#include <sinew/io/output.hpp>
#include <sinew/solver/solve_report.hpp>

#include <string>
#include <vector>

namespace sinew {

class Stepper {
 public:
  virtual ~Stepper() = default;
  // The first guess of the solve from the converged state u at load t0 to load t1, with the step's
  // prescribed values, into trial; the scene's loads and colliders are left set for the solve.
  // Returns a predictor's own solve (its CG iterations and times), if it made one.
  virtual SolveReport begin(double t0, double t1, const Vector& u, Vector& trial) = 0;
  // The solve converged at y: the new state u, at load t1.
  virtual void end(double t0, double t1, const Vector& y, Vector& u) = 0;
  // Where a load fraction stands, for progress lines ("load 0.25", "t = 0.0417 s"), and what a cut
  // halves ("increment", "time step").
  virtual std::string describe(double load) const = 0;
  virtual const char* cut_name() const = 0;
  // The time of a load fraction in seconds (the clock of the skin's frames).
  virtual double time_of(double load) const = 0;
  // A dynamic run's velocity (null for a quasi-static one): checkpointed, written as a node field.
  virtual Vector* velocity() { return nullptr; }
  // The step's time and kinetic energy into its record (collective), and the step's summary lines.
  virtual void record(StepRecord& rec) const { (void)rec; }
  virtual std::vector<std::string> summary(const StepRecord& rec) const {
    (void)rec;
    return {};
  }
};

}  // namespace sinew
