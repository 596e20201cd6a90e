// Rigged characters read with Assimp, posed and skinned (rig_file.hpp). The only translation unit
// that includes Assimp's headers.
#include <sinew/core/errors.hpp>
#include <sinew/core/rigid.hpp>
#include <sinew/core/xml_input.hpp>
#include <sinew/discretization/rig_file.hpp>

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <map>
#include <sstream>

namespace sinew {

namespace {

[[noreturn]] void bad(const std::string& path, const std::string& why) { throw InputError(path + ": " + why, InputErrorKind::BadMesh); }

bool finite3(const std::array<double, 3>& v) { return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]); }

// Assimp's 4x4 matrices are row-major and act on column vectors; the last row is (0 0 0 1) for the
// affine transforms a rig holds.
Affine affine(const aiMatrix4x4& m) {
  Affine a;
  const double r[3][4] = {{m.a1, m.a2, m.a3, m.a4}, {m.b1, m.b2, m.b3, m.b4}, {m.c1, m.c2, m.c3, m.c4}};
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) a.A(i, j) = r[i][j];
    a.t[i] = r[i][3];
  }
  return a;
}

bool finite(const Affine& a) {
  for (int k = 0; k < 9; ++k)
    if (!std::isfinite(a.A[k])) return false;
  return finite3(a.t);
}

Mat3 rotation(const std::array<double, 4>& q) { return rotation_of_quaternion(q[0], q[1], q[2], q[3]); }  // w, x, y, z

// The keys around `t`: index k and fraction f with the value between keys k and k + 1 (held outside).
template <class Key>
std::pair<std::size_t, double> bracket(const std::vector<Key>& keys, double t) {
  if (keys.size() == 1 || t <= keys.front().first) return {0, 0.0};
  if (t >= keys.back().first) return {keys.size() - 1, 0.0};
  const auto it = std::upper_bound(keys.begin(), keys.end(), t, [](double v, const Key& k) { return v < k.first; });
  const std::size_t k = static_cast<std::size_t>(it - keys.begin()) - 1;
  const double span = keys[k + 1].first - keys[k].first;
  return {k, span > 0.0 ? (t - keys[k].first) / span : 0.0};
}

std::array<double, 3> lerp(const std::vector<std::pair<double, std::array<double, 3>>>& keys, double t) {
  const auto [k, f] = bracket(keys, t);
  if (f == 0.0) return keys[k].second;
  std::array<double, 3> v;
  for (int i = 0; i < 3; ++i) v[i] = (1 - f) * keys[k].second[i] + f * keys[k + 1].second[i];
  return v;
}

// Spherical linear interpolation along the shorter arc.
std::array<double, 4> slerp(const std::vector<std::pair<double, std::array<double, 4>>>& keys, double t) {
  const auto [k, f] = bracket(keys, t);
  std::array<double, 4> a = keys[k].second;
  auto unit = [](std::array<double, 4> q) {
    const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    for (auto& c : q) c /= n;
    return q;
  };
  a = unit(a);
  if (f == 0.0) return a;
  std::array<double, 4> b = unit(keys[k + 1].second);
  double c = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
  if (c < 0.0) {
    c = -c;
    for (auto& x : b) x = -x;
  }
  double wa = 1 - f, wb = f;
  if (c < 1.0 - 1e-12) {
    const double theta = std::acos(std::min(1.0, c)), s = std::sin(theta);
    wa = std::sin((1 - f) * theta) / s;
    wb = std::sin(f * theta) / s;
  }
  std::array<double, 4> q;
  for (int i = 0; i < 4; ++i) q[i] = wa * a[i] + wb * b[i];
  return unit(q);
}

}  // namespace

int RigFile::node_index(const std::string& name) const {
  for (std::size_t n = 0; n < nodes.size(); ++n)
    if (nodes[n].name == name) return static_cast<int>(n);
  return -1;
}

