// Skeleton: bone regions, keyframe (or motion-file) interpolation composed down the hierarchy, and the
// linear-blend-skinning predictor for each load step.
#include <sinew/core/collective.hpp>
#include <sinew/core/sym_eigen.hpp>
#include <sinew/core/validation.hpp>
#include <sinew/core/xml_input.hpp>
#include <sinew/discretization/rig_file.hpp>
#include <sinew/scenes/skeleton.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

namespace sinew {

namespace {

std::array<double, 3> unit(const std::array<double, 3>& a) {
  const double n = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
  return {a[0] / n, a[1] / n, a[2] / n};
}

// Unit quaternions (w, x, y, z) for interpolating rotations.
using Quat = std::array<double, 4>;

Quat quat_of(const Mat3& R) {
  // Shepperd's method: pick the largest diagonal combination for accuracy.
  const double tr = R(0, 0) + R(1, 1) + R(2, 2);
  Quat q;
  if (tr > 0.0) {
    const double s = 2.0 * std::sqrt(tr + 1.0);
    q = {0.25 * s, (R(2, 1) - R(1, 2)) / s, (R(0, 2) - R(2, 0)) / s, (R(1, 0) - R(0, 1)) / s};
  } else if (R(0, 0) > R(1, 1) && R(0, 0) > R(2, 2)) {
    const double s = 2.0 * std::sqrt(1.0 + R(0, 0) - R(1, 1) - R(2, 2));
    q = {(R(2, 1) - R(1, 2)) / s, 0.25 * s, (R(0, 1) + R(1, 0)) / s, (R(0, 2) + R(2, 0)) / s};
  } else if (R(1, 1) > R(2, 2)) {
    const double s = 2.0 * std::sqrt(1.0 + R(1, 1) - R(0, 0) - R(2, 2));
    q = {(R(0, 2) - R(2, 0)) / s, (R(0, 1) + R(1, 0)) / s, 0.25 * s, (R(1, 2) + R(2, 1)) / s};
  } else {
    const double s = 2.0 * std::sqrt(1.0 + R(2, 2) - R(0, 0) - R(1, 1));
    q = {(R(1, 0) - R(0, 1)) / s, (R(0, 2) + R(2, 0)) / s, (R(1, 2) + R(2, 1)) / s, 0.25 * s};
  }
  return q;
}

}  // namespace

Mat3 slerp(const Mat3& A, const Mat3& B, double s) {
  Quat a = quat_of(A), b = quat_of(B);
  double d = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
  if (d < 0.0) {  // the shorter way round
    for (double& v : b) v = -v;
    d = -d;
  }
  Quat q;
  if (d > 0.9995) {
    for (int k = 0; k < 4; ++k) q[k] = a[k] + s * (b[k] - a[k]);
  } else {
    const double th = std::acos(d), sa = std::sin((1 - s) * th) / std::sin(th), sb = std::sin(s * th) / std::sin(th);
    for (int k = 0; k < 4; ++k) q[k] = sa * a[k] + sb * b[k];
  }
  const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  for (double& v : q) v /= n;
  return rotation_of_quaternion(q[0], q[1], q[2], q[3]);
}

KeyframeTrack::KeyframeTrack(const std::array<double, 3>& p, const NamedSections<KeyframeParameters>& keys) : pivot(p) {
  times.push_back(0.0);
  angles.push_back(0.0);
  translations.push_back({0.0, 0.0, 0.0});
  axes.push_back(keys.empty() ? std::array<double, 3>{0, 0, 1} : unit(keys.front().second.axis));
  for (const auto& [kname, k] : keys) {
    times.push_back(k.time);
    angles.push_back(k.angle);
    axes.push_back(unit(k.axis));
    translations.push_back(k.translation);
  }
}

Rigid KeyframeTrack::pose(double t) const {
  std::size_t k = 0;
  while (k + 1 < times.size() && times[k + 1] < t) ++k;
  Mat3 R;
  std::array<double, 3> d;
  if (k + 1 >= times.size()) {  // after the last keyframe: hold it
    R = axis_angle(axes[k], angles[k]);
    d = translations[k];
  } else {
    const double s = std::clamp((t - times[k]) / (times[k + 1] - times[k]), 0.0, 1.0);
    const auto& a0 = axes[k];
    const auto& a1 = axes[k + 1];
    if (a0[0] * a1[0] + a0[1] * a1[1] + a0[2] * a1[2] > 1.0 - 1e-12)  // one axis: the angle itself (beyond pi too)
      R = axis_angle(a1, (1 - s) * angles[k] + s * angles[k + 1]);
    else
      R = slerp(axis_angle(a0, angles[k]), axis_angle(a1, angles[k + 1]), s);
    for (int i = 0; i < 3; ++i) d[i] = (1 - s) * translations[k][i] + s * translations[k + 1][i];
  }
  // x -> R (x - pivot) + pivot + d
  Rigid T;
  T.R = R;
  const auto Rp = T.apply(pivot);
  for (int i = 0; i < 3; ++i) T.t[i] = pivot[i] - Rp[i] + d[i];
  return T;
}

namespace {

// The motion file: per bone name, its world transforms frame by frame.
std::map<std::string, std::vector<Rigid>> read_motion_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open the motion file", InputErrorKind::File);
  std::map<std::string, std::map<long long, Rigid>> by_bone;
  std::string line;
  long lineno = 0;
  while (std::getline(in, line)) {
    ++lineno;
    if (line.empty() || line[0] == '#' || line.rfind("frame", 0) == 0) continue;  // comments, header
    std::vector<std::string> f;
    std::stringstream ss(line);
    for (std::string item; std::getline(ss, item, ',');) f.push_back(item);
    const std::string at = path + ": line " + std::to_string(lineno) + ": ";
    if (f.size() != 14) throw InputError(at + "expected 14 fields (frame, bone, 9 rotation entries, 3 translation entries)");
    if (!strict_number(f[0], true)) throw InputError(at + "the frame '" + f[0] + "' is not a whole number");
    Rigid T;
    for (int k = 0; k < 12; ++k) {
      if (!strict_number(f[2 + k], false)) throw InputError(at + "'" + f[2 + k] + "' is not a finite number");
      const double v = std::strtod(f[2 + k].c_str(), nullptr);
      if (k < 9)
        T.R(k / 3, k % 3) = v;
      else
        T.t[k - 9] = v;
    }
    const Mat3 E = transpose(T.R) * T.R - Mat3::identity();
    if (std::sqrt(frobenius2(E)) > 1e-6 || std::fabs(det(T.R) - 1.0) > 1e-6)
      throw InputError(at + "the rotation is not a rotation (R^T R = I and det R = 1 to 1e-6)");
    std::string bone = f[1];
    bone.erase(0, bone.find_first_not_of(" \t"));
    bone.erase(bone.find_last_not_of(" \t") + 1);
    const long long frame = std::atoll(f[0].c_str());
    if (!by_bone[bone].emplace(frame, T).second)  // a second row would silently replace the first
      throw InputError(at + "bone '" + bone + "' has frame " + std::to_string(frame) + " twice");
  }
  std::map<std::string, std::vector<Rigid>> out;
  for (auto& [bone, frames] : by_bone) {
    long long expect = 0;
    for (const auto& [frame, T] : frames) {
      if (frame != expect) throw InputError(path + ": bone '" + bone + "' has no frame " + std::to_string(expect));
      out[bone].push_back(T);
      ++expect;
    }
  }
  return out;
}

}  // namespace

