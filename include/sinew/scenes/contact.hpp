// The "Contact" section of a scene: self-contact on the boundary surface and kinematic colliders
// (algebra/terms/contact.hpp), e.g.
//
//   <ParameterList name="Contact">
//     <Parameter name="Self contact" type="bool" value="true"/>
//     <ParameterList name="Colliders">
//       <ParameterList name="floor">  Shape half-space, Point, Normal </ParameterList>
//       <ParameterList name="ball">   Shape sphere, Center, Radius, Keyframes (or Bone) </ParameterList>
//     </ParameterList>
//   </ParameterList>
//
// A collider moves as a bone does: keyframes over the load fraction (rotation about Pivot, then a
// translation), or rigidly with a bone of the Skeleton. Its shape is given at rest (t = 0).
#pragma once

#include <sinew/algebra/terms/contact.hpp>
#include <sinew/core/section.hpp>
#include <sinew/scenes/skeleton.hpp>
#include <sinew/scenes/term_kind.hpp>

namespace sinew {

struct ColliderParameters {
  enum class Shape { HalfSpace, Sphere, Capsule, Cylinder, Mesh };
  Shape shape = Shape::HalfSpace;
  std::array<double, 3> point{}, normal{}, center{}, start{}, end{}, pivot{};
  double radius = 0.0;
  std::string surface, bone;
  NamedSections<KeyframeParameters> keyframes;

  template <class V>
  void visit(V& v) {
    v.choice("Shape", shape, Shape::HalfSpace,
             Choices<Shape>{{"half-space", Shape::HalfSpace},
                            {"sphere", Shape::Sphere},
                            {"capsule", Shape::Capsule},
                            {"cylinder", Shape::Cylinder},
                            {"mesh", Shape::Mesh}},
             "half-space (Point, Normal), sphere (Center, Radius), capsule (Start, End, Radius), cylinder "
             "(infinite: Start and End on its axis, Radius) or mesh (a closed Surface)");
    v.entry("Point", point, {0.0, 0.0, 0.0}, "half-space: a point on its plane");
    v.entry("Normal", normal, {0.0, 0.0, 1.0}, "half-space: the normal pointing out of the collider (into the free side)");
    v.entry("Center", center, {0.0, 0.0, 0.0}, "sphere: its centre");
    v.entry("Start", start, {0.0, 0.0, 0.0}, "capsule: one end of its segment; cylinder: a point on its axis");
    v.entry("End", end, {0.0, 0.0, 1.0}, "capsule: the other end; cylinder: another point on its axis");
    v.entry("Radius", radius, 0.0, "sphere, capsule, cylinder: the radius", Range::non_negative());
    v.entry("Surface", surface, std::string(""),
            "mesh: a closed triangle surface (.obj or .stl; a relative path is taken from the scene file's folder)");
    v.entry("Bone", bone, std::string(""), "move rigidly with this bone of the Skeleton (instead of keyframes)");
    v.entry("Pivot", pivot, {0.0, 0.0, 0.0}, "the point keyframe rotations turn about");
    v.sections("Keyframes", keyframes, "one sublist per pose (Time, Axis, Angle, Translation), ordered by Time");
  }
  template <class Context>
  void check(const Context& c) const {
    const bool round = shape == Shape::Sphere || shape == Shape::Capsule || shape == Shape::Cylinder;
    if (round && !(radius > 0.0)) c.fail("a sphere, capsule or cylinder needs 'Radius' > 0", InputErrorKind::MissingEntry);
    if (shape == Shape::HalfSpace && !(normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2] > 0.0))
      c.fail("'Normal' must be a non-zero vector");
    if (shape == Shape::Cylinder && start == end) c.fail("a cylinder needs different points 'Start' and 'End' on its axis");
    if (shape == Shape::Mesh && surface.empty())
      c.fail("a mesh collider needs 'Surface' (a closed .obj or .stl)", InputErrorKind::MissingEntry);
    if (shape != Shape::Mesh && c.given("Surface")) c.fail("'Surface' applies to Shape mesh only");
    if (!bone.empty() && !keyframes.empty()) c.fail("give 'Bone' or 'Keyframes', not both");
    double last = 0.0;
    for (const auto& [kname, k] : keyframes) {
      if (!(k.time > last)) c.fail("Keyframes/" + kname + ": 'Time' must exceed the previous keyframe's (and 0)");
      last = k.time;
    }
  }
};

struct ContactParameters {
  bool self = false;
  double stiffness = 0.0, thickness = 0.0, margin = 0.0;
  bool refine = true, smooth = false, keep = false, edge_pairs = true;
  enum class Model { Springs, Barrier };
  Model model = Model::Barrier;
  int rounds = 0;
  NamedSections<ColliderParameters> colliders;