std::vector<Affine> RigFile::pose(const RigClip* clip, double seconds) const {
  std::vector<const RigChannel*> channel(nodes.size(), nullptr);
  if (clip)
    for (const auto& c : clip->channels) channel[c.node] = &c;
  std::vector<Affine> world(nodes.size());
  for (std::size_t n = 0; n < nodes.size(); ++n) {
    Affine local = nodes[n].rest;
    if (const RigChannel* c = channel[n]) {
      // Local = T R S from the keys (Assimp gives an animated node at least one key of each kind).
      const std::array<double, 3> s = c->scale.empty() ? std::array<double, 3>{1, 1, 1} : lerp(c->scale, seconds);
      const Mat3 R = c->rotation.empty() ? Mat3::identity() : rotation(slerp(c->rotation, seconds));
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) local.A(i, j) = R(i, j) * s[j];
      local.t = c->translation.empty() ? nodes[n].rest.t : lerp(c->translation, seconds);
    }
    world[n] = nodes[n].parent < 0 ? local : world[nodes[n].parent].after(local);
  }
  return world;
}

Affine RigFile::world(int node, const RigClip* clip, double seconds) const { return pose(clip, seconds).at(node); }

std::vector<std::array<double, 3>> RigFile::skin(int mesh, const RigClip* clip, double seconds) const {
  return skin(mesh, pose(clip, seconds));
}

std::vector<std::array<double, 3>> RigFile::skin(int mesh, const std::vector<Affine>& W) const {
  const RigMesh& m = meshes.at(mesh);
  std::vector<std::array<double, 3>> x(m.vertices.size(), {0.0, 0.0, 0.0});
  if (m.bones.empty()) {
    for (std::size_t v = 0; v < x.size(); ++v) x[v] = W[m.node].apply(m.vertices[v]);
    return x;
  }
  for (const auto& b : m.bones) {
    const Affine T = W[b.node].after(b.inverse_bind);
    for (const auto& [v, w] : b.weights) {
      const auto y = T.apply(m.vertices[v]);
      for (int i = 0; i < 3; ++i) x[v][i] += w * y[i];
    }
  }
  return x;
}