void Skeleton::bones_from_rig(const SkeletonParameters& p, const Mesh& mesh, const Teuchos::Comm<int>& comm,
                              const std::string& where) {
  const RigClip* rest_clip = read_rig_and_clip(p, comm, where);
  const RigFile& rig = *rig_;
  const std::vector<Affine> rest = rig.pose(rest_clip, p.rest_time);
  if (source_) {
    try {
      retarget_ = std::make_unique<Retarget>(rig, rest, *source_, *clip_, clip_t0_, Retarget::parse_map(p.joint_map), p.retarget_scale);
    } catch (const InputError& e) {
      throw e.prefixed(where + ": ");
    }
  }
  // The lattice's cell size (uniform: any element's edge).
  double h = 0.0;
  auto Xh = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.X);
  auto Ch = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.conn);
  if (mesh.local_elements() > 0)
    for (int d = 0; d < 3; ++d) h = std::max(h, std::fabs(Xh(Ch(0, 1), d) - Xh(Ch(0, 0), d)));
  MPI_Allreduce(MPI_IN_PLACE, &h, 1, MPI_DOUBLE, MPI_MAX, raw_comm(comm));
  rig_path_ = p.rig;
  cell_ = h;
  // Which joints hold flesh, and where: from the skin's weights (the default) or a capsule per joint.
  const RestSkin skin = rest_skin(rig, rest_clip, p.rest_time);
  const bool capsules = p.bone_regions == SkeletonParameters::BoneRegions::Capsules;
  const JointSegments segments = capsules ? capsule_segments(rig, rest, p.bone_radius > 0.0 ? p.bone_radius : 1.5 * h)
                                          : weighted_segments(rig, rest, skin, h, p, where);
  if (segments.joints.empty()) throw InputError(where + ": " + p.rig + " has no joint that moves skin");
  const std::size_t J = segments.joints.size();
  auto owned_counts = [&](const std::vector<std::vector<int>>& of) {
    std::vector<long long> count(J);
    for (std::size_t j = 0; j < J; ++j)
      for (int n : of[j]) count[j] += static_cast<std::size_t>(n) < mesh.n_owned_nodes;
    MPI_Allreduce(MPI_IN_PLACE, count.data(), static_cast<int>(J), MPI_LONG_LONG, MPI_SUM, raw_comm(comm));
    return count;
  };
  std::vector<std::vector<int>> nodes = region_nodes(mesh, segments, 0.0);
  const std::vector<long long> region = owned_counts(nodes);
  std::vector<long long> count = region;
  // (Capsules, the user's 'Bone radius', hold every node within their radius as asked.)
  if (!capsules) {
    nodes = region_nodes(mesh, segments, h, &region);
    count = owned_counts(nodes);
  }
  std::vector<std::vector<Rigid>> frames = sample_frames(segments, rest, p.sample_rate);
  // Joints whose region holds no node anywhere (a finger thinner than the cells) are no bones, nor,
  // where the radius comes from the flesh's thickness, those whose region holds one node: a bone thinner
  // than the lattice, which pulls the flesh around that node as a point load (Testwuson's run with
  // inertia, whose feet each held one node: one quadrature point of a foot's surface cell inverted at
  // frames 8 and 19, J -0.025 and -0.030; with those six joints no bones, none inverted at any frame end).
  // The flesh there follows the bones beside it. Capsules, a 'Bone radius' and joints included by name
  // that dominate no skin (capsules of 1.5 cells) hold what they are asked to.
  const bool thickness_radius = !capsules && !(p.bone_radius > 0.0);
  for (std::size_t j = 0; j < J; ++j) {
    Joint report;
    report.name = rig.nodes[segments.joints[j]].name;
    report.why = segments.why[j];
    report.nodes = count[j];
    report.dominated = segments.dominated[j];
    report.radius = segments.radius[j];
    report.gap = segments.gap[j];
    report.a = segments.a[j];
    report.b = segments.b[j];
    double L2 = 0.0;
    for (int i = 0; i < 3; ++i) L2 += (segments.b[j][i] - segments.a[j][i]) * (segments.b[j][i] - segments.a[j][i]);
    report.length = std::sqrt(L2);
    const bool point = thickness_radius && segments.capped[j] && count[j] == 1;
    report.bone = segments.candidate[j] && count[j] > 0 && !point;
    if (segments.candidate[j] && point) {
      char buf[200];
      std::snprintf(buf, sizeof buf, "too thin for the lattice: its region (radius %.3g m) holds one node, which it would "
                    "pull as a point load; the flesh there follows the bones beside it", segments.radius[j]);
      report.why = buf;
    } else if (segments.candidate[j] && count[j] == 0) {
      char buf[200];
      if (region[j] > 0)
        std::snprintf(buf, sizeof buf, "too small beside another bone: its region's %lld node%s within a cell of a larger "
                      "bone's, and the flesh between bones is left free", region[j], region[j] == 1 ? " lies" : "s lie");
      else
        std::snprintf(buf, sizeof buf, "too thin for the lattice: its region (radius %.3g m) holds no node of the %.3g m cells",
                      segments.radius[j], h);
      report.why = buf;
    }
    joints_.push_back(report);
    if (!report.bone) {
      ++unused_joints_;
      continue;
    }
    Bone bone;
    bone.name = report.name;
    bone.frames = std::move(frames[j]);
    bone.nodes = std::move(nodes[j]);
    bones_.push_back(std::move(bone));
  }
  if (bones_.empty())
    throw InputError(where + ": no joint of " + p.rig +
                     " holds enough lattice nodes to be a bone (two; one with capsules or a 'Bone radius'; the cells are " +
                     std::to_string(h) + " m; 'sinew --check' lists each joint and why)");
  if (p.rig_weights) rig_weights_ = skin_weights(mesh, skin);
}

