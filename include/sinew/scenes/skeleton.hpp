// Bone-driven flesh (the paper's Fig. 1, 2, 7, 10): a "Skeleton" of rigid bones, each holding a region
// of nodes that follows it exactly (Dirichlet), while the rest of the body is flesh solved
// quasi-statically.
//
//   <ParameterList name="Skeleton">
//     <ParameterList name="Bones">
//       <ParameterList name="humerus">  Region (e.g. 'group humerus'), Pivot, Keyframes ... </ParameterList>
//       <ParameterList name="radius">   Parent humerus, Pivot (the elbow), Keyframes ...  </ParameterList>
//     </ParameterList>
//   </ParameterList>
//
// A bone's motion is a rotation about its Pivot (reference coordinates) followed by a translation,
// given at keyframes over the load fraction t in [0, 1] (an implicit rest keyframe at t = 0) and
// interpolated between them (the angle linearly about a shared axis, otherwise quaternion slerp; the
// translation linearly); a child bone's motion is composed after its parent's, so it moves with it.
// Alternatively a CSV "Motion file" gives one world transform per bone per frame.
//
// Each load step starts from a better guess than the last pose: the free nodes are carried along by
// linear-blend skinning of the bones' relative motion over the step, x <- sum_b w_b T_b(t) T_b(t0)^-1 x,
// with weights falling off with the distance to each bone (1/d^p, normalized).
#pragma once

#include <sinew/core/rigid.hpp>
#include <sinew/discretization/rig_file.hpp>
#include <sinew/scenes/region.hpp>

#include <Teuchos_Comm.hpp>

#include <map>
#include <memory>

namespace sinew {

struct KeyframeParameters {
  double time = 0.0, angle = 0.0;
  std::array<double, 3> axis{}, translation{};

  template <class V>
  void visit(V& v) {
    v.entry("Time", time, 1.0, "the load fraction of this pose, in (0, 1]", Range::closed(0.0, 1.0));
    v.entry("Axis", axis, {0.0, 0.0, 1.0}, "rotation axis (about the bone's Pivot)");
    v.entry("Angle", angle, 0.0, "rotation angle in radians, from the rest pose");
    v.entry("Translation", translation, {0.0, 0.0, 0.0}, "translation after the rotation, from the rest pose");
  }
  template <class Context>
  void check(const Context& c) const {
    if (!(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2] > 0.0)) c.fail("'Axis' must be a non-zero vector");
  }
};

// A motion over the load fraction t from keyframes: a rotation about a pivot followed by a translation,
// with an implicit rest key at t = 0, interpolated between keys (the angle linearly about a shared
// axis, otherwise quaternion slerp; the translation linearly) and held after the last. Bones and
// colliders move this way.
struct KeyframeTrack {
  std::array<double, 3> pivot{};
  std::vector<double> times;  // with t = 0 first
  std::vector<std::array<double, 3>> axes, translations;
  std::vector<double> angles;

  KeyframeTrack() = default;
  KeyframeTrack(const std::array<double, 3>& pivot, const NamedSections<KeyframeParameters>& keys);
  Rigid pose(double t) const;
};

// Rotation interpolated between A (s = 0) and B (s = 1) along the shorter arc (quaternion slerp).
Mat3 slerp(const Mat3& A, const Mat3& B, double s);

struct BoneParameters {
  std::string parent;
  std::array<double, 3> pivot{};
  RegionParameters region;
  NamedSections<KeyframeParameters> keyframes;

  template <class V>
  void visit(V& v) {
    v.entry("Parent", parent, std::string(""), "the bone this one moves with (none: a root bone)");
    v.entry("Pivot", pivot, {0.0, 0.0, 0.0}, "the point the bone rotates about, in the rest pose (a joint)");
    v.inline_section(region);
    v.sections("Keyframes", keyframes, "one sublist per pose (any names), ordered by Time");
  }
};