RigFile read_rig_file(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw InputError(path + ": cannot open the rig file (no such file)", InputErrorKind::File);
  Assimp::Importer importer;
  // Triangles only; the vertices as the artist made them (no welding: the simulated skin keeps the
  // input's topology, so that it can be loaded as a cache over the original).
  const aiScene* scene = importer.ReadFile(path, aiProcess_Triangulate);
  if (!scene || !scene->mRootNode) bad(path, std::string("Assimp cannot read it: ") + importer.GetErrorString());
  RigFile rig;
  rig.path = path;
  {
    std::string ext = std::filesystem::path(path).extension().string();
    for (auto& c : ext) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    rig.format = ext.empty() ? "?" : ext.substr(1);
  }
  // Nodes, parents first.
  std::map<const aiNode*, int> index;
  std::function<void(const aiNode*, int)> walk = [&](const aiNode* n, int parent) {
    RigNode node;
    node.name = n->mName.C_Str();
    node.parent = parent;
    node.rest = affine(n->mTransformation);
    if (!finite(node.rest)) bad(path, "node '" + node.name + "' has a non-finite transform");
    const int me = static_cast<int>(rig.nodes.size());
    index[n] = me;
    rig.nodes.push_back(node);
    for (unsigned c = 0; c < n->mNumChildren; ++c) walk(n->mChildren[c], me);
  };
  // Units: FBX files say how many centimetres a unit is (Blender's and Maya's exports: 1 or 100, so a
  // character may come in centimetres); Sinew's lengths, cell sizes and densities are in metres.
  double unit_cm = 0.0;
  if (scene->mMetaData) {
    float f = 0.0f;
    double d = 0.0;
    if (scene->mMetaData->Get("UnitScaleFactor", d))
      unit_cm = d;
    else if (scene->mMetaData->Get("UnitScaleFactor", f))
      unit_cm = f;
  }
  int root_parent = -1;
  if (std::isfinite(unit_cm) && unit_cm > 0.0 && std::fabs(unit_cm - 100.0) > 1e-9) {
    rig.metres_per_unit = unit_cm / 100.0;
    RigNode units;
    units.name = "$units";
    for (int i = 0; i < 3; ++i) units.rest.A(i, i) = rig.metres_per_unit;
    rig.nodes.push_back(units);
    root_parent = 0;
  }
  walk(scene->mRootNode, root_parent);
  std::map<unsigned, int> mesh_node;  // the node that places each mesh
  for (const auto& [n, i] : index)
    for (unsigned k = 0; k < n->mNumMeshes; ++k) mesh_node.emplace(n->mMeshes[k], i);
  // Meshes with their bones.
  for (unsigned mi = 0; mi < scene->mNumMeshes; ++mi) {
    const aiMesh* am = scene->mMeshes[mi];
    RigMesh m;
    m.name = am->mName.length ? am->mName.C_Str() : "mesh" + std::to_string(mi);
    m.node = mesh_node.count(mi) ? mesh_node[mi] : 0;
    for (unsigned v = 0; v < am->mNumVertices; ++v) {
      const std::array<double, 3> p{am->mVertices[v].x, am->mVertices[v].y, am->mVertices[v].z};
      if (!finite3(p)) bad(path, "mesh '" + m.name + "': vertex " + std::to_string(v) + " is not finite");
      m.vertices.push_back(p);
    }
    for (unsigned f = 0; f < am->mNumFaces; ++f)
      if (am->mFaces[f].mNumIndices == 3)  // points and lines are not skin
        m.triangles.push_back({static_cast<int>(am->mFaces[f].mIndices[0]), static_cast<int>(am->mFaces[f].mIndices[1]),
                               static_cast<int>(am->mFaces[f].mIndices[2])});
    std::vector<double> total(m.vertices.size(), 0.0);
    for (unsigned b = 0; b < am->mNumBones; ++b) {
      const aiBone* ab = am->mBones[b];
      RigMesh::Bone bone;
      bone.node = rig.node_index(ab->mName.C_Str());
      if (bone.node < 0) bad(path, "mesh '" + m.name + "': bone '" + std::string(ab->mName.C_Str()) + "' is no node of the hierarchy");
      rig.nodes[bone.node].joint = true;
      bone.inverse_bind = affine(ab->mOffsetMatrix);
      if (!finite(bone.inverse_bind)) bad(path, "mesh '" + m.name + "': bone '" + rig.nodes[bone.node].name + "' has a non-finite bind matrix");
      for (unsigned w = 0; w < ab->mNumWeights; ++w) {
        const int v = static_cast<int>(ab->mWeights[w].mVertexId);
        const double wt = ab->mWeights[w].mWeight;
        if (v < 0 || v >= static_cast<int>(m.vertices.size()) || !std::isfinite(wt) || wt < 0.0)
          bad(path, "mesh '" + m.name + "': bone '" + rig.nodes[bone.node].name + "' has a bad weight (vertex " + std::to_string(v) + ")");
        if (wt == 0.0) continue;
        bone.weights.emplace_back(v, wt);
        total[v] += wt;
      }
      m.bones.push_back(std::move(bone));
    }
    // Weights are normalized per vertex (exporters round them); a vertex of a skinned mesh that no
    // bone holds would collapse to the origin under skinning: an error naming it.
    if (!m.bones.empty()) {
      for (std::size_t v = 0; v < total.size(); ++v)
        if (!(total[v] > 0.0)) bad(path, "mesh '" + m.name + "': vertex " + std::to_string(v) + " has no bone weight");
      for (auto& b : m.bones)
        for (auto& [v, w] : b.weights) w /= total[v];
    }
    // Open edges, with coincident vertices welded (exporters split vertices along UV and normal seams).
    std::map<std::array<double, 3>, int> weld;
    std::vector<int> id(m.vertices.size());
    for (std::size_t v = 0; v < m.vertices.size(); ++v) id[v] = weld.emplace(m.vertices[v], static_cast<int>(weld.size())).first->second;
    std::map<std::pair<int, int>, int> edges;
    for (const auto& t : m.triangles)
      for (int a = 0; a < 3; ++a) {
        const int p = id[t[a]], q = id[t[(a + 1) % 3]];
        if (p != q) ++edges[{std::min(p, q), std::max(p, q)}];
      }
    for (const auto& [e, n] : edges) m.open_edges += n == 1;
    rig.meshes.push_back(std::move(m));
  }
  // Clips, times in seconds.
  for (unsigned ai = 0; ai < scene->mNumAnimations; ++ai) {
    const aiAnimation* an = scene->mAnimations[ai];
    RigClip clip;
    clip.name = an->mName.length ? an->mName.C_Str() : "clip" + std::to_string(ai);
    const double tps = an->mTicksPerSecond > 0.0 ? an->mTicksPerSecond : 25.0;  // Assimp's default when a file says none
    clip.duration = an->mDuration / tps;
    for (unsigned c = 0; c < an->mNumChannels; ++c) {
      const aiNodeAnim* na = an->mChannels[c];
      RigChannel ch;
      ch.node = rig.node_index(na->mNodeName.C_Str());
      if (ch.node < 0) bad(path, "clip '" + clip.name + "' animates '" + std::string(na->mNodeName.C_Str()) + "', which is no node");
      const std::string where = "clip '" + clip.name + "', node '" + rig.nodes[ch.node].name + "': ";
      auto time = [&](double ticks, const char* kind, unsigned k, double previous) {
        const double t = ticks / tps;
        if (!std::isfinite(t)) bad(path, where + kind + " key " + std::to_string(k) + " has a non-finite time");
        if (k > 0 && t < previous) bad(path, where + kind + " keys are not in time order (key " + std::to_string(k) + ")");
        return t;
      };
      for (unsigned k = 0; k < na->mNumPositionKeys; ++k) {
        const auto& key = na->mPositionKeys[k];
        const std::array<double, 3> v{key.mValue.x, key.mValue.y, key.mValue.z};
        if (!finite3(v)) bad(path, where + "translation key " + std::to_string(k) + " is not finite");
        ch.translation.emplace_back(time(key.mTime, "translation", k, k ? ch.translation.back().first : 0.0), v);
      }
      for (unsigned k = 0; k < na->mNumRotationKeys; ++k) {
        const auto& key = na->mRotationKeys[k];
        const std::array<double, 4> q{key.mValue.w, key.mValue.x, key.mValue.y, key.mValue.z};
        const double n = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3];
        if (!std::isfinite(n) || n < 1e-12) bad(path, where + "rotation key " + std::to_string(k) + " is not a rotation");
        ch.rotation.emplace_back(time(key.mTime, "rotation", k, k ? ch.rotation.back().first : 0.0), q);
      }
      for (unsigned k = 0; k < na->mNumScalingKeys; ++k) {
        const auto& key = na->mScalingKeys[k];
        const std::array<double, 3> v{key.mValue.x, key.mValue.y, key.mValue.z};
        if (!finite3(v)) bad(path, where + "scale key " + std::to_string(k) + " is not finite");
        ch.scale.emplace_back(time(key.mTime, "scale", k, k ? ch.scale.back().first : 0.0), v);
      }
      clip.channels.push_back(std::move(ch));
    }
    rig.clips.push_back(std::move(clip));
  }
  return rig;
}

