// Results on disk: parallel HDF5 written collectively by all ranks, an XDMF index for ParaView, and a
// per-step CSV log. Every file is written aside and renamed into place, so a crash never leaves a
// half-written file where a good one was.
//
//   DIR/mesh.h5            /coordinates (nodes x 3, reference), /connectivity (elements x nodes, global ids)
//   DIR/step_NNNNNN.h5     /position (x = X + u), /displacement, /J and /energy_density (per element),
//                          attributes: load fraction, step
//   DIR/NAME.xdmf          temporal collection over the steps written so far
//   DIR/log.csv            one row per converged load step
#pragma once

#include <sinew/scenes/scene.hpp>
#include <sinew/solver/nonlinear_solver.hpp>

#include <fstream>
#include <string>
#include <vector>

namespace sinew {

Teuchos::ParameterList valid_output_parameters();

struct StepRecord {
  int step = 0;
  double load = 0.0;
  int cuts = 0;
  SolveReport solve;
  EvaluationTotals totals;
  double volume_ratio = 1.0;
};

class Output {
 public:
  // params: the scene's "Output" sublist (validated here). Collective.
  Output(const Teuchos::ParameterList& params, const Scene& scene, const std::string& scene_file);

  bool enabled() const { return hdf5_; }
  const std::string& directory() const { return dir_; }
  int every() const { return every_; }

  void write_mesh();
  // Collective: one step file (aside, then renamed) and the XDMF index.
  void write_step(int step, double load, const Vector& u);
  // Rank 0 appends a row to log.csv.
  void log(const StepRecord& r);
  // Path of the HDF5 file of a written step.
  std::string step_file(int step) const;

 private:
  void write_xdmf() const;

  const Scene& scene_;
  std::string dir_, name_;
  bool hdf5_ = true;
  int every_ = 1;
  bool root_ = false;
  std::vector<std::pair<int, double>> written_;  // (step, load) of step files
  std::ofstream log_;
};

}  // namespace sinew