struct SkeletonParameters {
  NamedSections<BoneParameters> bones;
  std::string motion_file, rig, clip, retarget, joint_map;
  bool skinning = true;
  double falloff = 0.0, clip_start = 0.0, clip_end = -1.0, bone_radius = 0.0, sample_rate = 30.0, rest_time = -1.0,
         retarget_scale = 0.0;
  bool rig_weights = false;
  enum class Attachment { Auto, Fixed, Soft };
  Attachment attachment = Attachment::Auto;  // resolved to Fixed or Soft when the scene is read (driver/config)
  // The resolved attachment's word for messages: "soft" or "fixed".
  const char* attachment_word() const { return attachment == Attachment::Soft ? "soft" : "fixed"; }
  double bone_stiffness = 0.0;
  enum class BoneRegions { SkinWeights, Capsules };
  BoneRegions bone_regions = BoneRegions::SkinWeights;
  // 0.4, not 0.5: a bone holding half its flesh's thickness left the groin of BCN_Epileptic's clip two
  // 3 cm cells between the pelvis's and the thigh's held nodes, and its hip flexion folded one of them
  // (15 quasi-static frame ends with an inverted point, 16 with inertia). At 0.4 the corpus ends no
  // frame with an inverted point the rest pose did not have but Testwuson's run with inertia (1 point
  // at 2 frames, as at 0.5), and takes 5.7% fewer Newton iterations; 0.35 and 0.45 also keep BCN's
  // groin unfolded but cost it 28% and 19% more (the counts are chaotic in this value; docs/
  // performance.md, "Thinner bones").
  double bone_thickness = 0.4, joint_gap = 0.0;
  std::string skip_joints, include_joints;
  int run_up = -1;

