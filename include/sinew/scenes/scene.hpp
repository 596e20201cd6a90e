// A scene: mesh + materials + boundary conditions + skeleton + load path + initial state.
//
// Boundary conditions are listed under "Loading/Boundary conditions", one sublist each:
//   Region      which nodes (see region.hpp): a face of the bounding box, box, corners, all,
//               'group NAME' (a physical group of the mesh file), segment
//   Motion      "fixed" | "rotate" (about "Axis" through "Center" by "Angle" radians in total) |
//               "translate" (by "Displacement" in total) | "affine" (u = G (X - Center) + Displacement
//               in total, G the displacement "Gradient": patch tests, shear)
//   Components  which displacement components the condition prescribes: "xyz" (default), or a subset
//               such as "z" (a roller on a symmetry plane) or "xy"; the others stay free
// Motions are applied as load fraction t goes from 0 to 1 over "Steps" quasi-static steps: the
// prescribed displacement at t is the motion with t * Angle or t * Displacement. "Body force" (force per
// reference volume, e.g. density * gravity) is ramped the same way. A "Skeleton" (skeleton.hpp) adds
// bones whose nodes follow them.
#pragma once

#include <sinew/algebra/system.hpp>
#include <sinew/core/section.hpp>
#include <sinew/materials/parameters.hpp>
#include <sinew/scenes/contact.hpp>
#include <sinew/scenes/region.hpp>
#include <sinew/scenes/skeleton.hpp>
#include <sinew/scenes/term_registry.hpp>
#include <sinew/scenes/time.hpp>

#include <functional>
#include <memory>

namespace sinew {

// One boundary condition as the XML gives it.
struct BoundaryConditionParameters {
  enum class Motion { Fixed, Rotate, Translate, Affine };
  RegionParameters region;
  std::string components;
  Motion motion = Motion::Fixed;
  std::array<double, 3> axis{}, center{}, displacement{};
  std::array<double, 9> gradient{};
  double angle = 0.0;

  template <class V>
  void visit(V& v) {
    v.inline_section(region);
    v.choice("Motion", motion, Motion::Fixed,
             Choices<Motion>{{"fixed", Motion::Fixed},
                             {"rotate", Motion::Rotate},
                             {"translate", Motion::Translate},
                             {"affine", Motion::Affine}},
             "how the region moves");
    v.entry("Components", components, std::string("xyz"),
            "the displacement components prescribed: xyz, or a subset such as z (a roller) or xy");
    v.entry("Axis", axis, {0.0, 0.0, 1.0}, "rotate: axis direction");
    v.entry("Center", center, {0.0, 0.0, 0.0}, "rotate: a point on the axis");
    v.entry("Angle", angle, 0.0, "rotate: total angle in radians, reached at the last step");
    v.entry("Displacement", displacement, {0.0, 0.0, 0.0}, "translate, affine: total displacement (of Center)");
    v.entry("Gradient", gradient, {0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0},
            "affine: the total displacement gradient G, row by row (F = I + G)");
  }
  template <class Context>
  void check(const Context& c) const {
    if (motion == Motion::Rotate && !(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2] > 0.0))
      c.fail("'Axis' must be a non-zero vector");
    if (components.empty() || components.find_first_not_of("xyz") != std::string::npos)
      c.fail("'Components' must be a non-empty combination of x, y and z, got \"" + components + "\"");
  }
};

// The "Loading" section of a scene.
struct LoadingParameters {
  enum class Initial { Rest, Scramble };
  enum class Predictor { None, Extrapolate, Tangent };
  int steps = 0, max_cuts = 0, scramble_seed = 0;
  Predictor predictor = Predictor::Tangent;
  std::array<double, 3> body_force{}, gravity{};
  Initial initial = Initial::Rest;
  double scramble_scale = 0.0;
  NamedSections<BoundaryConditionParameters> conditions;

  template <class V>
  void visit(V& v) {
    v.entry("Steps", steps, 1, "number of quasi-static load steps", Range::closed(1, 1e6));
    v.sections("Boundary conditions", conditions, "one sublist per condition");
    v.entry("Body force", body_force, {0.0, 0.0, 0.0},
            "force per reference volume, ramped with the load (in full from the start of a dynamic run)");
    v.entry("Gravity", gravity, {0.0, 0.0, 0.0},
            "gravitational acceleration (e.g. {0, 0, -9.81}), times each material's Density; ramped like the body force");
    v.choice("Initial state", initial, Initial::Rest,
             Choices<Initial>{{"rest", Initial::Rest}, {"scramble", Initial::Scramble}},
             "the starting displacement: rest, or scramble (vertices placed at random, Fig. 3)");
    v.entry("Scramble scale", scramble_scale, 2.0, "scramble: the vertices fill a box of this many times the rest volume",
            Range::positive());
    v.entry("Scramble seed", scramble_seed, 1, "scramble: random seed");
    // Default tangent, measured against extrapolate on 1 rank x 2 threads (docs/performance.md): the
    // 969k-DOF stretch's first step 10 -> 4 Newton iterations and 83.9 -> 50.0 s; every shipped scene
    // the same or one Newton iteration fewer (the twist's pi/2 rotation refuses the tangent; scenes with
    // the springs' contact do not use it; with the barrier every step does: driver/quasi_static.cpp).
    v.choice("Predictor", predictor, Predictor::Tangent,
             Choices<Predictor>{{"none", Predictor::None}, {"extrapolate", Predictor::Extrapolate}, {"tangent", Predictor::Tangent}},
             "each step's first guess: none: the last state with the new prescribed values (and a rig's skinning); "
             "extrapolate: or the linear extrapolation of the last two converged states when its energy is "
             "lower; tangent: the same, and where there is nothing to extrapolate from (the first step, from "
             "rest or a checkpoint; with the barrier contact, every step; not with the springs) the linearised "
             "response of the body to the guess (one CG solve on the last state's Hessian) when its energy is lower");
    v.entry("Maximum cuts", max_cuts, 6,
            "a step that fails is retried with half the load increment, at most this many times", Range::closed(0, 30));
  }
};

