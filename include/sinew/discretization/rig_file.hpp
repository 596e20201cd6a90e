// Rigged characters as artists deliver them (issue 22; the paper's Sec. 6: "the bones are transformed
// by the skinning of a production rig, which often results in nonrigid transforms"), read with Assimp
// (Debian's libassimp-dev, BSD-3, linked, never copied): glTF 2.0, FBX, COLLADA, DirectX .x, BVH.
//
//   read_rig_file   the skin meshes (triangles, per-vertex joint weights), the node hierarchy with
//                   its rest (bind) transforms, which nodes are joints, and the animation clips
//   RigFile::world  a node's world transform at a clip's time: each animated node's local transform
//                   from its keys (translation and scale linearly, rotation by quaternion slerp,
//                   held before the first key and after the last), composed from the root down
//   RigFile::skin   a mesh's vertices by linear-blend skinning at a clip's time, x = sum_j w_j W_j B_j v
//                   (W_j the joint's world transform, B_j its inverse bind matrix); at the bind pose
//                   it gives back the vertices as stored (the node holding a skinned mesh does not
//                   move it, as glTF specifies and Assimp's importers follow); a mesh without bones
//                   moves with its node
//
// Transforms are affine (a production rig may scale and shear), not rigid. Only this reader's
// translation unit includes Assimp's headers.
#pragma once

#include <sinew/core/small_matrix.hpp>
#include <sinew/discretization/triangle_surface.hpp>

#include <array>
#include <string>
#include <vector>

namespace sinew {

// y = A x + t
struct Affine {
  Mat3 A = Mat3::identity();
  std::array<double, 3> t{{0.0, 0.0, 0.0}};

  std::array<double, 3> apply(const std::array<double, 3>& x) const {
    std::array<double, 3> y;
    for (int i = 0; i < 3; ++i) y[i] = A(i, 0) * x[0] + A(i, 1) * x[1] + A(i, 2) * x[2] + t[i];
    return y;
  }
  // x = A^-1 (y - t), with A^-1 = cofactor(A)^T / det A
  Affine inverse() const {
    Affine b;
    b.A = (1.0 / det(A)) * transpose(cofactor(A));
    const auto minus_t = b.apply(t);
    for (int i = 0; i < 3; ++i) b.t[i] = -minus_t[i];
    return b;
  }
  // (this o b)(x) = this(b(x))
  Affine after(const Affine& b) const {
    Affine c;
    c.A = A * b.A;
    c.t = apply(b.t);
    return c;
  }
};

struct RigNode {
  std::string name;
  int parent = -1;      // index in RigFile::nodes, -1 for the root
  Affine rest;          // local transform relative to the parent, as the file stores it
  bool joint = false;   // a mesh's bone names it (it moves skin)
};

struct RigMesh {
  std::string name;
  std::vector<std::array<double, 3>> vertices;  // in the mesh's own frame, as stored
  std::vector<std::array<int, 3>> triangles;
  int node = -1;  // the node that places it in the scene (its world transform at rest)
  // Skinning: per bone, the joint node, the inverse bind matrix, and (vertex, weight) pairs.
  struct Bone {
    int node = -1;
    Affine inverse_bind;
    std::vector<std::pair<int, double>> weights;
  };
  std::vector<Bone> bones;
  long long open_edges = 0;  // edges on one triangle only (0: closed), after welding coincident vertices
};

// Keys of one animated node; times in seconds.
struct RigChannel {
  int node = -1;
  std::vector<std::pair<double, std::array<double, 3>>> translation, scale;
  std::vector<std::pair<double, std::array<double, 4>>> rotation;  // quaternion w, x, y, z
};

struct RigClip {
  std::string name;
  double duration = 0.0;  // seconds
  std::vector<RigChannel> channels;
};

struct RigFile {
  std::string path, format;
  // Metres per unit of the file (an FBX file's UnitScaleFactor / 100; 1 for formats that say none).
  // When not 1, a node '$units' above the file's root scales everything the file holds to metres.
  double metres_per_unit = 1.0;
  std::vector<RigNode> nodes;  // parents before their children
  std::vector<RigMesh> meshes;
  std::vector<RigClip> clips;