  template <class V>
  void visit(V& v) {
    v.entry("Self contact", self, false, "the body's surface pushes back where it meets itself (Sec. 6)");
    v.entry("Stiffness", stiffness, 0.0,
            "penalty stiffness k: traction per unit of penetration (0: 10 (mu_L + lambda_L) / h, h the mean edge length; "
            "the barrier's self contact, whose kappa is k A / thickness^2, (mu_L + lambda_L) / h)",
            Range::non_negative());
    v.entry("Thickness", thickness, 0.0,
            "the gap below which the springs push, or where the barrier starts (0: 0.05 h, with the barrier's self "
            "contact 0.15 h); the deepest penetration is reported per step",
            Range::non_negative());
    v.entry("Margin", margin, 0.0,
            "self contact: surface points this close to the surface are paired before they touch (0: thickness + h / 2)",
            Range::non_negative());
    v.choice("Self contact model", model, Model::Barrier,
             Choices<Model>{{"springs", Model::Springs}, {"barrier", Model::Barrier}},
             "barrier: a log barrier on each surface point's distance to the faces near it, which grows without "
             "bound as they touch, with every Newton step and first guess cut short of a point passing through a "
             "face (after Li et al. 2020; 'Thickness' is where it starts; a rig's bones are then soft: Skeleton/"
             "'Bone attachment' auto); springs: the paper's penalty springs on planes frozen at detection (Sec. 6), "
             "fewer Newton iterations where they hold, but points can end deeper than 'Thickness' and some clips do "
             "not finish (docs/contact.md)");
    v.entry("Edge pairs", edge_pairs, true,
            "barrier: edge-edge pairs beside the point-face ones, in the energy and in the collision test, so that "
            "two edges cannot pass through each other with no point crossing a face (IPC's edge-edge distance, "
            "mollified where the edges turn parallel). Without them the rig corpus's surfaces passed through "
            "themselves at most frame ends (BCN_Epileptic's clip: up to 121 surface edges through a face, 63 of 79 "
            "frames); with them at none (docs/performance.md)");
    v.entry("Refine targets", refine, true,
            "self contact: move each target to the closest point of the deformed surface nearby (the paper's local "
            "optimization)");
    v.entry("Smooth onset", smooth, false,
            "self contact: a spring's stiffness ramps from 0 to 'Stiffness' over its first 'Thickness' of "
            "compression (a C2 energy: Newton's model stays right where springs engage or let go in a crease; "
            "arm_contact.xml 217 -> 192 Newton iterations) instead of the plain k/2 max(0, s)^2 onset. Off by "
            "default: huesitos' curl then ended with springs 0.051 deep (thickness 0.0075; 0.011 without) "
            "(docs/performance.md)");
    v.entry("Keep springs across steps", keep, false,
            "self contact: a step starts from the springs its last state converged with (pairs that slid off their "
            "target by more than 'Margin' dropped, new contacts paired), instead of pairing every sample afresh; "
            "after a failed attempt the detection is fresh. Off by default: BCN_Epileptic's clip took 1,575 Newton "
            "iterations instead of 1,997, but stopped at step 39 (or 41) in other runs (docs/performance.md)");
    v.entry("Maximum rounds", rounds, 10,
            "solves per step: after each, new contacts are paired and the tractions of points still behind a surface "
            "by more than a tenth of the thickness are raised (augmented Lagrangian); a step ends when nothing changes",
            Range::closed(1, 100));
    v.sections("Colliders", colliders, "one sublist per kinematic collider, named as you like");
  }
  bool active() const { return self || !colliders.empty(); }
  template <class Context>
  void check(const Context& c) const {
    if (c.given("Margin") && margin > 0.0 && thickness > 0.0 && !(margin > thickness))
      c.fail("'Margin' must exceed 'Thickness'");
    // The springs' own options say nothing to the barrier: a scene that sets them expects springs.
    // ('Self contact' false with a model given is a comparison run with self contact switched off.)
    if (model == Model::Springs && c.given("Edge pairs"))
      c.fail("'Edge pairs' applies to 'Self contact model' barrier only");
    if (model == Model::Barrier) {
      for (const char* spring_only : {"Smooth onset", "Keep springs across steps", "Refine targets"})
        if (c.given(spring_only))
          c.fail(std::string("'") + spring_only + "' applies to 'Self contact model' springs only (barrier is the default)");
    }
  }
};

// The colliders' shapes and motions on a skeleton. Collective (a mesh surface is read on every rank
// and its failure agreed on); throws InputError naming the collider.
class Colliders {
 public:
  Colliders(const ContactParameters& p, const Skeleton& skeleton, const Teuchos::Comm<int>& comm, const std::string& where);
  std::vector<ColliderShape> shapes() const { return shapes_; }
  std::size_t size() const { return shapes_.size(); }
  // The pose of collider k at load fraction t.
  Rigid pose(std::size_t k, double t) const;

 private:
  const Skeleton& skeleton_;
  std::vector<ColliderShape> shapes_;
  std::vector<KeyframeTrack> tracks_;
  std::vector<int> bone_;  // -1: keyframes
};

// The contact term of a scene (collective): ContactSettings from the section, automatic values scaled
// with the stiffest law and the mesh (a traction of mu_L + lambda_L pushes a surface point in by a
// tenth of a cell; thickness 0.05 h, 0.15 h for the barrier's self contact; margin thickness + h / 2),
// collider poses from `colliders` (which the term keeps). Throws InputError ("Contact: ...") for a
// margin not above the thickness.
std::shared_ptr<ContactTerm> make_contact_term(const ContactParameters& p, const System& system,
                                               std::shared_ptr<const Colliders> colliders);

// The Contact section as a registered term kind (scenes/term_registry.hpp).
struct Contact {
  using Parameters = ContactParameters;
  static constexpr const char* section = "Contact";
  static constexpr const char* doc = "self contact (a barrier, or the paper's penalty springs) and kinematic colliders (penalty springs)";
  static bool active(const Parameters& p) { return p.active(); }
  static std::shared_ptr<EnergyTerm> make(const Parameters& p, const TermContext& c);
  static void resolve_paths(Parameters& p, const std::function<void(std::string&)>& resolve) {
    for (auto& [name, collider] : p.colliders) resolve(collider.surface);
  }
};

}  // namespace sinew
