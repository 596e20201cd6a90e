// glTF 2.0 binary, PC2 and Sinew's frame record of the simulated skin (skin_cache.hpp).
#include <sinew/io/skin_cache.hpp>

#include "durable_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace sinew {

namespace {

// JSON string with the escapes JSON needs.
std::string quoted(const std::string& s) {
  std::string out = "\"";
  for (const unsigned char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += static_cast<char>(c);
    } else if (c < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", c);
      out += buf;
    } else {
      out += static_cast<char>(c);
    }
  }
  return out + "\"";
}

// A number as JSON takes it (no NaN or infinity: those become 0, which only min/max could meet).
std::string num(double x) {
  if (!std::isfinite(x)) return "0";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", x);
  return buf;
}

// The binary chunk and the accessors into it, one buffer view per accessor.
class GlbBuilder {
 public:
  // Adds float data as an accessor of `type` ("SCALAR", "VEC3", "VEC4"); with_bounds writes min/max
  // (required for POSITION and animation inputs). target: 34962 for vertex attributes, 0 for none.
  int add_floats(const std::vector<float>& data, const char* type, int components, bool with_bounds, int target) {
    const std::size_t count = data.size() / components;
    std::ostringstream a;
    a << "{\"bufferView\":" << add_view(data.data(), data.size() * sizeof(float), target) << ",\"componentType\":5126,\"count\":"
      << count << ",\"type\":\"" << type << "\"";
    if (with_bounds) {
      std::vector<double> lo(components, HUGE_VAL), hi(components, -HUGE_VAL);
      for (std::size_t k = 0; k < count; ++k)
        for (int c = 0; c < components; ++c) {
          const double v = data[k * components + c];
          if (!std::isfinite(v)) continue;
          lo[c] = std::min(lo[c], v);
          hi[c] = std::max(hi[c], v);
        }
      a << ",\"min\":[";
      for (int c = 0; c < components; ++c) a << (c ? "," : "") << num(count ? lo[c] : 0.0);
      a << "],\"max\":[";
      for (int c = 0; c < components; ++c) a << (c ? "," : "") << num(count ? hi[c] : 0.0);
      a << "]";
    }
    a << "}";
    accessors_.push_back(a.str());
    return static_cast<int>(accessors_.size()) - 1;
  }
  int add_indices(const std::vector<std::uint32_t>& data) {
    std::ostringstream a;
    a << "{\"bufferView\":" << add_view(data.data(), data.size() * sizeof(std::uint32_t), 34963)
      << ",\"componentType\":5125,\"count\":" << data.size() << ",\"type\":\"SCALAR\"}";
    accessors_.push_back(a.str());
    return static_cast<int>(accessors_.size()) - 1;
  }
  std::string accessors_json() const { return join(accessors_); }
  std::string views_json() const { return join(views_); }
  const std::vector<char>& bin() const { return bin_; }

  static std::string join(const std::vector<std::string>& items) {
    std::string s = "[";
    for (std::size_t k = 0; k < items.size(); ++k) s += (k ? "," : "") + items[k];
    return s + "]";
  }

 private:
  int add_view(const void* data, std::size_t bytes, int target) {
    const std::size_t offset = bin_.size();
    bin_.insert(bin_.end(), static_cast<const char*>(data), static_cast<const char*>(data) + bytes);
    while (bin_.size() % 4) bin_.push_back(0);
    std::ostringstream v;
    v << "{\"buffer\":0,\"byteOffset\":" << offset << ",\"byteLength\":" << bytes;
    if (target) v << ",\"target\":" << target;
    v << "}";
    views_.push_back(v.str());
    return static_cast<int>(views_.size()) - 1;
  }
  std::vector<char> bin_;
  std::vector<std::string> views_, accessors_;
};

// Writes bytes aside and renames them into place.
void write_file_durably(const std::string& path, const std::vector<const std::vector<char>*>& parts) {
  io_detail::write_durably(path, "wb", [&](std::FILE* f) {
    bool ok = true;
    for (const auto* p : parts) ok = ok && std::fwrite(p->data(), 1, p->size(), f) == p->size();
    return ok;
  });
}