  template <class V>
  void visit(V& v) {
    v.sections("Bones", bones, "one sublist per bone, named as the bone");
    v.choice("Bone attachment", attachment, Attachment::Auto,
             Choices<Attachment>{{"auto", Attachment::Auto}, {"fixed", Attachment::Fixed}, {"soft", Attachment::Soft}},
             "how bones hold their nodes: fixed (the nodes move with the bone, prescribed) or soft (each node pulled "
             "towards where the bone carries it by a stiff spring, an energy term: algebra/terms/bone_springs.hpp); "
             "auto: soft where Contact/'Self contact model' is barrier with self contact on (its collision test must "
             "see every node: a prescribed bone node would carry the surface through a face), fixed otherwise");
    v.entry("Bone stiffness", bone_stiffness, 0.0,
            "soft attachment: the springs' stiffness per volume per length (0: 100 (mu_L + lambda_L) / h^2, h the mean "
            "edge length: a node's spring a hundred times a cell's stiffness)",
            Range::non_negative());
    v.entry("Rig", rig, std::string(""),
            "bones from a rigged character's joints instead of Bones (see sinew-rig): each joint that moves skin holds "
            "the lattice nodes within 'Bone radius' of the segment to its first child joint (a node near several "
            "goes to the nearest) and follows the joint's motion in 'Clip' (made rigid by polar decomposition); a "
            "relative path is taken from the scene file's folder");
    v.entry("Clip", clip, std::string(""), "the rig's animation clip (empty: its first); with 'Retarget from', that file's");
    v.entry("Retarget from", retarget, std::string(""),
            "a file whose clip drives the Rig's joints instead of the Rig's own (a BVH motion capture, another "
            "character; see sinew-rig), through 'Joint map': each mapped joint turns in the world as its source "
            "joint turns from the source's pose at 'Clip start' (where the rig stands in its rest pose); a relative "
            "path is taken from the scene file's folder");
    v.entry("Joint map", joint_map, std::string(""),
            "with 'Retarget from': 'source joint:rig joint' pairs, comma-separated (unmapped rig joints move with "
            "their parent)");
    v.entry("Retarget scale", retarget_scale, 0.0,
            "with 'Retarget from': the factor on the source root's translation (0: the ratio of the mapped joints' "
            "heights in the rig and in the source)",
            Range::non_negative());
    v.entry("Clip start", clip_start, 0.0, "the clip's time, in seconds, at load 0", Range::non_negative());
    v.entry("Rest time", rest_time, -1.0,
            "the clip's time whose pose is the rest (stress-free) shape: the skin (Mesh/Type rig, the same file) is "
            "voxelized in it and the bones move from it; negative: the file's bind pose. A pose with the arms away "
            "from the body keeps a hand from fusing with a thigh");
    v.entry("Clip end", clip_end, -1.0, "the clip's time, in seconds, at load 1 (negative: the clip's end)");
    v.choice("Bone regions", bone_regions, BoneRegions::SkinWeights,
             Choices<BoneRegions>{{"skin weights", BoneRegions::SkinWeights}, {"capsules", BoneRegions::Capsules}},
             "which joints of a Rig hold flesh, and which: skin weights (a joint is a bone where it dominates skin "
             "vertices; it holds the lattice nodes within 'Bone thickness' times the local flesh thickness of its "
             "segment, leaving 'Joint gap' free at both ends so that a bent joint folds flesh instead of crushing it) or "
             "capsules (every joint that moves skin holds the nodes within 'Bone radius' of its segment; neighbouring "
             "capsules meet at the joints)");
    v.entry("Bone thickness", bone_thickness, 0.4,
            "skin weights: a bone's radius as a fraction of the median distance from its segment to the skin it "
            "dominates (unless 'Bone radius' is given)",
            Range::open_closed(0.0, 1.0));
    v.entry("Joint gap", joint_gap, 0.0,
            "skin weights: the flesh left free at each end of a bone, in metres (0: the larger of a cell and the bone's "
            "radius, at most 35% of the segment)",
            Range::non_negative());
    v.entry("Skip joints", skip_joints, std::string(""), "joints (comma-separated names) that hold no flesh even where they dominate skin");
    v.entry("Include joints", include_joints, std::string(""),
            "joints (comma-separated names) that are bones although they dominate no skin (a capsule of 'Bone radius', "
            "or 1.5 cells, to their first child joint)");
    v.entry("Run-up steps", run_up, -1,
            "load steps before the clip starts in which the bones move from the rest pose to the clip's first frame "
            "(quasi-static, also before a dynamic run's time starts), so that step 1 is no jump; negative: one per 15 "
            "degrees of the largest joint rotation (at most 10), none when the clip starts at rest",
            Range::closed(-1, 1000));
    v.entry("Bone radius", bone_radius, 0.0,
            "the radius of a joint's bone (0: with skin weights, from the local flesh thickness ('Bone thickness'); "
            "with capsules, 1.5 lattice cells)",
            Range::non_negative());
    v.entry("Clip samples per second", sample_rate, 30.0, "how densely the clip is sampled into frames (slerp between them)",
            Range::closed(1.0, 10000.0));
    v.entry("Rig skinning weights", rig_weights, false,
            "with a Rig: the skinning guess takes each node's bone weights from the nearest skin vertex's weights in "
            "the file instead of Sinew's distance weights ('Skinning falloff'); on inputs/rig_human.xml both take 29 "
            "Newton iterations, no skinning guess 37");
    v.entry("Motion file", motion_file, std::string(""),
            "CSV of world transforms instead of keyframes: lines 'frame,bone,r00,r01,r02,r10,r11,r12,r20,r21,r22,tx,ty,tz' "
            "(frames 0..F-1 spread evenly over the load; a relative path is taken from the scene file's folder)");
    v.entry("Skinning guess", skinning, true,
            "start each step from the last pose carried along by linear-blend skinning of the bones' motion");
    v.entry("Skinning falloff", falloff, 4.0, "p of the skinning weights 1/d^p (d: distance to a bone)", Range::closed(0.5, 16.0));
  }
  template <class Context>
  void check(const Context& c) const;
};