namespace {

double distance(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

}  // namespace

Skeleton::RestSkin Skeleton::rest_skin(const RigFile& rig, const RigClip* rest_clip, double rest_time) {
  RestSkin skin;
  for (std::size_t m = 0; m < rig.meshes.size(); ++m) {
    const auto x = rig.skin(static_cast<int>(m), rest_clip, rest_time);
    std::vector<std::vector<std::pair<int, double>>> w(x.size());
    for (const auto& bone : rig.meshes[m].bones)
      for (const auto& [v, wt] : bone.weights)
        if (wt > 0.0) w[v].emplace_back(bone.node, wt);
    skin.x.insert(skin.x.end(), x.begin(), x.end());
    skin.w.insert(skin.w.end(), w.begin(), w.end());
  }
  return skin;
}

Skeleton::JointSegments Skeleton::capsule_segments(const RigFile& rig, const std::vector<Affine>& rest, double radius) {
  // Each joint's segment at rest: from its origin to its first child joint's (a point for a leaf).
  JointSegments s;
  for (std::size_t n = 0; n < rig.nodes.size(); ++n) {
    if (!rig.nodes[n].joint) continue;
    s.joints.push_back(static_cast<int>(n));
    s.a.push_back(rest[n].t);
    s.b.push_back(rest[n].t);
    for (std::size_t c = n + 1; c < rig.nodes.size(); ++c)
      if (rig.nodes[c].parent == static_cast<int>(n) && rig.nodes[c].joint) {
        s.b.back() = rest[c].t;
        break;
      }
    s.radius.push_back(radius);
    s.gap.push_back(0.0);
    s.capped.push_back(0);
    s.candidate.push_back(1);
    s.why.push_back("moves skin (capsules)");
    s.dominated.push_back(0);
  }
  return s;
}

Skeleton::JointSegments Skeleton::weighted_segments(const RigFile& rig, const std::vector<Affine>& rest, const RestSkin& skin,
                                                    double h, const SkeletonParameters& p, const std::string& where) {
  // The skin a joint dominates: the vertices whose largest weight is its own. A joint that dominates
  // none (a facial control, a helper, a tail whose mesh is absent) holds no flesh.
  const std::size_t N = rig.nodes.size();
  std::vector<long long> dominated(N, 0);
  std::vector<std::array<double, 3>> centroid(N, {0.0, 0.0, 0.0});
  std::vector<int> owner(skin.x.size(), -1);
  for (std::size_t v = 0; v < skin.x.size(); ++v) {
    double best = 0.0;
    for (const auto& [node, w] : skin.w[v])
      if (w > best) {
        best = w;
        owner[v] = node;
      }
    if (owner[v] < 0) continue;
    ++dominated[owner[v]];
    for (int i = 0; i < 3; ++i) centroid[owner[v]][i] += skin.x[v][i];
  }
  // The user's lists, each name a joint of the file.
  auto listed = [&](const std::string& text, const char* entry) {
    std::vector<char> in(N, 0);
    for (const std::string& name : comma_list(text)) {
      const int n = rig.node_index(name);
      if (n < 0 || !rig.nodes[n].joint) {
        std::vector<std::string> names;
        for (const auto& node : rig.nodes)
          if (node.joint) names.push_back(node.name);
        const std::string near = closest_name(name, names);
        throw InputError(where + ": '" + entry + "': \"" + name + "\" is not a joint of " + rig.path + " that moves skin" +
                         (near.empty() ? "" : " (did you mean \"" + near + "\"?)"));
      }
      in[n] = 1;
    }
    return in;
  };
  const std::vector<char> skip = listed(p.skip_joints, "Skip joints"), include = listed(p.include_joints, "Include joints");
  JointSegments s;
  std::vector<double> d;
  for (std::size_t n = 0; n < N; ++n) {
    if (!rig.nodes[n].joint) continue;
    const auto a = rest[n].t;
    std::array<double, 3> b = a;
    std::vector<std::array<double, 3>> children;
    for (std::size_t c = n + 1; c < N; ++c)
      if (rig.nodes[c].parent == static_cast<int>(n) && rig.nodes[c].joint) children.push_back(rest[c].t);
    s.joints.push_back(static_cast<int>(n));
    s.dominated.push_back(dominated[n]);
    if (skip[n] || (dominated[n] == 0 && !include[n])) {
      s.a.push_back(a);
      s.b.push_back(children.empty() ? a : children.front());
      s.radius.push_back(0.0);
      s.gap.push_back(0.0);
      s.capped.push_back(0);
      s.candidate.push_back(0);
      s.why.push_back(skip[n] ? "skipped: listed in 'Skip joints'" : "dominates no skin: no skin vertex has its largest weight here");
      continue;
    }
    if (dominated[n] == 0) {  // included by name: a capsule to its first child, as 'Bone regions' capsules
      s.a.push_back(a);
      s.b.push_back(children.empty() ? a : children.front());
      s.radius.push_back(p.bone_radius > 0.0 ? p.bone_radius : 1.5 * h);
      s.gap.push_back(0.0);
      s.capped.push_back(0);
      s.candidate.push_back(1);
      s.why.push_back("included ('Include joints'), dominates no skin vertex");
      continue;
    }
    // The segment: to the child joint nearest the middle of the dominated skin (a limb's next joint),
    // else, for a leaf or children at the joint itself, to that middle.
    std::array<double, 3> c = centroid[n];
    for (double& v : c) v /= static_cast<double>(dominated[n]);
    double best = HUGE_VAL;
    for (const auto& child : children)
      if (distance(child, a) >= 0.5 * h && distance(child, c) < best) {
        best = distance(child, c);
        b = child;
      }
    if (best == HUGE_VAL) b = c;
    // The local thickness: the median distance from the segment to the dominated skin.
    d.clear();
    for (std::size_t v = 0; v < skin.x.size(); ++v)
      if (owner[v] == static_cast<int>(n)) d.push_back(segment_distance(skin.x[v].data(), a, b));
    std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2), d.end());
    const double thickness = d[d.size() / 2];
    const double radius = p.bone_radius > 0.0 ? p.bone_radius : p.bone_thickness * thickness;
    const double L = distance(a, b);
    s.a.push_back(a);
    s.b.push_back(b);
    s.radius.push_back(radius);
    s.gap.push_back(std::min(p.joint_gap > 0.0 ? p.joint_gap : std::max(h, radius), 0.35 * L));
    s.capped.push_back(1);
    s.candidate.push_back(1);
    char buf[96];
    std::snprintf(buf, sizeof buf, "dominates %lld skin vertices, flesh %.3g m thick", dominated[n], thickness);
    s.why.push_back(buf);
  }
  return s;
}