// Everything a Scene is built from.
struct SceneDescription {
  std::string name, file;  // the scene's name (output file names) and its file (messages)
  MeshParameters mesh;
  MaterialParameters material;
  LoadingParameters loading;
  SkeletonParameters skeleton;
  SceneTerms terms;  // contact and the other registered terms (scenes/term_registry.hpp)
  TimeParameters time;
};

// A prescribed motion resolved on this rank's nodes: a boundary condition, or a bone.
struct BoundaryCondition {
  std::string name;
  std::array<bool, 3> prescribed{{true, true, true}};  // which components
  std::vector<int> nodes;                              // local node indices (owned and ghost)
  // Prescribed displacement of a node at reference position X and load fraction t.
  std::function<std::array<double, 3>(const std::array<double, 3>& X, double t)> value;
};

class Scene {
 public:
  // Collective; throws InputError naming the file and entry at fault.
  Scene(const SceneDescription& d, Teuchos::RCP<const Teuchos::Comm<int>> comm);

  System& system() { return *system_; }
  const System& system() const { return *system_; }
  const std::vector<BoundaryCondition>& boundary_conditions() const { return bcs_; }
  // Load steps of a quasi-static run, time steps of a dynamic one.
  int steps() const { return time_.dynamic() ? time_.steps() : loading_.steps; }
  const TimeParameters& time() const { return time_; }
  bool dynamic() const { return time_.dynamic(); }
  int max_cuts() const { return loading_.max_cuts; }
  bool extrapolate() const { return !dynamic() && loading_.predictor != LoadingParameters::Predictor::None; }
  bool tangent_predictor() const { return !dynamic() && loading_.predictor == LoadingParameters::Predictor::Tangent; }
  const std::string& name() const { return name_; }

  // Sets the Dirichlet entries of u (owned DOFs) for load fraction t, and every term's load
  // (System::set_load: the body force's ramp, the colliders' poses).
  void apply_load(double t, Vector& u);

  // A better start for the step from load t0 to t1 than the state at t0: the free nodes carried along
  // by the bones' motion (linear-blend skinning), when there is a skeleton and skinning is on.
  void predict(double t0, double t1, Vector& u) const;
  // A dynamic step's guess beside the inertial predictor u_n + h v_n: where the bones' motion over the
  // step is not at the constant velocity that predictor assumes, the free nodes get the skinned motion's
  // second difference too (Skeleton::skin_acceleration; scale 1 for u_n+1, 1/2 for the midpoint's y).
  // Spring-held nodes then start near their targets instead of a bone's acceleration h^2 a behind.
  void predict_acceleration(double t0, double t1, const Vector& u, Vector& guess, double scale) const;
  const Skeleton& skeleton() const { return *skeleton_; }

  // The run-up before step 1 (skeleton.hpp): its steps, the bones at s of the way from the rest pose to
  // load 0 (1: done), and the skinning guess from s0 to s1.
  int run_up_steps() const { return skeleton_->run_up_steps(); }
  void set_run_up(double s) { skeleton_->set_run_up(s); }
  void predict_run_up(double s0, double s1, Vector& u) const;

  // The starting displacement: zero, or the "scramble" of the paper's Fig. 3.
  void initial_state(Vector& u) const;
  // The starting velocity of a dynamic run: Time/Initial velocity plus Initial spin x (X - centroid).
  void initial_velocity(Vector& v) const;

  // Contact (null without a Contact section): a term of the system, whose rounds the driver runs as
  // every term's (System::round). Collider poses follow apply_load.
  ContactTerm* contact() { return system_->find_term<ContactTerm>(); }

 private:
  // The construction's steps, in order (each throws InputError naming its entry; the constructor adds
  // the file).
  void build_system(const SceneDescription& d, const Teuchos::RCP<const Teuchos::Comm<int>>& comm);
  void resolve_conditions(const Teuchos::Comm<int>& comm);
  void add_bones(const SkeletonParameters& p, const Teuchos::Comm<int>& comm);
  void check_conditions(const SceneDescription& d, const Teuchos::Comm<int>& comm) const;
  void fix_prescribed_dofs();

  std::string name_;
  LoadingParameters loading_;
  TimeParameters time_;
  std::unique_ptr<System> system_;
  std::unique_ptr<Skeleton> skeleton_;
  std::vector<BoundaryCondition> bcs_;
  std::vector<char> free_;  // owned nodes with no prescribed component
  Kokkos::View<double* [3]>::HostMirror X_;  // reference coordinates of local nodes
};

}  // namespace sinew
