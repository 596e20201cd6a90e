// A scene: mesh + material + boundary conditions + load path + initial state, built from the XML.
//
// Boundary conditions are listed under "Loading/Boundary conditions", one sublist each:
//   Region  "face x-" ... "face z+" | "box" (with "Box lower", "Box upper") | "corners" (four
//           non-coplanar corners of the bounding box) | "all"
//   Motion  "fixed" | "rotate" (about "Axis" through "Center" by "Angle" radians in total) |
//           "translate" (by "Displacement" in total)
// Motions are applied as load fraction t goes from 0 to 1 over "Steps" quasi-static steps: the
// prescribed displacement at t is the motion with t * Angle or t * Displacement. "Body force" (force per
// reference volume, e.g. density * gravity) is ramped the same way.
#pragma once

#include <sinew/algebra/elastic_system.hpp>
#include <sinew/driver/config.hpp>

#include <memory>

namespace sinew {

Teuchos::ParameterList valid_loading_parameters();
Teuchos::ParameterList valid_boundary_condition_parameters();

struct BoundaryCondition {
  enum class Motion { Fixed, Rotate, Translate };
  std::string name, region;
  Motion motion = Motion::Fixed;
  std::array<double, 3> axis{{0, 0, 1}}, center{{0, 0, 0}}, displacement{{0, 0, 0}};
  double angle = 0.0;
  std::vector<int> nodes;  // local node indices (owned and ghost)

  // Prescribed displacement of a node at reference position X and load fraction t.
  std::array<double, 3> value(const std::array<double, 3>& X, double t) const;
};

class Scene {
 public:
  Scene(const SceneConfig& config, Teuchos::RCP<const Teuchos::Comm<int>> comm);

  ElasticSystem& system() { return *system_; }
  const ElasticSystem& system() const { return *system_; }
  const std::vector<BoundaryCondition>& boundary_conditions() const { return bcs_; }
  int steps() const { return steps_; }
  int max_cuts() const { return max_cuts_; }
  const std::string& name() const { return name_; }

  // Sets the Dirichlet entries of u (owned DOFs) and the body force for load fraction t.
  void apply_load(double t, Vector& u);

  // The starting displacement: zero, or the "scramble" of the paper's Fig. 3.
  void initial_state(Vector& u) const;

 private:
  std::string name_;
  std::unique_ptr<ElasticSystem> system_;
  std::vector<BoundaryCondition> bcs_;
  int steps_ = 1, max_cuts_ = 6;
  std::array<double, 3> body_{{0, 0, 0}};
  std::string initial_ = "rest";
  double scramble_scale_ = 2.0;
  unsigned scramble_seed_ = 1;
  Kokkos::View<double* [3]>::HostMirror X_;  // reference coordinates of local nodes
};

}  // namespace sinew