std::vector<std::vector<int>> Skeleton::region_nodes(const Mesh& mesh, const JointSegments& s, double h,
                                                     const std::vector<long long>* sizes) {
  // Each node to the joint whose region holds it most deeply (distance over radius): production rigs'
  // regions overlap.
  auto Xh = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.X);
  std::vector<std::vector<int>> nodes(s.joints.size());
  auto assign = [&](const double X[3]) {
    int best = -1;
    double best_q = 1.0;
    for (std::size_t j = 0; j < s.joints.size(); ++j) {
      if (!s.candidate[j] || !(s.radius[j] > 0.0)) continue;
      double dist;
      if (!s.capped[j]) {
        dist = segment_distance(X, s.a[j], s.b[j]);
      } else {
        // A cylinder over the segment without 'gap' at either end (a ball at the middle of a segment
        // too short for both gaps).
        const auto &a = s.a[j], &b = s.b[j];
        const double L = distance(a, b), g = s.gap[j];
        const double r[3] = {X[0] - a[0], X[1] - a[1], X[2] - a[2]};
        if (L - 2.0 * g <= 1e-12 * (L + 1.0)) {
          const std::array<double, 3> m{0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2])};
          dist = distance({X[0], X[1], X[2]}, m);
        } else {
          const double u[3] = {(b[0] - a[0]) / L, (b[1] - a[1]) / L, (b[2] - a[2]) / L};
          const double along = r[0] * u[0] + r[1] * u[1] + r[2] * u[2];
          if (along < g || along > L - g) continue;
          double perp2 = 0.0;
          for (int i = 0; i < 3; ++i) perp2 += (r[i] - along * u[i]) * (r[i] - along * u[i]);
          dist = std::sqrt(perp2);
        }
      }
      const double q = dist / s.radius[j];
      if (q <= best_q) {
        best_q = q;
        best = static_cast<int>(j);
      }
    }
    return best;
  };
  // No two bones hold nodes of one cell (one cell away along the lattice, diagonals included): the gaps
  // at a bone's ends free the flesh along a chain, but two bones whose regions meet side by side held
  // neighbouring nodes, and the cell between them was crushed when one turned past the other
  // (Testwuson's run: 21 inverted points at load steps 17-20, all in one cell whose three nodes moved
  // with one bone and whose far face turned 6-8 cm past them with another; with a free layer between
  // bones, 0 inverted at every frame, 191 Newton iterations instead of 195). One side of each meeting
  // gives way, the smaller region (else the later joint), so that one free node lies between two bones'
  // held ones: where both gave way, the FBX bar (two cells thick) went from 0 to 2 inverted points in its
  // dynamic run; where the larger gave way, to 4 (its Bone.006, one node, pulled the flesh around it as a
  // point load); the smaller, 0, and Wuson's run 0 and 1 as with both. A function of the
  // rest position alone (the neighbours are probed where the lattice puts them), so every rank decides
  // the same for a node it shares.
  auto yields_to = [&](int bone, int other) {
    const long long a = sizes ? (*sizes)[bone] : 0, b = sizes ? (*sizes)[other] : 0;
    return a != b ? a < b : bone > other;
  };
  auto next_to_other = [&](const double X[3], int bone) {
    for (int i = -1; i <= 1; ++i)
      for (int j = -1; j <= 1; ++j)
        for (int k = -1; k <= 1; ++k) {
          const double Y[3] = {X[0] + i * h, X[1] + j * h, X[2] + k * h};
          const int other = assign(Y);
          if (other >= 0 && other != bone && yields_to(bone, other)) return true;
        }
    return false;
  };
  for (std::size_t n = 0; n < mesh.local_nodes(); ++n) {
    const double X[3] = {Xh(n, 0), Xh(n, 1), Xh(n, 2)};
    const int best = assign(X);
    if (best >= 0 && !(h > 0.0 && next_to_other(X, best))) nodes[best].push_back(static_cast<int>(n));
  }
  return nodes;
}

