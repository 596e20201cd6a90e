// Skeleton: bone regions, keyframe (or motion-file) interpolation composed down the hierarchy, and the
// linear-blend-skinning predictor for each load step.
#include <sinew/core/collective.hpp>
#include <sinew/core/sym_eigen.hpp>
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
  const JointSegments segments = joint_segments(rig, rest);
  if (segments.joints.empty()) throw InputError(where + ": " + p.rig + " has no joint that moves skin");
  // The capsule radius: 1.5 cells unless given (the lattice is uniform: any element's edge).
  double h = 0.0;
  auto Xh = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.X);
  auto Ch = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.conn);
  if (mesh.local_elements() > 0)
    for (int d = 0; d < 3; ++d) h = std::max(h, std::fabs(Xh(Ch(0, 1), d) - Xh(Ch(0, 0), d)));
  MPI_Allreduce(MPI_IN_PLACE, &h, 1, MPI_DOUBLE, MPI_MAX, raw_comm(comm));
  const double radius = p.bone_radius > 0.0 ? p.bone_radius : 1.5 * h;
  std::vector<std::vector<int>> nodes = capsule_nodes(mesh, segments, radius);
  std::vector<std::vector<Rigid>> frames = sample_frames(segments, rest, p.sample_rate);
  // Joints whose capsule holds no node anywhere (a finger thinner than the cells) are no bones.
  std::vector<long long> count(segments.joints.size());
  for (std::size_t j = 0; j < segments.joints.size(); ++j)
    for (int n : nodes[j]) count[j] += static_cast<std::size_t>(n) < mesh.n_owned_nodes;
  MPI_Allreduce(MPI_IN_PLACE, count.data(), static_cast<int>(count.size()), MPI_LONG_LONG, MPI_SUM, raw_comm(comm));
  for (std::size_t j = 0; j < segments.joints.size(); ++j) {
    if (count[j] == 0) {
      ++unused_joints_;
      continue;
    }
    Bone bone;
    bone.name = rig.nodes[segments.joints[j]].name;
    bone.frames = std::move(frames[j]);
    bone.nodes = std::move(nodes[j]);
    bones_.push_back(std::move(bone));
  }
  if (bones_.empty()) throw InputError(where + ": no joint of " + p.rig + " holds a lattice node within 'Bone radius' " + std::to_string(radius));
  if (p.rig_weights) rig_weights_ = skin_weights(mesh, rest_clip, p.rest_time);
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

Skeleton::JointSegments Skeleton::joint_segments(const RigFile& rig, const std::vector<Affine>& rest) {
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
  }
  return s;
}

std::vector<std::vector<int>> Skeleton::capsule_nodes(const Mesh& mesh, const JointSegments& s, double radius) {
  // Nodes to the nearest capsule that holds them (production rigs' capsules overlap).
  auto Xh = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.X);
  std::vector<std::vector<int>> nodes(s.joints.size());
  for (std::size_t n = 0; n < mesh.local_nodes(); ++n) {
    const double X[3] = {Xh(n, 0), Xh(n, 1), Xh(n, 2)};
    int best = -1;
    double best_d = radius;
    for (std::size_t j = 0; j < s.joints.size(); ++j) {
      const double d = segment_distance(X, s.a[j], s.b[j]);
      if (d <= best_d) {
        best_d = d;
        best = static_cast<int>(j);
      }
    }
    if (best >= 0) nodes[best].push_back(static_cast<int>(n));
  }
  return nodes;
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

std::vector<std::vector<std::pair<int, double>>> Skeleton::skin_weights(const Mesh& mesh, const RigClip* rest_clip,
                                                                         double rest_time) const {
  // The file's own skinning weights for the first guess: each owned node takes those of the nearest
  // skin vertex at rest, over the joints that became bones (renormalized; none left: distance weights).
  const RigFile& rig = *rig_;
  auto Xh = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.X);
  std::vector<int> bone_of(rig.nodes.size(), -1);
  for (std::size_t k = 0; k < bones_.size(); ++k) bone_of[rig.node_index(bones_[k].name)] = static_cast<int>(k);
  std::vector<std::array<double, 3>> vx;
  std::vector<std::vector<std::pair<int, double>>> vw;
  for (std::size_t m = 0; m < rig.meshes.size(); ++m) {
    const auto x = rig.skin(static_cast<int>(m), rest_clip, rest_time);
    std::vector<std::vector<std::pair<int, double>>> w(x.size());
    for (const auto& bone : rig.meshes[m].bones)
      if (bone_of[bone.node] >= 0)
        for (const auto& [v, wt] : bone.weights) w[v].emplace_back(bone_of[bone.node], wt);
    vx.insert(vx.end(), x.begin(), x.end());
    vw.insert(vw.end(), w.begin(), w.end());
  }
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
    }
  }
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

Rigid Skeleton::transform(std::size_t b, double t) const {
  const Bone& bone = bones_[b];
  const Rigid L = local(bone, t);
  if (bone.parent < 0 || !bone.frames.empty()) return L;
  return transform(static_cast<std::size_t>(bone.parent), t).after(L);
}

void Skeleton::skin(double t0, double t1, const double* X, const std::vector<char>& free, double* u, std::size_t owned) const {
  std::vector<Rigid> M(bones_.size());
  for (std::size_t b = 0; b < bones_.size(); ++b) M[b] = transform(b, t1).after(transform(b, t0).inverse());
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
