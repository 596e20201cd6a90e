// The simulated skin where artists work (issue 43): an animated glTF 2.0 binary (.glb) and a PC2 point
// cache, both rebuilt from Sinew's own record of the written skin frames.
//
//   DIR/skin.frames  every written skin frame, appended as it is computed (fixed-size records: step,
//                    load, time, positions, per-vertex fields), flushed to disk each time; a restart
//                    keeps the records up to its step and appends after them, and the two files below
//                    are made from it
//   DIR/skin.glb     the rest skin as a mesh with one morph target per frame (position and normal
//                    offsets from the rest), weights animated with STEP interpolation at the frames'
//                    times; per-vertex fields (J, the distance to the rig's own skinning) as accessors
//                    named in the mesh's extras; a rig's node hierarchy (names, animated TRS) beside it
//   DIR/skin.pc2     the frames' positions as a PC2 point cache (Blender's Mesh Cache modifier, Maya,
//                    3ds Max), applied to DIR/skin_rest.obj (the same vertices, in the same order)
//
// glTF is Y-up in metres: positions are written as the scene gives them (a DCC importer turns Y-up to
// its own convention); the PC2 keeps the scene's axes, like the OBJ files.
#pragma once

#include <sinew/discretization/rig_file.hpp>

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace sinew {

// One written frame of the skin.
struct SkinFrame {
  int step = 0;
  double load = 0.0, time = 0.0;          // time in seconds (the clip's, the run's, or step / frame rate)
  std::vector<float> x;                   // 3 per vertex
  std::vector<std::vector<float>> fields; // one value per vertex for each field of the track
};

// A rig's node hierarchy, animated with the frames (world transforms at a frame's load).
struct SkinRig {
  std::vector<std::string> names;
  std::vector<int> parents;  // parents before their children; -1 for a root
  std::function<std::vector<Affine>(double load)> pose;
};

// Everything the writers need.
struct SkinTrack {
  std::string name = "skin";
  std::vector<float> rest;                  // 3 per vertex
  std::vector<std::array<int, 3>> triangles;
  std::vector<std::string> field_names;
  std::vector<SkinFrame> frames;
  double frame_rate = 24.0;                 // PC2's frame numbers, the viewer's playback
  const SkinRig* rig = nullptr;             // optional
};

// An affine map as glTF's translation, rotation (unit quaternion x, y, z, w) and scale: each column's
// length is its scale, the rest made a rotation (a reflection turns the first scale negative). Exact for
// a rotation times scales along the node's own axes, which is what rigs hold.
void decompose_trs(const Affine& m, float t[3], float q[4], float s[3]);

// Area-weighted unit vertex normals of a triangle surface (3 per vertex).
std::vector<float> vertex_normals(const std::vector<float>& x, const std::vector<std::array<int, 3>>& triangles);

// Writes the track as a binary glTF 2.0 file, aside and then renamed into place. Throws
// std::runtime_error when the file cannot be written.
void write_glb(const std::string& path, const SkinTrack& track);

// Writes the frames' positions as a PC2 point cache (header: "POINTCACHE2\0", version 1, vertices,
// start frame, frames per sample, samples; then float32 x, y, z per vertex per sample), aside and then
// renamed. The start and the sampling are in frames at the track's frame rate (as Blender's, Maya's and
// 3ds Max's exporters write them), from the first two frames' times.
void write_pc2(const std::string& path, const SkinTrack& track);

// Sinew's append-only record of the written frames (DIR/skin.frames): a header (magic, version, vertex
// and field counts, field names) and one fixed-size record per frame.
class SkinFrameFile {
 public:
  // Opens `path` for a skin of `vertices` vertices with these fields. keep_up_to_step < 0: a new run,
  // the file is made anew. Otherwise (a restart) the frames of an existing file with the same vertices
  // and fields whose step is <= keep_up_to_step are read into `kept` and the rest cut off; a missing or
  // different file is made anew (`note` says why). Throws std::runtime_error on an I/O failure.
  SkinFrameFile(const std::string& path, std::size_t vertices, const std::vector<std::string>& fields, int keep_up_to_step,
                std::vector<SkinFrame>& kept, std::string& note);
  // Appends one frame and flushes it to disk.
  void append(const SkinFrame& f);

 private:
  void write_header();
  std::string path_;
  std::size_t vertices_ = 0;
  std::vector<std::string> fields_;
  std::uint64_t frames_ = 0;
};

// Reads a whole frame file (tests, tools). Throws std::runtime_error when it is not one.
std::vector<SkinFrame> read_skin_frames(const std::string& path, std::vector<std::string>* field_names = nullptr);

}  // namespace sinew