template <class T>
void put(std::vector<char>& out, const T& v) {
  const char* p = reinterpret_cast<const char*>(&v);
  out.insert(out.end(), p, p + sizeof(T));
}

constexpr char kFrameMagic[8] = {'S', 'I', 'N', 'E', 'W', 'S', 'K', 'N'};
constexpr std::uint32_t kFrameVersion = 1;
constexpr std::size_t kFieldNameBytes = 32;

std::size_t header_bytes(std::size_t fields) { return 8 + 3 * 4 + fields * kFieldNameBytes; }
std::size_t record_bytes(std::size_t vertices, std::size_t fields) { return 8 + 8 + 8 + 4 * (3 + fields) * vertices; }

struct FrameFileHeader {
  std::uint32_t version = 0, vertices = 0;
  std::vector<std::string> fields;
};

// Reads a frame file's header; false when the file is not one.
bool read_header(std::FILE* f, FrameFileHeader& h) {
  char magic[8];
  std::uint32_t v[3];
  if (std::fread(magic, 1, 8, f) != 8 || std::memcmp(magic, kFrameMagic, 8) != 0) return false;
  if (std::fread(v, 4, 3, f) != 3 || v[0] != kFrameVersion || v[2] > 64) return false;
  h.version = v[0];
  h.vertices = v[1];
  h.fields.clear();
  for (std::uint32_t k = 0; k < v[2]; ++k) {
    char name[kFieldNameBytes + 1] = {};
    if (std::fread(name, 1, kFieldNameBytes, f) != kFieldNameBytes) return false;
    h.fields.emplace_back(name);
  }
  return true;
}

bool read_record(std::FILE* f, std::size_t vertices, std::size_t fields, SkinFrame& r) {
  std::int64_t step = 0;
  if (std::fread(&step, 8, 1, f) != 1 || std::fread(&r.load, 8, 1, f) != 1 || std::fread(&r.time, 8, 1, f) != 1) return false;
  r.step = static_cast<int>(step);
  r.x.resize(3 * vertices);
  if (std::fread(r.x.data(), 4, r.x.size(), f) != r.x.size()) return false;
  r.fields.assign(fields, std::vector<float>(vertices));
  for (auto& v : r.fields)
    if (std::fread(v.data(), 4, v.size(), f) != v.size()) return false;
  return true;
}

}  // namespace

void decompose_trs(const Affine& m, float t[3], float q[4], float s[3]) {
  Mat3 R = m.A;
  for (int j = 0; j < 3; ++j) {
    double len = std::sqrt(R(0, j) * R(0, j) + R(1, j) * R(1, j) + R(2, j) * R(2, j));
    if (len <= 0.0) len = 1.0;
    s[j] = static_cast<float>(len);
    for (int i = 0; i < 3; ++i) R(i, j) /= len;
  }
  if (det(R) < 0.0) {
    s[0] = -s[0];
    for (int i = 0; i < 3; ++i) R(i, 0) = -R(i, 0);
  }
  for (int i = 0; i < 3; ++i) t[i] = static_cast<float>(m.t[i]);
  // Shepperd's method: the largest of the four squared components first, for accuracy.
  const double tr = R(0, 0) + R(1, 1) + R(2, 2);
  double w, x, y, z;
  if (tr > 0.0) {
    const double r = std::sqrt(1.0 + tr) * 2.0;
    w = 0.25 * r;
    x = (R(2, 1) - R(1, 2)) / r;
    y = (R(0, 2) - R(2, 0)) / r;
    z = (R(1, 0) - R(0, 1)) / r;
  } else if (R(0, 0) > R(1, 1) && R(0, 0) > R(2, 2)) {
    const double r = std::sqrt(1.0 + R(0, 0) - R(1, 1) - R(2, 2)) * 2.0;
    w = (R(2, 1) - R(1, 2)) / r;
    x = 0.25 * r;
    y = (R(0, 1) + R(1, 0)) / r;
    z = (R(0, 2) + R(2, 0)) / r;
  } else if (R(1, 1) > R(2, 2)) {
    const double r = std::sqrt(1.0 + R(1, 1) - R(0, 0) - R(2, 2)) * 2.0;
    w = (R(0, 2) - R(2, 0)) / r;
    x = (R(0, 1) + R(1, 0)) / r;
    y = 0.25 * r;
    z = (R(1, 2) + R(2, 1)) / r;
  } else {
    const double r = std::sqrt(1.0 + R(2, 2) - R(0, 0) - R(1, 1)) * 2.0;
    w = (R(1, 0) - R(0, 1)) / r;
    x = (R(0, 2) + R(2, 0)) / r;
    y = (R(1, 2) + R(2, 1)) / r;
    z = 0.25 * r;
  }
  const double n = std::sqrt(w * w + x * x + y * y + z * z);
  q[0] = static_cast<float>(x / n);
  q[1] = static_cast<float>(y / n);
  q[2] = static_cast<float>(z / n);
  q[3] = static_cast<float>(w / n);
}

