// Results on disk: parallel HDF5 written collectively by all ranks, an XDMF index for ParaView, and a
// per-step CSV log. Every file is written aside and renamed into place, so a crash never leaves a
// half-written file where a good one was.
//
//   DIR/mesh.h5            /coordinates (nodes x 3, reference), /connectivity (elements x nodes, global ids)
//   DIR/step_NNNNNN.h5     /position (x = X + u), /displacement, /J and /energy_density (per element),
//                          attributes: load fraction, step
//   DIR/NAME.xdmf          temporal collection over the steps written so far
//   DIR/log.csv            one row per converged load step
//   DIR/checkpoint.h5      /displacement and the step and load reached: everything a restart needs
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
  // params: the scene's "Output" sublist (validated here). Collective. With restart_step >= 0 the run
  // continues an earlier one in the same folder: the log keeps its rows up to that step and the XDMF
  // index its step files.
  Output(const Teuchos::ParameterList& params, const Scene& scene, const std::string& scene_file,
         int restart_step = -1);

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

  int checkpoint_every() const { return checkpoint_every_; }
  std::string checkpoint_file() const { return dir_ + "/checkpoint.h5"; }
  // Collective: the state after `step` converged at load fraction `load` (aside, then renamed).
  void write_checkpoint(int step, double load, const Vector& u);

  struct Checkpoint {
    int step = 0;
    double load = 0.0;
  };
  // Collective: reads a checkpoint into u (which must live on the same mesh). Throws InputError when the
  // file is missing, unreadable or from another mesh.
  static Checkpoint read_checkpoint(const std::string& path, const Scene& scene, Vector& u);

 private:
  void write_xdmf() const;

  const Scene& scene_;
  std::string dir_, name_;
  bool hdf5_ = true;
  int every_ = 1, checkpoint_every_ = 1;
  bool root_ = false;
  std::vector<std::pair<int, double>> written_;  // (step, load) of step files
  std::ofstream log_;
};

}  // namespace sinew