std::string Skeleton::joint_listing() const {
  std::string out = "joints of " + rig_path_ + " (bone or not, lattice nodes held, radius, free flesh at each end):\n";
  std::size_t w = 0;
  for (const Joint& j : joints_) w = std::max(w, j.name.size());
  for (const Joint& j : joints_) {
    char buf[256];
    if (j.bone)
      std::snprintf(buf, sizeof buf, "  %-*s  bone  %6lld nodes  radius %.3g m  gap %.3g m  length %.3g m  (%s)\n", static_cast<int>(w),
                    j.name.c_str(), j.nodes, j.radius, j.gap, j.length, j.why.c_str());
    else
      std::snprintf(buf, sizeof buf, "  %-*s  no    %s\n", static_cast<int>(w), j.name.c_str(), j.why.c_str());
    out += buf;
  }
  return out;
}

std::string Skeleton::joint_summary() const {
  // "32 bones from the joints of F (22 joints hold no flesh: 14 dominate no skin vertex, ...)"
  std::map<std::string, int> why;
  for (const Joint& j : joints_)
    if (!j.bone) ++why[j.why.substr(0, j.why.find(':'))];
  std::string out = std::to_string(bones_.size()) + " bones from the joints of " + rig_path_;
  if (unused_joints_ > 0) {
    out += " (" + std::to_string(unused_joints_) + " joint" + (unused_joints_ == 1 ? "" : "s") + " hold no flesh:";
    bool first = true;
    for (const auto& [reason, k] : why) {
      out += (first ? " " : ", ") + std::to_string(k) + " " + reason;
      first = false;
    }
    out += ")";
  }
  return out;
}

const RigClip* Skeleton::read_rig_and_clip(const SkeletonParameters& p, const Teuchos::Comm<int>& comm, const std::string& where) {
  auto file = std::make_shared<RigFile>();
  collectively(raw_comm(comm), [&] { *file = read_rig_file(p.rig); });
  rig_ = file;
  const RigFile& rig = *file;
  // The clip: the rig's own, or another file's carried onto the rig's joints ('Retarget from').
  if (!p.retarget.empty()) {
    auto source = std::make_shared<RigFile>();
    collectively(raw_comm(comm), [&] { *source = read_rig_file(p.retarget); });
    source_ = source;
  }
  const RigFile& moving = source_ ? *source_ : rig;
  const RigClip* clip = moving.clip(p.clip);
  if (!clip) {
    std::string names;
    for (const auto& c : moving.clips) names += (names.empty() ? "'" : ", '") + c.name + "'";
    throw InputError(where + ": " + moving.path + (p.clip.empty() ? " has no animation clip" : " has no clip '" + p.clip + "'") +
                     (names.empty() ? "" : " (it has " + names + ")"));
  }
  const double t0 = p.clip_start, t1 = p.clip_end >= 0.0 ? p.clip_end : clip->duration;
  if (!(t1 > t0)) throw InputError(where + ": 'Clip start' " + std::to_string(t0) + " is not before the clip's end " + std::to_string(t1));
  clip_ = clip;
  clip_t0_ = t0;
  clip_t1_ = t1;
  // The rest pose: a frame of the rig's own clip (when retargeting, its first) or the bind pose.
  const RigClip* rest_clip = nullptr;
  if (p.rest_time >= 0.0) {
    rest_clip = source_ ? rig.clip("") : clip;
    if (!rest_clip) throw InputError(where + ": 'Rest time' needs a clip in " + p.rig + ", which has none");
  }
  return rest_clip;
}

std::vector<std::vector<Rigid>> Skeleton::sample_frames(const JointSegments& s, const std::vector<Affine>& rest, double sample_rate) {
  // The clip sampled into frames over the load; each joint's motion from rest made rigid about its
  // origin (a production rig may scale or shear: the departure is kept for the run's header).
  const int F = std::max(1, static_cast<int>(std::ceil((clip_t1_ - clip_t0_) * sample_rate)));
  std::vector<std::vector<Rigid>> frames(s.joints.size());
  for (int k = 0; k <= F; ++k) {
    const std::vector<Affine> W = rig_pose(static_cast<double>(k) / F);
    for (std::size_t j = 0; j < s.joints.size(); ++j) {
      const Affine D = W[s.joints[j]].after(rest[s.joints[j]].inverse());
      Rigid T;
      T.R = nearest_rotation(D.A);
      for (int q = 0; q < 9; ++q) nonrigid_ = std::max(nonrigid_, std::fabs(T.R[q] - D.A[q]));
      const auto c = D.apply(s.a[j]);
      for (int i = 0; i < 3; ++i) T.t[i] = c[i] - (T.R(i, 0) * s.a[j][0] + T.R(i, 1) * s.a[j][1] + T.R(i, 2) * s.a[j][2]);
      frames[j].push_back(T);
    }
  }
  return frames;
}