const RigClip* RigFile::clip(const std::string& name) const {
  for (const auto& c : clips)
    if (name.empty() || c.name == name) return &c;
  return nullptr;
}

namespace {

std::vector<int> chosen_meshes(const RigFile& rig, const std::string& meshes) {
  std::vector<int> chosen;
  std::stringstream list(meshes);
  for (std::string name; std::getline(list, name, ',');) {
    name.erase(0, name.find_first_not_of(" \t"));
    name.erase(name.find_last_not_of(" \t") + 1);
    if (name.empty()) continue;
    int found = -1;
    for (std::size_t m = 0; m < rig.meshes.size(); ++m)
      if (rig.meshes[m].name == name) found = static_cast<int>(m);
    if (found < 0) {
      std::string names;
      for (const auto& m : rig.meshes) names += (names.empty() ? "'" : ", '") + m.name + "'";
      bad(rig.path, "no mesh '" + name + "' (the file has " + names + ")");
    }
    chosen.push_back(found);
  }
  if (chosen.empty())
    for (std::size_t m = 0; m < rig.meshes.size(); ++m) chosen.push_back(static_cast<int>(m));
  return chosen;
}

}  // namespace

TriangleSurface rig_surface(const RigFile& rig, const std::string& meshes, const std::vector<Affine>& world) {
  TriangleSurface s;
  s.path = rig.path;
  for (int m : chosen_meshes(rig, meshes)) {
    const int base = static_cast<int>(s.vertices.size());
    const auto x = rig.skin(m, world);
    s.vertices.insert(s.vertices.end(), x.begin(), x.end());
    for (const auto& t : rig.meshes[m].triangles) s.triangles.push_back({base + t[0], base + t[1], base + t[2]});
  }
  if (s.triangles.empty()) bad(rig.path, "the chosen meshes have no triangles");
  s.set_bounds();
  return s;
}