// The skeleton on this rank's nodes. Collective to build.
class Skeleton {
 public:
  Skeleton(const SkeletonParameters& p, const Mesh& mesh, const Teuchos::Comm<int>& comm, const std::string& where);

  bool empty() const { return bones_.empty(); }
  std::size_t size() const { return bones_.size(); }
  const std::string& name(std::size_t b) const { return bones_[b].name; }
  const std::vector<int>& nodes(std::size_t b) const { return bones_[b].nodes; }
  // The bone's world transform at load fraction t (rest -> posed), parents composed.
  Rigid transform(std::size_t b, double t) const;
  // Carries the free owned nodes of displacement `u` (interleaved xyz, owned nodes) from load t0 to t1
  // by linear-blend skinning. X: reference coordinates of local nodes; free[n]: node n is not attached.
  void skin(double t0, double t1, const double* X, const std::vector<char>& free, double* u, std::size_t owned) const;
  // A dynamic step's guess: adds scale times the skinned motion's second difference at the state x_n
  // (X + u_n), sum_b w_b [T_b(t1) + T_b(tp)] T_b(t0)^-1 x_n - 2 x_n, to the free owned nodes of `guess`;
  // tp = t0 - (t1 - t0), no earlier than load 0. See Scene::predict_acceleration.
  void skin_acceleration(double t0, double t1, const double* X, const std::vector<char>& free, const double* u, double* guess,
                         double scale, std::size_t owned) const;
  bool skinning() const { return skinning_; }
  // A skeleton from a rig: joints whose capsule held no node, and the largest entry by which a joint's
  // motion departed from a rotation (made rigid by polar decomposition).
  int unused_joints() const { return unused_joints_; }
  // The skinning guess's weights of an owned node: (bone, weight), summing to 1.
  const std::vector<std::pair<int, double>>& weights(std::size_t owned_node) const { return weights_.at(owned_node); }
  double nonrigid() const { return nonrigid_; }
  // A skeleton from a rig: what became of each joint that moves skin (bone or not, and why; nodes held,
  // radius, gap at its ends), listed by --check; and a one-line count for the run's header.
  struct Joint {
    std::string name, why;
    bool bone = false;
    long long nodes = 0, dominated = 0;  // lattice nodes held; skin vertices whose largest weight is this joint's
    double radius = 0.0, gap = 0.0, length = 0.0;
    std::array<double, 3> a{}, b{};  // its segment at rest: from the joint's origin
  };
  const std::vector<Joint>& joints() const { return joints_; }
  std::string joint_listing() const;
  std::string joint_summary() const;

  // The run-up (Sec. "From the rest pose to the clip" of the README): before step 1 the bones move from
  // the rest pose (s = 0) to their pose at load 0 (s = 1) over run_up_steps() quasi-static steps. While
  // s < 1, transform(b, 0) is the pose at s: each bone turns about its centre along the shorter arc
  // while the centre moves on a straight line.
  int run_up_steps() const { return run_up_steps_; }
  double largest_start_rotation() const { return start_rotation_; }  // radians, of any bone from rest to load 0
  void set_run_up(double s) { run_up_ = s; }
  // Carries free owned nodes along by the bones' motion from run-up s0 to s1, as skin().
  void skin_run_up(double s0, double s1, const double* X, const std::vector<char>& free, double* u, std::size_t owned) const;
  // A skeleton from a rig: the file (nullptr for other skeletons) and the world transforms of its
  // nodes at a load fraction (its clip, or a retargeted one), from which the plain linear-blend skin
  // of the file is written beside the simulated one; the retargeting's scale (0 without).
  const RigFile* rig() const { return rig_.get(); }
  std::vector<Affine> rig_pose(double load) const;
  // The clip's time, in seconds, at a load fraction (of the retargeted clip when retargeting).
  double rig_seconds(double load) const { return clip_t0_ + (clip_t1_ - clip_t0_) * load; }
  double retarget_scale() const { return retarget_ ? retarget_->scale() : 0.0; }
  // Collective. The fastest a held node moves between consecutive samples k/samples, k = 0..samples, of
  // the motion (run-up excluded), when the whole motion takes `seconds`: the largest |T_b(t_k+1) X -
  // T_b(t_k) X| / (seconds / samples) over bones b and their nodes X, and the largest second difference
  // |x_k+1 - 2 x_k + x_k-1| / dt^2. A dynamic run prints both beside the flesh's shear-wave speed
  // sqrt(mu / density): flesh cannot follow bones that outrun its waves (docs/performance.md).
  struct PeakSpeed {
    double speed = 0.0;  // m/s (length units per second)
    int sample = 0;      // the sample k + 1 at whose end it was reached
    double acceleration = 0.0;  // the largest second difference / dt^2
    std::string bone;
  };
  PeakSpeed peak_speed(const Mesh& mesh, const Teuchos::Comm<int>& comm, int samples, double seconds) const;