std::vector<std::vector<std::pair<int, double>>> Skeleton::skin_weights(const Mesh& mesh, const RestSkin& skin) const {
  // The file's own skinning weights for the first guess: each owned node takes those of the nearest
  // skin vertex at rest, over the joints that became bones (renormalized; none left: distance weights).
  const RigFile& rig = *rig_;
  auto Xh = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.X);
  std::vector<int> bone_of(rig.nodes.size(), -1);
  for (std::size_t k = 0; k < bones_.size(); ++k) bone_of[rig.node_index(bones_[k].name)] = static_cast<int>(k);
  const auto& vx = skin.x;
  std::vector<std::vector<std::pair<int, double>>> vw(vx.size());
  for (std::size_t v = 0; v < vx.size(); ++v)
    for (const auto& [node, wt] : skin.w[v])
      if (bone_of[node] >= 0) vw[v].emplace_back(bone_of[node], wt);
  std::vector<std::vector<std::pair<int, double>>> weights(mesh.n_owned_nodes);
#pragma omp parallel for schedule(dynamic, 64)
  for (long long n = 0; n < static_cast<long long>(mesh.n_owned_nodes); ++n) {
    double best = HUGE_VAL;
    std::size_t at = 0;
    for (std::size_t v = 0; v < vx.size(); ++v) {
      double d = 0.0;
      for (int i = 0; i < 3; ++i) d += (vx[v][i] - Xh(n, i)) * (vx[v][i] - Xh(n, i));
      if (d < best && !vw[v].empty()) {
        best = d;
        at = v;
      }
    }
    if (best == HUGE_VAL) continue;
    double total = 0.0;
    for (const auto& bw : vw[at]) total += bw.second;
    auto w = vw[at];
    for (auto& bw : w) bw.second /= total;
    weights[n] = std::move(w);
  }
  return weights;
}

std::vector<Affine> Skeleton::rig_pose(double load) const {
  if (!rig_) return {};
  const double seconds = rig_seconds(load);
  return retarget_ ? retarget_->pose(seconds) : rig_->pose(clip_, seconds);
}

Skeleton::Skeleton(const SkeletonParameters& p, const Mesh& mesh, const Teuchos::Comm<int>& comm, const std::string& where)
    : skinning_(p.skinning), falloff_(p.falloff) {
  if (!p.rig.empty()) bones_from_rig(p, mesh, comm, where);
  std::map<std::string, std::vector<Rigid>> frames;
  if (!p.motion_file.empty()) collectively(raw_comm(comm), [&] { frames = read_motion_file(p.motion_file); });
  std::size_t nframes = 0;
  for (const auto& [name, bp] : p.bones) {
    Bone b;
    b.name = name;
    b.track = KeyframeTrack(bp.pivot, bp.keyframes);
    if (!p.motion_file.empty()) {
      const auto it = frames.find(name);
      if (it == frames.end()) throw InputError(where + "/Bones/" + name + ": the motion file has no frames for this bone");
      if (nframes != 0 && it->second.size() != nframes)
        throw InputError(p.motion_file + ": bone '" + name + "' has " + std::to_string(it->second.size()) + " frames, others " +
                         std::to_string(nframes));
      nframes = it->second.size();
      b.frames = it->second;
    }
    b.nodes = select_region(mesh, comm, bp.region, where + "/Bones/" + name);
    bones_.push_back(std::move(b));
  }
  for (std::size_t k = 0; k < p.bones.size(); ++k)
    for (std::size_t j = 0; j < bones_.size(); ++j)
      if (p.bones[k].second.parent == bones_[j].name) bones_[k].parent = static_cast<int>(j);
  for (const auto& [bone, f] : frames)
    if (std::none_of(bones_.begin(), bones_.end(), [&](const Bone& b) { return b.name == bone; }))
      throw InputError(p.motion_file + ": bone '" + bone + "' is not in the skeleton's Bones");

  // Each bone's segment for the skinning weights: the principal axis of its attached nodes, spanning
  // their extent along it (a point for a single node).
  auto Xh = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.X);
  MPI_Comm c = raw_comm(comm);
  for (Bone& b : bones_) {
    double s[10] = {0};  // count, sum x (3), sum x x^T (6)
    for (int n : b.nodes) {
      if (static_cast<std::size_t>(n) >= mesh.n_owned_nodes) continue;
      const double x[3] = {Xh(n, 0), Xh(n, 1), Xh(n, 2)};
      s[0] += 1;
      for (int i = 0; i < 3; ++i) s[1 + i] += x[i];
      s[4] += x[0] * x[0];
      s[5] += x[1] * x[1];
      s[6] += x[2] * x[2];
      s[7] += x[0] * x[1];
      s[8] += x[0] * x[2];
      s[9] += x[1] * x[2];
    }
    MPI_Allreduce(MPI_IN_PLACE, s, 10, MPI_DOUBLE, MPI_SUM, c);
    if (s[0] == 0) throw InputError(where + "/Bones/" + b.name + ": its region selects no node", InputErrorKind::EmptyRegion);
    const double m[3] = {s[1] / s[0], s[2] / s[0], s[3] / s[0]};
    double C[9] = {s[4] / s[0] - m[0] * m[0], s[7] / s[0] - m[0] * m[1], s[8] / s[0] - m[0] * m[2],
                   s[7] / s[0] - m[0] * m[1], s[5] / s[0] - m[1] * m[1], s[9] / s[0] - m[1] * m[2],
                   s[8] / s[0] - m[0] * m[2], s[9] / s[0] - m[1] * m[2], s[6] / s[0] - m[2] * m[2]};
    double ev[3], Q[9];
    jacobi_eigen<3>(C, ev, Q);
    const int k = ev[0] >= ev[1] && ev[0] >= ev[2] ? 0 : (ev[1] >= ev[2] ? 1 : 2);
    const double axis[3] = {Q[0 * 3 + k], Q[1 * 3 + k], Q[2 * 3 + k]};
    double ext[2] = {HUGE_VAL, HUGE_VAL};  // -min, max of the projection
    for (int n : b.nodes) {
      if (static_cast<std::size_t>(n) >= mesh.n_owned_nodes) continue;
      double proj = 0.0;
      for (int i = 0; i < 3; ++i) proj += (Xh(n, i) - m[i]) * axis[i];
      ext[0] = std::min(ext[0], proj);
      ext[1] = std::min(ext[1], -proj);
    }
    MPI_Allreduce(MPI_IN_PLACE, ext, 2, MPI_DOUBLE, MPI_MIN, c);
    for (int i = 0; i < 3; ++i) {
      b.seg_a[i] = m[i] + ext[0] * axis[i];
      b.seg_b[i] = m[i] - ext[1] * axis[i];
      b.centre[i] = m[i];
    }
  }
  plan_run_up(p.run_up);
  // Skinning weights of the owned nodes: 1/d^p to each bone, normalized; small ones dropped.
  weights_.assign(mesh.n_owned_nodes, {});
  if (bones_.empty()) return;
  const double scale = std::max({mesh.upper[0] - mesh.lower[0], mesh.upper[1] - mesh.lower[1], mesh.upper[2] - mesh.lower[2]});
  for (std::size_t n = 0; n < mesh.n_owned_nodes; ++n) {
    const double X[3] = {Xh(n, 0), Xh(n, 1), Xh(n, 2)};
    double total = 0.0;
    std::vector<std::pair<int, double>> w;
    for (std::size_t b = 0; b < bones_.size(); ++b) {
      const double d = std::max(segment_distance(X, bones_[b].seg_a, bones_[b].seg_b), 1e-6 * scale);
      w.emplace_back(static_cast<int>(b), std::pow(d / scale, -falloff_));
      total += w.back().second;
    }
    for (auto& [b, v] : w) v /= total;
    w.erase(std::remove_if(w.begin(), w.end(), [](const auto& bw) { return bw.second < 1e-4; }), w.end());
    total = 0.0;
    for (const auto& bw : w) total += bw.second;
    for (auto& [b, v] : w) v /= total;
    weights_[n] = std::move(w);
  }
  for (std::size_t n = 0; n < rig_weights_.size(); ++n)
    if (!rig_weights_[n].empty()) weights_[n] = std::move(rig_weights_[n]);
  rig_weights_.clear();
}