std::vector<float> vertex_normals(const std::vector<float>& x, const std::vector<std::array<int, 3>>& triangles) {
  std::vector<double> n(x.size(), 0.0);
  for (const auto& t : triangles) {
    const float* p0 = &x[3 * t[0]];
    const float* p1 = &x[3 * t[1]];
    const float* p2 = &x[3 * t[2]];
    const double a[3] = {double(p1[0]) - p0[0], double(p1[1]) - p0[1], double(p1[2]) - p0[2]};
    const double b[3] = {double(p2[0]) - p0[0], double(p2[1]) - p0[1], double(p2[2]) - p0[2]};
    const double c[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
    for (int v : t)
      for (int d = 0; d < 3; ++d) n[3 * v + d] += c[d];
  }
  std::vector<float> out(x.size(), 0.0f);
  for (std::size_t v = 0; v < x.size() / 3; ++v) {
    const double len = std::sqrt(n[3 * v] * n[3 * v] + n[3 * v + 1] * n[3 * v + 1] + n[3 * v + 2] * n[3 * v + 2]);
    // A vertex on no triangle (or on degenerate ones only) gets an up vector: glTF wants unit normals.
    for (int d = 0; d < 3; ++d) out[3 * v + d] = len > 0.0 ? static_cast<float>(n[3 * v + d] / len) : (d == 1 ? 1.0f : 0.0f);
  }
  return out;
}

void write_glb(const std::string& path, const SkinTrack& track) {
  const std::size_t V = track.rest.size() / 3, F = track.frames.size();
  GlbBuilder b;
  const std::vector<float> rest_normals = vertex_normals(track.rest, track.triangles);
  const int position = b.add_floats(track.rest, "VEC3", 3, true, 34962);
  const int normal = b.add_floats(rest_normals, "VEC3", 3, false, 34962);
  std::vector<std::uint32_t> index;
  index.reserve(3 * track.triangles.size());
  for (const auto& t : track.triangles)
    for (int v : t) index.push_back(static_cast<std::uint32_t>(v));
  const int indices = b.add_indices(index);

  // One morph target per frame: offsets of the positions and normals from the rest.
  std::ostringstream targets, names, steps;
  std::vector<float> dx(3 * V), dn(3 * V);
  for (std::size_t f = 0; f < F; ++f) {
    const SkinFrame& fr = track.frames[f];
    const std::vector<float> n = vertex_normals(fr.x, track.triangles);
    for (std::size_t k = 0; k < 3 * V; ++k) {
      dx[k] = fr.x[k] - track.rest[k];
      dn[k] = n[k] - rest_normals[k];
    }
    const int p = b.add_floats(dx, "VEC3", 3, true, 34962), q = b.add_floats(dn, "VEC3", 3, false, 34962);
    targets << (f ? "," : "") << "{\"POSITION\":" << p << ",\"NORMAL\":" << q << "}";
    char name[32];
    std::snprintf(name, sizeof name, "step_%06d", fr.step);
    names << (f ? "," : "") << quoted(name);
    steps << (f ? "," : "") << fr.step;
  }
  // Per-vertex fields, one accessor per field holding every frame (frame-major): for viewers that
  // colour the skin; importers keep them as custom properties.
  std::ostringstream fields;
  for (std::size_t k = 0; k < track.field_names.size(); ++k) {
    std::vector<float> all;
    all.reserve(F * V);
    for (const auto& fr : track.frames) all.insert(all.end(), fr.fields[k].begin(), fr.fields[k].end());
    fields << (k ? "," : "") << quoted(track.field_names[k]) << ":" << b.add_floats(all, "SCALAR", 1, true, 0);
  }

  // The animation: frame f's weights are 1 for target f and 0 elsewhere, held until the next frame.
  std::vector<std::string> samplers, channels;
  std::vector<float> times(F), weights(F * F, 0.0f);
  for (std::size_t f = 0; f < F; ++f) {
    times[f] = static_cast<float>(track.frames[f].time);
    weights[f * F + f] = 1.0f;
  }
  int time_accessor = -1;
  if (F > 0) {
    time_accessor = b.add_floats(times, "SCALAR", 1, true, 0);
    const int w = b.add_floats(weights, "SCALAR", 1, false, 0);
    samplers.push_back("{\"input\":" + std::to_string(time_accessor) + ",\"output\":" + std::to_string(w) +
                       ",\"interpolation\":\"STEP\"}");
    channels.push_back("{\"sampler\":0,\"target\":{\"node\":0,\"path\":\"weights\"}}");
  }

  // The rig's nodes after the skin's node, with their local transforms at each frame.
  std::vector<std::string> nodes;
  nodes.push_back("{\"name\":" + quoted(track.name) + ",\"mesh\":0}");
  std::vector<int> roots{0};
  if (track.rig && F > 0) {
    const SkinRig& rig = *track.rig;
    const std::size_t N = rig.names.size();
    std::vector<std::vector<float>> T(N), R(N), S(N);
    for (std::size_t f = 0; f < F; ++f) {
      const std::vector<Affine> world = rig.pose(track.frames[f].load);
      if (world.size() != N) throw std::logic_error("write_glb: the rig's pose has another number of nodes");
      for (std::size_t j = 0; j < N; ++j) {
        const Affine local = rig.parents[j] < 0 ? world[j] : world[rig.parents[j]].inverse().after(world[j]);
        float t[3], q[4], s[3];
        decompose_trs(local, t, q, s);
        T[j].insert(T[j].end(), t, t + 3);
        R[j].insert(R[j].end(), q, q + 4);
        S[j].insert(S[j].end(), s, s + 3);
      }
    }
    std::vector<std::vector<int>> children(N);
    for (std::size_t j = 0; j < N; ++j)
      if (rig.parents[j] >= 0) children[rig.parents[j]].push_back(static_cast<int>(j));
    for (std::size_t j = 0; j < N; ++j) {
      std::ostringstream n;
      n << "{\"name\":" << quoted(rig.names[j]) << ",\"translation\":[" << num(T[j][0]) << "," << num(T[j][1]) << ","
        << num(T[j][2]) << "],\"rotation\":[" << num(R[j][0]) << "," << num(R[j][1]) << "," << num(R[j][2]) << ","
        << num(R[j][3]) << "],\"scale\":[" << num(S[j][0]) << "," << num(S[j][1]) << "," << num(S[j][2]) << "]";
      if (!children[j].empty()) {
        n << ",\"children\":[";
        for (std::size_t c = 0; c < children[j].size(); ++c) n << (c ? "," : "") << 1 + children[j][c];
        n << "]";
      }
      n << "}";
      nodes.push_back(n.str());
      if (rig.parents[j] < 0) roots.push_back(1 + static_cast<int>(j));
      const std::pair<const char*, std::pair<const std::vector<float>*, const char*>> paths[3] = {
          {"translation", {&T[j], "VEC3"}}, {"rotation", {&R[j], "VEC4"}}, {"scale", {&S[j], "VEC3"}}};
      for (const auto& [what, data] : paths) {
        const int out = b.add_floats(*data.first, data.second, data.second[3] == '4' ? 4 : 3, false, 0);
        channels.push_back("{\"sampler\":" + std::to_string(samplers.size()) + ",\"target\":{\"node\":" + std::to_string(1 + j) +
                           ",\"path\":\"" + what + "\"}}");
        samplers.push_back("{\"input\":" + std::to_string(time_accessor) + ",\"output\":" + std::to_string(out) +
                           ",\"interpolation\":\"STEP\"}");
      }
    }
  }

  std::ostringstream j;
  j << "{\"asset\":{\"version\":\"2.0\",\"generator\":\"Sinew\"},\"scene\":0,\"scenes\":[{\"name\":"
    << quoted(track.name) << ",\"nodes\":[";
  for (std::size_t r = 0; r < roots.size(); ++r) j << (r ? "," : "") << roots[r];
  j << "]}],\"nodes\":" << GlbBuilder::join(nodes) << ",\"meshes\":[{\"name\":" << quoted(track.name)
    << ",\"primitives\":[{\"attributes\":{\"POSITION\":" << position << ",\"NORMAL\":" << normal << "},\"indices\":" << indices
    << ",\"mode\":4" << (F ? ",\"targets\":[" + targets.str() + "]" : "") << "}]";
  if (F) {
    // Without the animation (a static view) the first frame shows, as the skeleton's nodes do.
    j << ",\"weights\":[";
    for (std::size_t f = 0; f < F; ++f) j << (f ? ",0" : "1");
    j << "]";
  }
  j << ",\"extras\":{\"targetNames\":[" << names.str() << "],\"sinew_steps\":[" << steps.str() << "],\"sinew_frame_rate\":"
    << num(track.frame_rate) << ",\"sinew_fields\":{" << fields.str() << "}}}]";
  if (!channels.empty())
    j << ",\"animations\":[{\"name\":" << quoted(track.name) << ",\"samplers\":" << GlbBuilder::join(samplers)
      << ",\"channels\":" << GlbBuilder::join(channels) << "}]";
  j << ",\"buffers\":[{\"byteLength\":" << b.bin().size() << "}],\"bufferViews\":" << b.views_json()
    << ",\"accessors\":" << b.accessors_json() << "}";

  std::string json = j.str();
  while (json.size() % 4) json += ' ';
  std::vector<char> head, json_chunk(json.begin(), json.end()), bin_head;
  const std::uint64_t total = 12 + 8 + json_chunk.size() + 8 + b.bin().size();
  if (total > std::numeric_limits<std::uint32_t>::max())
    throw std::runtime_error(path + ": " + std::to_string(total >> 20) + " MB is more than a glTF binary holds (4 GB); write fewer frames");
  put(head, std::uint32_t{0x46546C67});  // "glTF"
  put(head, std::uint32_t{2});
  put(head, static_cast<std::uint32_t>(total));
  put(head, static_cast<std::uint32_t>(json_chunk.size()));
  put(head, std::uint32_t{0x4E4F534A});  // "JSON"
  put(bin_head, static_cast<std::uint32_t>(b.bin().size()));
  put(bin_head, std::uint32_t{0x004E4942});  // "BIN\0"
  write_file_durably(path, {&head, &json_chunk, &bin_head, &b.bin()});
}

void write_pc2(const std::string& path, const SkinTrack& track) {
  const std::size_t V = track.rest.size() / 3, F = track.frames.size();
  std::vector<char> head, data;
  const char magic[12] = {'P', 'O', 'I', 'N', 'T', 'C', 'A', 'C', 'H', 'E', '2', '\0'};
  head.insert(head.end(), magic, magic + 12);
  const float start = F ? static_cast<float>(track.frames[0].time * track.frame_rate) : 0.0f;
  const float sampling = F > 1 ? static_cast<float>((track.frames[1].time - track.frames[0].time) * track.frame_rate) : 1.0f;
  put(head, std::int32_t{1});
  put(head, static_cast<std::int32_t>(V));
  put(head, start);
  put(head, sampling);
  put(head, static_cast<std::int32_t>(F));
  data.reserve(F * V * 12);
  for (const auto& fr : track.frames)
    data.insert(data.end(), reinterpret_cast<const char*>(fr.x.data()), reinterpret_cast<const char*>(fr.x.data() + fr.x.size()));
  write_file_durably(path, {&head, &data});
}

SkinFrameFile::SkinFrameFile(const std::string& path, std::size_t vertices, const std::vector<std::string>& fields,
                             int keep_up_to_step, std::vector<SkinFrame>& kept, std::string& note)
    : path_(path), vertices_(vertices), fields_(fields) {
  for (const auto& f : fields_)
    if (f.size() >= kFieldNameBytes) throw std::logic_error("SkinFrameFile: field name '" + f + "' too long");
  kept.clear();
  if (keep_up_to_step >= 0) {
    if (std::FILE* f = std::fopen(path.c_str(), "rb")) {
      FrameFileHeader h;
      if (read_header(f, h) && h.vertices == vertices && h.fields == fields) {
        SkinFrame r;
        while (read_record(f, vertices, fields.size(), r) && r.step <= keep_up_to_step) kept.push_back(r);
      } else {
        note = path + " is from another skin or version: the skin's caches start again at the restart";
      }
      std::fclose(f);
    } else {
      note = "no " + path + ": the skin's caches start at the restart";
    }
  }
  frames_ = kept.size();
  if (frames_ == 0) {
    write_header();
    return;
  }
  // Cut off the frames after the restart (and a record a crash left half-written).
  const off_t size = static_cast<off_t>(header_bytes(fields_.size()) + frames_ * record_bytes(vertices_, fields_.size()));
  if (::truncate(path_.c_str(), size) != 0) throw std::runtime_error("cannot truncate " + path_);
  io_detail::sync_path(path_, false);
}

void SkinFrameFile::write_header() {
  std::vector<char> head(kFrameMagic, kFrameMagic + 8);
  put(head, kFrameVersion);
  put(head, static_cast<std::uint32_t>(vertices_));
  put(head, static_cast<std::uint32_t>(fields_.size()));
  for (const auto& f : fields_) {
    char name[kFieldNameBytes] = {};
    std::memcpy(name, f.data(), f.size());
    head.insert(head.end(), name, name + kFieldNameBytes);
  }
  write_file_durably(path_, {&head});
  frames_ = 0;
}

void SkinFrameFile::append(const SkinFrame& r) {
  if (r.x.size() != 3 * vertices_ || r.fields.size() != fields_.size())
    throw std::logic_error("SkinFrameFile::append: a frame of another shape");
  std::vector<char> rec;
  rec.reserve(record_bytes(vertices_, fields_.size()));
  put(rec, static_cast<std::int64_t>(r.step));
  put(rec, r.load);
  put(rec, r.time);
  rec.insert(rec.end(), reinterpret_cast<const char*>(r.x.data()), reinterpret_cast<const char*>(r.x.data() + r.x.size()));
  for (const auto& v : r.fields) {
    if (v.size() != vertices_) throw std::logic_error("SkinFrameFile::append: a field of another size");
    rec.insert(rec.end(), reinterpret_cast<const char*>(v.data()), reinterpret_cast<const char*>(v.data() + v.size()));
  }
  const int fd = ::open(path_.c_str(), O_WRONLY);
  if (fd < 0) throw std::runtime_error("cannot open " + path_ + " to append a frame");
  const off_t at = static_cast<off_t>(header_bytes(fields_.size()) + frames_ * rec.size());
  std::size_t done = 0;
  while (done < rec.size()) {
    const ssize_t w = ::pwrite(fd, rec.data() + done, rec.size() - done, at + static_cast<off_t>(done));
    if (w <= 0) {
      ::close(fd);
      throw std::runtime_error("appending a frame to " + path_ + " failed (disk full?)");
    }
    done += static_cast<std::size_t>(w);
  }
  const int synced = ::fsync(fd);
  ::close(fd);
  if (synced != 0) throw std::runtime_error("flushing " + path_ + " to disk failed");
  ++frames_;
}

std::vector<SkinFrame> read_skin_frames(const std::string& path, std::vector<std::string>* field_names) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) throw std::runtime_error("cannot open " + path);
  FrameFileHeader h;
  if (!read_header(f, h)) {
    std::fclose(f);
    throw std::runtime_error(path + " is not a Sinew skin frame file");
  }
  std::vector<SkinFrame> frames;
  SkinFrame r;
  while (read_record(f, h.vertices, h.fields.size(), r)) frames.push_back(r);
  std::fclose(f);
  if (field_names) *field_names = h.fields;
  return frames;
}

}  // namespace sinew
