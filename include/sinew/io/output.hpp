// Results on disk: parallel HDF5 written collectively by all ranks, an XDMF index for ParaView, and a
// per-step CSV log. Every file is written aside, flushed to disk and renamed into place (and the folder
// synced), so a crash never leaves a half-written file where a good one was; a failure on any rank is
// reported on every rank, never left waiting in a barrier.
//
//   DIR/mesh.h5            /coordinates (nodes x 3, reference), /connectivity (elements x nodes),
//                          /node_gid, /element_gid; attribute layout (a digest of the row order)
//   DIR/mesh_layoutK.h5    the same for a restart on another number of ranks (another row order)
//   DIR/step_NNNNNN.h5     /position (x = X + u), /displacement, /J and /energy_density (per element),
//                          /contact_pressure (per node, with contact), /fiber and /activation (per
//                          element, with muscles), attributes: load fraction, step,
//                          layout (which mesh file's rows these follow; the XDMF index pairs them)
//   DIR/NAME.xdmf          temporal collection over the steps written so far
//   DIR/surface_NNNNNN.obj the deformed boundary surface with normals (surface.hpp), for renderers
//   DIR/skin_NNNNNN.obj    a voxelized mesh's input surface carried along by the lattice
//   DIR/lbs_NNNNNN.obj     a rigged character's skin posed by the file's own linear-blend skinning,
//                          the same topology as skin_*.obj, for comparison (add_surface_sequence)
//   DIR/skin.glb, skin.pc2 the skin's frames (those of skin_*.obj) as an animated glTF binary and a
//   DIR/skin_rest.obj      PC2 point cache of the rest skin, made from DIR/skin.frames (skin_cache.hpp)
//   DIR/log.csv            one row per converged load step
//   DIR/newton.csv         one row per Newton iteration (residual, CG iterations, step length)
//   DIR/checkpoint.h5      /displacement, where the load path stood and the energy terms' states
//                          (/term NAME/...): everything a restart needs
#pragma once

#include <sinew/algebra/system.hpp>
#include <sinew/core/parameters.hpp>
#include <sinew/core/range.hpp>
#include <sinew/io/skin_cache.hpp>
#include <sinew/io/surface.hpp>
#include <sinew/solver/solve_report.hpp>

#include <array>
#include <cstdint>
#include <fstream>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace sinew {

// The "Output" section of a scene.
struct OutputParameters {
  std::string directory;
  int every = 0, checkpoint_every = 0, surface_every = 0;
  bool hdf5 = true, surface = true;
  std::optional<bool> skin_gltf, skin_pc2;  // absent: on where the scene has a skin

  template <class V>
  void visit(V& v) {
    v.entry("Directory", directory, std::string(""), "results folder (default results/<Scene>)");
    v.entry("Every", every, 1, "write fields every this many steps (the last step is always written)",
            Range::at_least(1));
    v.entry("HDF5", hdf5, true, "write HDF5/XDMF fields (the CSV log is always written)");
    v.entry("Surface OBJ", surface, true,
            "write the deformed boundary surface with normals as DIR/surface_NNNNNN.obj (for Blender, Houdini, Maya)");
    v.entry("Surface every", surface_every, 1,
            "write the surface at every this-many-th field output (the first and last step always)", Range::at_least(1));
    v.optional("Skin glTF", skin_gltf,
               "write the simulated skin as an animated glTF binary, DIR/skin.glb: one morph target per written "
               "skin frame, the rig's nodes beside it (default: on where the scene has a skin, Mesh/Type voxelize or rig)");
    v.optional("Skin PC2", skin_pc2,
               "write the simulated skin as a PC2 point cache, DIR/skin.pc2, for DIR/skin_rest.obj (Blender's Mesh "
               "Cache modifier, Maya, 3ds Max; default: on where the scene has a skin)");
    v.entry("Checkpoint every", checkpoint_every, 1,
            "write DIR/checkpoint.h5 every this many steps (0: never); sinew --restart continues from it",
            Range::non_negative());
  }
};