Rigid Skeleton::local(const Bone& b, double t) const {
  if (!b.frames.empty()) {  // world transforms from the motion file: no parent to compose
    const double f = std::clamp(t, 0.0, 1.0) * static_cast<double>(b.frames.size() - 1);
    const std::size_t k = std::min(static_cast<std::size_t>(f), b.frames.size() - 1);
    if (k + 1 >= b.frames.size()) return b.frames.back();
    const double s = f - static_cast<double>(k);
    Rigid T;
    T.R = slerp(b.frames[k].R, b.frames[k + 1].R, s);
    for (int i = 0; i < 3; ++i) T.t[i] = (1 - s) * b.frames[k].t[i] + s * b.frames[k + 1].t[i];
    return T;
  }
  return b.track.pose(t);
}

Rigid Skeleton::posed(std::size_t b, double t) const {
  const Bone& bone = bones_[b];
  const Rigid L = local(bone, t);
  if (bone.parent < 0 || !bone.frames.empty()) return L;
  return posed(static_cast<std::size_t>(bone.parent), t).after(L);
}

Rigid Skeleton::transform(std::size_t b, double t) const {
  if (run_up_ < 1.0 && t <= 0.0) return run_up_pose(b, run_up_);
  return posed(b, t);
}

Rigid Skeleton::run_up_pose(std::size_t b, double s) const {
  // x -> R_s (x - c) + c + s (T(c) - c), R_s = slerp(I, R, s): the bone's centre c on a straight line.
  const Rigid T = posed(b, 0.0);
  const auto& c = bones_[b].centre;
  const auto Tc = T.apply(c);
  Rigid P;
  P.R = slerp(Mat3::identity(), T.R, s);
  const auto Rc = P.apply(c);
  for (int i = 0; i < 3; ++i) P.t[i] = c[i] - Rc[i] + s * (Tc[i] - c[i]);
  return P;
}