void check_rest_time(const RigClip& clip, double seconds, const std::string& path) {
  if (seconds <= clip.duration + 1e-9) return;
  char buf[64];
  std::snprintf(buf, sizeof buf, "%g s lies past the end of", seconds);
  char end[48];
  std::snprintf(end, sizeof end, " (%g s)", clip.duration);
  throw InputError(std::string("Skeleton: 'Rest time' ") + buf + " the clip '" + clip.name + "' of " + path + end +
                   "; give a time within the clip (or none: the bind pose)");
}

TriangleSurface rig_surface(const RigFile& rig, const std::string& meshes, const RigClip* clip, double seconds) {
  TriangleSurface s = rig_surface(rig, meshes, rig.pose(clip, seconds));
  // Turned outward as a whole when the soup's signed volume is negative.
  double volume = 0.0;
  for (const auto& T : s.triangles) {
    const auto &a = s.vertices[T[0]], &b = s.vertices[T[1]], &c = s.vertices[T[2]];
    volume += a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0]);
  }
  if (volume < 0.0)
    for (auto& T : s.triangles) std::swap(T[1], T[2]);
  return s;
}

std::vector<std::pair<std::string, std::string>> Retarget::parse_map(const std::string& text) {
  std::vector<std::pair<std::string, std::string>> map;
  auto trim = [](std::string v) {
    v.erase(0, v.find_first_not_of(" \t\n"));
    v.erase(v.find_last_not_of(" \t\n") + 1);
    return v;
  };
  for (const std::string& pair : comma_list(text)) {
    const auto colon = pair.find(':');
    const std::string from = trim(pair.substr(0, colon)), to = colon == std::string::npos ? "" : trim(pair.substr(colon + 1));
    if (colon == std::string::npos || from.empty() || to.empty() || to.find(':') != std::string::npos)
      throw InputError("'Joint map': '" + pair + "' is not 'source joint:rig joint'");
    map.emplace_back(from, to);
  }
  return map;
}

Retarget::Retarget(const RigFile& rig, const std::vector<Affine>& rig_reference, const RigFile& source, const RigClip& clip,
                   double source_reference, const std::vector<std::pair<std::string, std::string>>& map, double scale)
    : rig_(rig), source_(source), clip_(clip), reference_(rig_reference) {
  if (map.empty()) throw InputError("'Joint map' maps no joint");
  auto listing = [](const RigFile& f) {
    std::string names;
    int shown = 0;
    for (const auto& n : f.nodes) {
      if (shown == 12) {
        names += ", ...";
        break;
      }
      names += (names.empty() ? "'" : ", '") + n.name + "'";
      ++shown;
    }
    return names;
  };
  from_.assign(rig.nodes.size(), -1);
  for (const auto& [src, dst] : map) {
    const int s = source.node_index(src), d = rig.node_index(dst);
    if (s < 0) throw InputError("'Joint map': " + source.path + " has no joint '" + src + "' (it has " + listing(source) + ")");
    if (d < 0) throw InputError("'Joint map': " + rig.path + " has no joint '" + dst + "' (it has " + listing(rig) + ")");
    if (from_[d] >= 0) throw InputError("'Joint map': the rig's joint '" + dst + "' is mapped twice");
    from_[d] = s;
  }
  local_.resize(rig.nodes.size());
  top_.assign(rig.nodes.size(), 0);
  std::vector<char> mapped_above(rig.nodes.size(), 0);
  for (std::size_t n = 0; n < rig.nodes.size(); ++n) {
    const int parent = rig.nodes[n].parent;
    local_[n] = parent < 0 ? reference_[n] : reference_[parent].inverse().after(reference_[n]);
    const char above = parent >= 0 && (mapped_above[parent] || from_[parent] >= 0);
    mapped_above[n] = above;
    top_[n] = from_[n] >= 0 && !above;
  }
  source_reference_ = source.pose(&clip, source_reference);
  if (scale > 0.0) {
    scale_ = scale;
    return;
  }
  // The ratio of heights: the largest extent of the mapped joints' reference positions in each.
  double lo[2][3], hi[2][3];
  for (auto* b : {lo[0], lo[1]}) std::fill(b, b + 3, HUGE_VAL);
  for (auto* b : {hi[0], hi[1]}) std::fill(b, b + 3, -HUGE_VAL);
  for (std::size_t n = 0; n < rig.nodes.size(); ++n) {
    if (from_[n] < 0) continue;
    for (int i = 0; i < 3; ++i) {
      lo[0][i] = std::min(lo[0][i], reference_[n].t[i]);
      hi[0][i] = std::max(hi[0][i], reference_[n].t[i]);
      lo[1][i] = std::min(lo[1][i], source_reference_[from_[n]].t[i]);
      hi[1][i] = std::max(hi[1][i], source_reference_[from_[n]].t[i]);
    }
  }
  double extent[2] = {0.0, 0.0};
  for (int k = 0; k < 2; ++k)
    for (int i = 0; i < 3; ++i) extent[k] = std::max(extent[k], hi[k][i] - lo[k][i]);
  scale_ = extent[1] > 0.0 && extent[0] > 0.0 ? extent[0] / extent[1] : 1.0;
}