// One converged load step, as the log records it.
struct StepRecord {
  int step = 0;
  double load = 0.0;
  int cuts = 0;
  SolveReport solve;
  EvaluationTotals totals;
  double volume_ratio = 1.0;
  // Dynamic runs: the time at the step's end and the kinetic energy there.
  double time = 0.0, kinetic = 0.0;
  double seconds_rounds = 0.0;  // in the terms' rounds between solves (contact detection)
  int pattern_changes = 0;      // times the matrix pattern grew for the terms' new couplings
  // How far along its path the first guess of the step's converged attempt went (1: all the way; the
  // contact barrier's collision test pulls a guess that would pass the surface through itself back).
  double first_guess = 1.0;
  // The terms' columns of the log (System::log_columns): each term's energy share and its own values.
  std::vector<double> term_values;
};

// Where a run stands on its load path: everything a restart needs besides the displacement. Inside a
// step that was cut, `load` lies between step/steps and (step + 1)/steps and `increment` is the cut one.
struct LoadState {
  int step = 0;            // the last completed load step
  double load = 0.0;       // the load fraction of the displacement
  double increment = 0.0;  // the next increment to try (0: the rest of the next step)
  int cuts = 0;            // cuts made so far in the step under way
  double previous_load = -1.0;  // load of the converged state before this one (< 0: none kept)
  // What a restart should tell the user: entries of its physics that the checkpoint's run did not have,
  // taken at their defaults.
  std::vector<std::string> notes;
};

class Output {
 public:
  // Collective. `name` names the XDMF file; `steps` is the number of load steps (for restarts). With
  // restart_step >= 0 the run continues an earlier one in the same folder: the log keeps its rows up to
  // that step and the XDMF index its step files. Throws InputError (kind File) when the folder cannot
  // be created.
  Output(const OutputParameters& params, const System& system, const std::string& name, int steps,
         int restart_step = -1);

  bool enabled() const { return params_.hdf5; }
  const std::string& directory() const { return dir_; }
  int every() const { return params_.every; }

  void write_mesh();
  // Per owned node, a named scalar (n values) or vector (3 n, interleaved) written beside the step's
  // fields (contact pressure, velocity).
  using NodeFields = std::vector<std::pair<std::string, std::vector<double>>>;
  // Collective: one step file and the XDMF index, and the surface when its turn has come. Every step of
  // a run must be given the same node fields (the XDMF index lists them for all).
  void write_step(int step, double load, const Vector& u, const NodeFields& node_fields = {},
                  const std::vector<TermState::Nodal>& element_fields = {});
  // Path of the surface OBJ of a step.
  std::string surface_file(int step) const;
  // Another surface written with the boundary surface (same steps) as DIR/<prefix>_NNNNNN.obj: `at`
  // gives its vertices (3 coordinates each) and triangles at a load fraction; rank 0 calls it.
  using SurfaceAt = std::function<void(double load, std::vector<double>& x, std::vector<std::array<int, 3>>& triangles)>;
  void add_surface_sequence(const std::string& prefix, SurfaceAt at) { sequences_.emplace_back(prefix, std::move(at)); }
  // The skin's caches: the time of a frame at a load fraction (default: load x steps / frame rate, one
  // load step a frame), the frame rate of the PC2's frame numbers, and a rig's nodes to animate beside
  // the skin in the glTF file. Set before the first write_step.
  void set_frame_clock(std::function<double(double load)> time, double frame_rate);
  void set_skin_rig(SkinRig rig) { skin_rig_ = std::move(rig); }
  bool skin_caches() const;
  // Collective: brings the skin's glTF and PC2 files up to the last written frame (each write_step
  // refreshes them only while that costs under 2% of the run's time). Call when the run ends, however.
  void finish();
  // Rank 0: "skin caches: F frames of V vertices; sizes; seconds writing them" (empty without caches).
  std::string skin_cache_summary() const;
  // Collective: rank 0 appends a row to log.csv; a failed write is an error on every rank.
  void log(const StepRecord& r);
  // Rank 0 appends a row to newton.csv (`load`: the load fraction being solved for).
  void log_newton(int step, double load, const NewtonIterate& it);
  // Path of the HDF5 file of a written step.
  std::string step_file(int step) const;