Skeleton::PeakSpeed Skeleton::peak_speed(const Mesh& mesh, const Teuchos::Comm<int>& comm, int samples, double seconds) const {
  PeakSpeed peak;
  if (bones_.empty() || samples < 1 || !(seconds > 0.0)) return peak;
  auto Xh = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.X);
  const double dt = seconds / samples;
  double speed = 0.0;
  int where[2] = {0, -1};  // the sample and the bone of this rank's fastest node
  for (std::size_t b = 0; b < bones_.size(); ++b) {
    Rigid before = posed(b, 0.0), last = before;  // the poses at samples k - 2 and k - 1
    for (int k = 1; k <= samples; ++k) {
      const Rigid next = posed(b, static_cast<double>(k) / samples);
      for (int n : bones_[b].nodes) {
        if (static_cast<std::size_t>(n) >= mesh.n_owned_nodes) continue;
        const std::array<double, 3> X{Xh(n, 0), Xh(n, 1), Xh(n, 2)};
        const auto x2 = next.apply(X), x1 = last.apply(X), x0 = before.apply(X);
        const double v = distance(x2, x1) / dt;
        if (v > speed) {
          speed = v;
          where[0] = k;
          where[1] = static_cast<int>(b);
        }
        if (k >= 2) {
          double a2 = 0.0;
          for (int i = 0; i < 3; ++i) a2 += (x2[i] - 2.0 * x1[i] + x0[i]) * (x2[i] - 2.0 * x1[i] + x0[i]);
          peak.acceleration = std::max(peak.acceleration, std::sqrt(a2) / (dt * dt));
        }
      }
      before = last;
      last = next;
    }
  }
  const MPI_Comm c = raw_comm(comm);
  MPI_Allreduce(MPI_IN_PLACE, &peak.acceleration, 1, MPI_DOUBLE, MPI_MAX, c);
  // The rank with the fastest node says where (bones are the same on every rank).
  struct {
    double speed;
    int rank;
  } mine{speed, comm.getRank()}, top{0.0, 0};
  MPI_Allreduce(&mine, &top, 1, MPI_DOUBLE_INT, MPI_MAXLOC, c);
  MPI_Bcast(where, 2, MPI_INT, top.rank, c);
  peak.speed = top.speed;
  peak.sample = where[0];
  if (where[1] >= 0) peak.bone = bones_[static_cast<std::size_t>(where[1])].name;
  return peak;
}

void Skeleton::plan_run_up(int steps) {
  // The largest rotation of a bone from rest to load 0 sets the automatic count: one step per 15 degrees
  // (at most 10); none when every bone starts at rest.
  // (A shift of the bones' centres counts by how far it departs from their mean shift: a character
  // placed elsewhere in the world moves rigidly, which the skinning guess carries exactly.)
  double angle = 0.0, shift = 0.0;
  std::array<double, 3> mean{0.0, 0.0, 0.0};
  std::vector<std::array<double, 3>> d(bones_.size());
  for (std::size_t b = 0; b < bones_.size(); ++b) {
    const Rigid T = posed(b, 0.0);
    const double c = std::clamp(0.5 * (T.R(0, 0) + T.R(1, 1) + T.R(2, 2) - 1.0), -1.0, 1.0);
    angle = std::max(angle, std::acos(c));
    const auto Tc = T.apply(bones_[b].centre);
    for (int i = 0; i < 3; ++i) {
      d[b][i] = Tc[i] - bones_[b].centre[i];
      mean[i] += d[b][i] / static_cast<double>(bones_.size());
    }
  }
  for (const auto& db : d) shift = std::max(shift, distance(db, mean));
  start_rotation_ = angle;
  if (steps >= 0)
    run_up_steps_ = steps;
  else if (angle < M_PI / 180.0 && shift <= 0.25 * cell_)  // the skinning guess covers a degree or a rigid shift
    run_up_steps_ = 0;
  else
    run_up_steps_ = std::clamp(static_cast<int>(std::ceil(angle / (15.0 * M_PI / 180.0))), 1, 10);
}

void Skeleton::skin(double t0, double t1, const double* X, const std::vector<char>& free, double* u, std::size_t owned) const {
  std::vector<Rigid> M(bones_.size());
  for (std::size_t b = 0; b < bones_.size(); ++b) M[b] = transform(b, t1).after(transform(b, t0).inverse());
  skin_by(M, X, free, u, owned);
}

void Skeleton::skin_acceleration(double t0, double t1, const double* X, const std::vector<char>& free, const double* u,
                                 double* guess, double scale, std::size_t owned) const {
  const double tp = std::max(0.0, t0 - (t1 - t0));
  std::vector<Rigid> ahead(bones_.size()), back(bones_.size());
  for (std::size_t b = 0; b < bones_.size(); ++b) {
    const Rigid from = transform(b, t0).inverse();
    ahead[b] = transform(b, t1).after(from);
    back[b] = transform(b, tp).after(from);
  }
  for (std::size_t n = 0; n < owned; ++n) {
    if (!free[n] || weights_[n].empty()) continue;
    const std::array<double, 3> x{X[3 * n] + u[3 * n], X[3 * n + 1] + u[3 * n + 1], X[3 * n + 2] + u[3 * n + 2]};
    std::array<double, 3> a{0.0, 0.0, 0.0};
    for (const auto& [b, w] : weights_[n]) {
      const auto y = ahead[b].apply(x), z = back[b].apply(x);
      for (int i = 0; i < 3; ++i) a[i] += w * (y[i] + z[i] - 2.0 * x[i]);
    }
    for (int i = 0; i < 3; ++i) guess[3 * n + i] += scale * a[i];
  }
}

void Skeleton::skin_run_up(double s0, double s1, const double* X, const std::vector<char>& free, double* u, std::size_t owned) const {
  std::vector<Rigid> M(bones_.size());
  for (std::size_t b = 0; b < bones_.size(); ++b) M[b] = run_up_pose(b, s1).after(run_up_pose(b, s0).inverse());
  skin_by(M, X, free, u, owned);
}

void Skeleton::skin_by(const std::vector<Rigid>& M, const double* X, const std::vector<char>& free, double* u, std::size_t owned) const {
  for (std::size_t n = 0; n < owned; ++n) {
    if (!free[n] || weights_[n].empty()) continue;
    const std::array<double, 3> x{X[3 * n] + u[3 * n], X[3 * n + 1] + u[3 * n + 1], X[3 * n + 2] + u[3 * n + 2]};
    std::array<double, 3> y{0.0, 0.0, 0.0};
    for (const auto& [b, w] : weights_[n]) {
      const auto z = M[b].apply(x);
      for (int i = 0; i < 3; ++i) y[i] += w * z[i];
    }
    for (int i = 0; i < 3; ++i) u[3 * n + i] = y[i] - X[3 * n + i];
  }
}

}  // namespace sinew