  // Each joint's segment at rest (from its origin a to b) and the region of lattice nodes it holds: a
  // capsule of its radius about the segment, or (capped) a cylinder leaving 'gap' free at both ends.
  // (Public for tests, as is region_nodes.)
  struct JointSegments {
    std::vector<int> joints;  // rig node indices
    std::vector<std::array<double, 3>> a, b;
    std::vector<double> radius, gap;
    std::vector<char> capped, candidate;  // candidate: may hold nodes (else why says why not)
    std::vector<std::string> why;
    std::vector<long long> dominated;
  };
  // The lattice nodes each joint holds; with h > 0 (the cell size) a node one cell from another joint's
  // region is held by one of them only: the one whose region is larger (`sizes`: nodes per joint with
  // h = 0, the same on every rank), else the earlier joint.
  static std::vector<std::vector<int>> region_nodes(const Mesh& mesh, const JointSegments& s, double h,
                                                    const std::vector<long long>* sizes = nullptr);

 private:
  // A rig's joints as bones, in named steps: the file and its clip (returns the rest pose's clip, or
  // null for the bind pose), each joint's segment at rest, the lattice nodes of each joint's capsule,
  // the clip sampled into rigid frames, the file's skinning weights per owned node.
  void bones_from_rig(const SkeletonParameters& p, const Mesh& mesh, const Teuchos::Comm<int>& comm, const std::string& where);
  const RigClip* read_rig_and_clip(const SkeletonParameters& p, const Teuchos::Comm<int>& comm, const std::string& where);
  static JointSegments capsule_segments(const RigFile& rig, const std::vector<Affine>& rest, double radius);
  // The skin at rest: its vertices and their (rig node, weight) pairs.
  struct RestSkin {
    std::vector<std::array<double, 3>> x;
    std::vector<std::vector<std::pair<int, double>>> w;
  };
  static RestSkin rest_skin(const RigFile& rig, const RigClip* rest_clip, double rest_time);
  static JointSegments weighted_segments(const RigFile& rig, const std::vector<Affine>& rest, const RestSkin& skin, double h,
                                         const SkeletonParameters& p, const std::string& where);
  std::vector<std::vector<Rigid>> sample_frames(const JointSegments& s, const std::vector<Affine>& rest, double sample_rate);
  std::vector<std::vector<std::pair<int, double>>> skin_weights(const Mesh& mesh, const RestSkin& skin) const;
  struct Bone {
    std::string name;
    int parent = -1;
    KeyframeTrack track;
    std::vector<Rigid> frames;  // world transforms per frame (motion file), else empty
    std::vector<int> nodes;     // attached local nodes
    std::array<double, 3> seg_a{}, seg_b{};  // the bone's segment for the skinning weights
    std::array<double, 3> centre{};          // of its nodes at rest: the run-up turns the bone about it
  };
  Rigid local(const Bone& b, double t) const;
  Rigid posed(std::size_t b, double t) const;         // transform() without the run-up
  Rigid run_up_pose(std::size_t b, double s) const;   // between rest (s = 0) and the pose at load 0
  void skin_by(const std::vector<Rigid>& M, const double* X, const std::vector<char>& free, double* u, std::size_t owned) const;
  void plan_run_up(int steps);
  std::vector<Bone> bones_;
  bool skinning_ = true;
  double falloff_ = 4.0;
  int unused_joints_ = 0;
  std::vector<std::vector<std::pair<int, double>>> rig_weights_;  // per owned node, from the file's skin
  double nonrigid_ = 0.0;
  std::vector<Joint> joints_;
  std::string rig_path_;
  double run_up_ = 1.0, start_rotation_ = 0.0, cell_ = 0.0;
  int run_up_steps_ = 0;
  std::vector<std::vector<std::pair<int, double>>> weights_;  // per owned node: (bone, weight)
  std::shared_ptr<const RigFile> rig_, source_;  // source_: the file whose clip is retargeted
  std::unique_ptr<Retarget> retarget_;
  const RigClip* clip_ = nullptr;  // in *rig_, or in *source_ when retargeting
  double clip_t0_ = 0.0, clip_t1_ = 0.0;
};

