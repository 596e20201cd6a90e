// A scene file, read and validated as a whole before any work: every section parsed into its struct
// (strict types, finite numbers in range, no unknown or duplicate entries), so `sinew --check` finds
// every mistake a run would, without building a mesh or a matrix.
#pragma once

#include <sinew/io/output.hpp>
#include <sinew/scenes/scene.hpp>
#include <sinew/solver/nonlinear_solver.hpp>

#include <Teuchos_RCP.hpp>

#include <string>

namespace sinew {

// The top level of a scene file.
struct SceneFileParameters {
  std::string scene, description;
  MeshParameters mesh;
  MaterialParameters material;
  LoadingParameters loading;
  SkeletonParameters skeleton;
  SceneTerms terms;  // the registered terms' sections: Contact, Pressure (scenes/term_registry.hpp)
  TimeParameters time;
  SolverParameters solver;
  OutputParameters output;

  template <class V>
  void visit(V& v) {
    v.entry("Scene", scene, std::string("custom"), "scene name, used in output file names");
    v.entry("Description", description, std::string(""), "free text");
    v.section("Mesh", mesh, "the mesh: generator and resolution (required)");
    v.section("Material", material, "hyperelastic law(s) (required)");
    v.section("Loading", loading, "boundary conditions, body force and load steps");
    v.section("Skeleton", skeleton, "bones that drive the flesh");
    terms.visit(v);
    v.section("Time", time, "quasi-static load steps, or time steps with mass (dynamics)");
    v.section("Solver", solver, "Newton, CG and multigrid parameters");
    v.section("Output", output, "HDF5/XDMF fields, log and checkpoints");
  }
  template <class Context>
  void check(const Context& c) const {
    if (!c.given("Mesh")) c.fail("missing sublist 'Mesh'", InputErrorKind::MissingEntry);
    if (!c.given("Material")) c.fail("missing sublist 'Material'", InputErrorKind::MissingEntry);
  }
};

struct SceneConfig {
  std::string file;             // for messages
  SceneFileParameters params;   // every section, parsed and checked

  SceneDescription scene() const {
    return {params.scene, file, params.mesh, params.material, params.loading, params.skeleton, params.terms, params.time};
  }
};

// Reads and validates a scene file (paths in it taken from its folder). Throws InputError naming the
// file and the entry at fault.
SceneConfig read_scene(const std::string& path);

// What `sinew --check` adds to reading: a mesh file's header, and the group names the scene uses
// (material regions, 'group NAME' regions) checked against it. Throws InputError.
void check_mesh_file(const SceneConfig& scene);

// Validates a parameter list already in memory; `name` stands for the file in messages.
SceneConfig make_scene(const Teuchos::RCP<Teuchos::ParameterList>& params, const std::string& name);

// Every accepted entry of a scene file, with defaults and documentation (sinew --parameters).
std::string parameter_reference();

// Human-readable summary of a scene (sinew --check).
std::string describe(const SceneConfig& scene);

// A skeleton from a rig: each joint, bone or not (and why), the lattice nodes it holds, its radius and
// the gaps at its ends, for sinew --check; empty without a Rig. Builds the mesh (collective).
std::string describe_joints(const SceneConfig& scene);

}  // namespace sinew