  int checkpoint_every() const { return params_.checkpoint_every; }
  std::string checkpoint_file() const { return dir_ + "/checkpoint.h5"; }
  // Collective: the displacement u at load state `at`.
  // previous: the converged state at at.previous_load, kept for the predictor (written when given and
  // at.previous_load >= 0).
  // velocity: a dynamic run's, which a restart needs to continue the same trajectory.
  // terms: the energy terms' states (System::save_states), written as /term NAME/... datasets.
  using TermStates = std::vector<std::pair<std::string, TermState>>;
  void write_checkpoint(const LoadState& at, const Vector& u, const Vector* previous = nullptr,
                        const Vector* velocity = nullptr, const TermStates& terms = {});

  // Collective: reads a checkpoint into u (which must live on the same mesh, on any number of ranks).
  // Throws InputError (kind File) when the file is missing, unreadable, corrupt, from another mesh or
  // number of steps, or (with physics given) from a scene with other physics.
  // With velocity given, the checkpoint must hold one (a dynamic run's).
  // With physics given, a checkpoint whose stored digest of a section differs is refused, naming the
  // section and, where the checkpoint recorded its entries, the entries that differ; entries the
  // checkpoint's run did not have and this scene leaves at their defaults (parameters added since) are
  // accepted and named in the returned notes.
  struct PhysicsSection {
    std::string name;
    SectionFingerprint fingerprint;
  };
  using Physics = std::vector<PhysicsSection>;
  // With terms given, the states of the system's terms the checkpoint holds are read into it (per-node
  // arrays to this run's owned nodes, whatever the number of ranks that wrote them).
  static LoadState read_checkpoint(const std::string& path, const System& system, int steps, Vector& u,
                                   Vector* previous = nullptr, Vector* velocity = nullptr,
                                   const Physics* physics = nullptr, TermStates* terms = nullptr);
  // The scene's physics sections, whose digests and entries every checkpoint written after this stores.
  void set_physics(Physics physics) { physics_ = std::move(physics); }

 private:
  void write_xdmf() const;
  void write_log_row(const StepRecord& r);

  OutputParameters params_;
  const System& sys_;
  std::string dir_, name_;
  int steps_ = 1;
  bool root_ = false;
  struct Written {
    int step;
    double load;
    std::string mesh;  // the mesh file whose rows the step's rows follow
  };
  std::vector<Written> written_;                 // the step files the XDMF index lists
  std::uint64_t layout_ = 0;                     // digest of the output row order (output.cpp)
  std::string mesh_name_ = "mesh.h5";            // the mesh file of this run's layout
  bool mesh_on_disk_ = false;                    // a restart found it already written
  Physics physics_;
  std::vector<std::pair<std::string, int>> node_fields_;  // extra node fields of the step files: name, components
  std::vector<std::pair<std::string, int>> element_fields_;  // the terms' element fields: name, components
  std::unique_ptr<BoundarySurface> surface_;     // when surfaces are written
  std::unique_ptr<EmbeddedSkin> skin_;           // when a voxelized mesh carries its surface
  std::vector<std::pair<std::string, SurfaceAt>> sequences_;
  std::ofstream log_, newton_log_;
  // The skin's caches (rank 0 holds the frames).
  void add_skin_frame(int step, double load, const std::vector<double>& x, const std::vector<double>& J,
                      const std::vector<std::vector<double>>& sequences);
  void write_skin_caches();
  int restart_step_ = -1;
  std::function<double(double)> frame_time_;
  double frame_rate_ = 24.0;
  SkinRig skin_rig_;
  std::unique_ptr<SkinFrameFile> skin_file_;
  std::vector<SkinFrame> skin_frames_;
  std::vector<std::string> skin_fields_;
  std::size_t skin_frames_exported_ = 0;
  double started_ = 0.0, export_seconds_ = 0.0, append_seconds_ = 0.0;
};

}  // namespace sinew