template <class Context>
void SkeletonParameters::check(const Context& c) const {
  if (c.given("Bone stiffness") && attachment == Attachment::Fixed) c.fail("'Bone stiffness' applies to 'Bone attachment' soft only");
  if (!rig.empty()) {
    if (!bones.empty()) c.fail("give 'Bones' or a 'Rig' (whose joints are the bones), not both");
    if (!motion_file.empty()) c.fail("give a 'Motion file' or a 'Rig' (whose clip moves the bones), not both");
    if (clip_end >= 0.0 && !(clip_end > clip_start)) c.fail("'Clip end' must exceed 'Clip start'");
    if (!retarget.empty() && joint_map.empty())
      c.fail("'Retarget from' needs a 'Joint map' ('source joint:rig joint' pairs)", InputErrorKind::MissingEntry);
    if (retarget.empty())
      for (const char* retarget_only : {"Joint map", "Retarget scale"})
        if (c.given(retarget_only)) c.fail("'" + std::string(retarget_only) + "' applies with 'Retarget from' only");
    if (bone_regions == BoneRegions::Capsules)
      for (const char* weights_only : {"Bone thickness", "Joint gap"})
        if (c.given(weights_only)) c.fail("'" + std::string(weights_only) + "' applies to 'Bone regions' skin weights only");
  } else {
    for (const char* rig_only : {"Clip", "Clip start", "Clip end", "Bone radius", "Clip samples per second", "Rig skinning weights",
                                 "Rest time", "Retarget from", "Joint map", "Retarget scale", "Bone regions", "Bone thickness",
                                 "Joint gap", "Skip joints", "Include joints"})
      if (c.given(rig_only)) c.fail("'" + std::string(rig_only) + "' applies to a skeleton from a 'Rig' only");
  }
  std::map<std::string, std::string> parent_of;
  for (const auto& [name, b] : bones) parent_of[name] = b.parent;
  for (const auto& [name, b] : bones) {
    if (!b.parent.empty() && !parent_of.count(b.parent))
      c.fail("Bones/" + name + ": 'Parent' \"" + b.parent + "\" is not a bone of this skeleton");
    // A chain of parents must end at a root.
    std::string at = name;
    for (std::size_t k = 0; k <= bones.size(); ++k) {
      at = parent_of[at];
      if (at.empty()) break;
      if (k == bones.size()) c.fail("Bones/" + name + ": its chain of parents is a cycle");
    }
    double last = 0.0;
    for (const auto& [kname, k] : b.keyframes) {
      if (!(k.time > last)) c.fail("Bones/" + name + "/Keyframes/" + kname + ": 'Time' must exceed the previous keyframe's (and 0)");
      last = k.time;
    }
    if (!motion_file.empty() && !b.keyframes.empty())
      c.fail("Bones/" + name + ": give keyframes or a 'Motion file', not both");
  }
}

}  // namespace sinew