std::vector<Affine> Retarget::pose(double seconds) const {
  const std::vector<Affine> S = source_.pose(&clip_, seconds);
  std::vector<Affine> W(rig_.nodes.size());
  for (std::size_t n = 0; n < rig_.nodes.size(); ++n) {
    const int parent = rig_.nodes[n].parent;
    W[n] = parent < 0 ? local_[n] : W[parent].after(local_[n]);
    const int s = from_[n];
    if (s < 0) continue;
    const Mat3 turn = nearest_rotation(S[s].A) * transpose(nearest_rotation(source_reference_[s].A));
    W[n].A = turn * reference_[n].A;
    if (top_[n])
      for (int i = 0; i < 3; ++i) W[n].t[i] = reference_[n].t[i] + scale_ * (S[s].t[i] - source_reference_[s].t[i]);
  }
  return W;
}

std::string describe(const RigFile& rig) {
  std::ostringstream os;
  long long joints = 0;
  for (const auto& n : rig.nodes) joints += n.joint;
  os << rig.path << " (" << rig.format << "): " << rig.meshes.size() << " mesh" << (rig.meshes.size() == 1 ? "" : "es") << ", "
     << rig.nodes.size() << " nodes (" << joints << " joints that move skin), " << rig.clips.size() << " clip"
     << (rig.clips.size() == 1 ? "" : "s") << "\n";
  os << "meshes:\n";
  for (const auto& m : rig.meshes) {
    os << "  '" << m.name << "': " << m.vertices.size() << " vertices, " << m.triangles.size() << " triangles, ";
    if (m.open_edges == 0)
      os << "closed";
    else
      os << "open (" << m.open_edges << " open edges)";
    os << ", " << m.bones.size() << " bones, placed by node '" << rig.nodes[m.node].name << "'\n";
  }
  // The skin's box in the bind pose: what a 'Cell size' is chosen against.
  if (!rig.meshes.empty()) {
    const TriangleSurface skin = rig_surface(rig, "");
    os << "  skin in the bind pose: a box of " << skin.upper[0] - skin.lower[0] << " x " << skin.upper[1] - skin.lower[1] << " x "
       << skin.upper[2] - skin.lower[2] << " (from " << skin.lower[0] << ", " << skin.lower[1] << ", " << skin.lower[2] << ")\n";
  }
  if (rig.metres_per_unit != 1.0) os << "  units: " << rig.metres_per_unit << " m each (the file's UnitScaleFactor), scaled to metres\n";
  os << "nodes (* joint):\n";
  std::vector<int> depth(rig.nodes.size(), 0);
  for (std::size_t n = 0; n < rig.nodes.size(); ++n) {
    if (rig.nodes[n].parent >= 0) depth[n] = depth[rig.nodes[n].parent] + 1;
    os << "  " << std::string(2 * depth[n], ' ') << (rig.nodes[n].joint ? "* " : "  ") << rig.nodes[n].name << "\n";
  }
  os << "clips:\n";
  for (const auto& c : rig.clips) {
    long long keys = 0;
    for (const auto& ch : c.channels) keys += ch.translation.size() + ch.rotation.size() + ch.scale.size();
    os << "  '" << c.name << "': " << c.duration << " s, " << c.channels.size() << " animated nodes, " << keys << " keys\n";
  }
  return os.str();
}

}  // namespace sinew