  int node_index(const std::string& name) const;  // -1 when absent
  const RigClip* clip(const std::string& name) const;  // by name (empty: the first); nullptr when absent
  // World transform of a node at `seconds` into `clip` (nullptr: the rest pose).
  Affine world(int node, const RigClip* clip, double seconds) const;
  // World transforms of every node at once (cheaper than calling world() per node).
  std::vector<Affine> pose(const RigClip* clip, double seconds) const;
  // A mesh's vertices skinned at the pose (a mesh without bones moves with its node).
  std::vector<std::array<double, 3>> skin(int mesh, const RigClip* clip, double seconds) const;
  // The same from the world transforms of every node (pose()'s, or a retargeted motion's).
  std::vector<std::array<double, 3>> skin(int mesh, const std::vector<Affine>& world) const;
};

// Throws InputError (kind File for a file that cannot be opened, BadMesh for one Assimp cannot read or
// whose contents are broken: non-finite vertices, transforms or keys, keys out of time order, a bone
// that is no node, a vertex of a skinned mesh that no bone holds), naming the file and the culprit.
// Weights are normalized per vertex (exporters round them).
RigFile read_rig_file(const std::string& path);

// The skin as one triangle soup: the named meshes (comma-separated; empty: all), each skinned at the
// pose of `clip` at `seconds` (nullptr: the bind pose); turned outward as a whole when its signed
// volume is negative. Throws InputError naming a mesh the file does not have (and those it has).
TriangleSurface rig_surface(const RigFile& rig, const std::string& meshes, const RigClip* clip = nullptr, double seconds = 0.0);
// A rest pose at `seconds` of `clip` (of the file at `path`) must lie within the clip: throws InputError
// ("Skeleton: 'Rest time' ... lies past the end of ...") otherwise.
void check_rest_time(const RigClip& clip, double seconds, const std::string& path);
// The same skinned by given world transforms of every node (pose()'s, or a retargeted motion's), its
// triangles as the file stores them (not turned).
TriangleSurface rig_surface(const RigFile& rig, const std::string& meshes, const std::vector<Affine>& world);

// A clip of another skeleton (a BVH motion capture, another character) carried onto this rig's
// joints through a joint-name map, in world space and relative to a reference pose of each: a mapped
// joint turns in the world as its source joint turns from the source's reference (its clip at
// `source_reference` seconds),
//     R(t) = polar(S(t)) polar(S_ref)^T R_ref                 (S: the source joint's world matrix)
// so that at the reference time the rig stands in its own reference pose (its rest), whatever the
// source's pose; unmapped joints keep their reference pose relative to their parent; every joint's
// position follows from the rig's own bone lengths, except the topmost mapped joints, which move as
// their source joints move from the reference, times `scale` (<= 0: the ratio of the mapped joints'
// heights, the largest extent of their reference positions, in the rig and in the source).
class Retarget {
 public:
  // map: (source joint, rig joint) pairs. Throws InputError naming an unknown joint (and listing the
  // file's), a rig joint mapped twice, or an empty map.
  Retarget(const RigFile& rig, const std::vector<Affine>& rig_reference, const RigFile& source, const RigClip& clip,
           double source_reference, const std::vector<std::pair<std::string, std::string>>& map, double scale);
  // World transforms of every node of the rig at `seconds` of the source's clip.
  std::vector<Affine> pose(double seconds) const;
  double scale() const { return scale_; }

  // "src:dst, src:dst, ..." (spaces around names ignored). Throws InputError on a malformed pair.
  static std::vector<std::pair<std::string, std::string>> parse_map(const std::string& text);

 private:
  const RigFile& rig_;
  const RigFile& source_;
  const RigClip& clip_;
  std::vector<Affine> reference_, local_;  // the rig's reference world transforms, and local ones
  std::vector<Affine> source_reference_;   // the source's world transforms at its reference time
  std::vector<int> from_;                  // per rig node: its source node, or -1
  std::vector<char> top_;                  // per rig node: mapped, with no mapped ancestor
  double scale_ = 1.0;
};

// A listing of the file for a user choosing meshes, joints and clips (sinew-rig).
std::string describe(const RigFile& rig);

}  // namespace sinew
