// Gmsh MSH 4.1 and 2.2 readers (ASCII and binary), streamed through a 1 MB buffer so that a file is
// never held in memory whole; only the nodes and the volume elements are kept. Written from the
// "MSH file format" chapter of the Gmsh reference manual.
#include <sinew/core/errors.hpp>
#include <sinew/core/parameters.hpp>
#include <sinew/core/validation.hpp>
#include <sinew/core/small_matrix.hpp>
#include <sinew/discretization/mesh_file.hpp>
#include <sinew/discretization/shape_functions.hpp>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <map>
#include <memory>
#include <set>
#include <unordered_map>

namespace sinew {

namespace {

// Gmsh element types: name, node count and dimension (enough to name or skip any of them).
struct GmshType {
  int id;
  const char* name;
  int nodes, dim;
};
constexpr GmshType kGmshTypes[] = {
    {1, "line2", 2, 1},       {2, "tri3", 3, 2},       {3, "quad4", 4, 2},      {4, "tet4", 4, 3},
    {5, "hex8", 8, 3},        {6, "prism6", 6, 3},     {7, "pyramid5", 5, 3},   {8, "line3", 3, 1},
    {9, "tri6", 6, 2},        {10, "quad9", 9, 2},     {11, "tet10", 10, 3},    {12, "hex27", 27, 3},
    {13, "prism18", 18, 3},   {14, "pyramid14", 14, 3}, {15, "point", 1, 0},    {16, "quad8", 8, 2},
    {17, "hex20", 20, 3},     {18, "prism15", 15, 3},  {19, "pyramid13", 13, 3}, {20, "tri9", 9, 2},
    {21, "tri10", 10, 2},     {22, "tri12", 12, 2},    {23, "tri15", 15, 2},    {24, "tri15i", 15, 2},
    {25, "tri21", 21, 2},     {26, "line4", 4, 1},     {27, "line5", 5, 1},     {28, "line6", 6, 1},
    {29, "tet20", 20, 3},     {30, "tet35", 35, 3},    {31, "tet56", 56, 3},    {92, "hex64", 64, 3},
    {93, "hex125", 125, 3}};

const GmshType* gmsh_type(int id) {
  for (const auto& t : kGmshTypes)
    if (t.id == id) return &t;
  return nullptr;
}

// A buffered reader over a file, for ASCII tokens and binary records alike; errors name the line.
class Source {
 public:
  explicit Source(const std::string& path) : path_(path), file_(std::fopen(path.c_str(), "rb"), &std::fclose) {
    if (!file_) throw InputError(path + ": cannot open mesh file", InputErrorKind::File);
    std::error_code ec;
    size_ = static_cast<long long>(std::filesystem::file_size(path, ec));
    if (ec) size_ = 0;
  }

  // A count the file declares, checked before anything is reserved for it: each item needs at least
  // `min_bytes` of what is left of the file, so a corrupt or hostile header (999999999999 nodes) is an
  // error naming its line, not an allocation failure.
  long long count(long long v, long long min_bytes, const char* what) {
    if (v < 0) fail(std::string("a negative count (") + what + ": " + std::to_string(v) + ")");
    const long long left = std::max(0LL, size_ - offset_);
    if (v > left / std::max(1LL, min_bytes))
      fail(std::string("declares ") + std::to_string(v) + " " + what + " but the " + std::to_string(left) +
           " bytes left in the file can hold at most " + std::to_string(left / std::max(1LL, min_bytes)) + " (corrupt or truncated?)");
    return v;
  }

  [[noreturn]] void fail(const std::string& why) const {
    throw InputError(path_ + ": line " + std::to_string(line_) + ": " + why, InputErrorKind::BadMesh);
  }
  const std::string& path() const { return path_; }

  bool eof() {
    return !fill(1);
  }
  int get() {
    if (!fill(1)) return EOF;
    const char c = buf_[pos_++];
    ++offset_;
    if (c == '\n') ++line_;
    return static_cast<unsigned char>(c);
  }
  void skip_space() {
    while (fill(1) && std::isspace(static_cast<unsigned char>(buf_[pos_]))) get();
  }
  // The next whitespace-delimited token ("" at the end of the file).
  std::string token() {
    skip_space();
    std::string t;
    while (fill(1) && !std::isspace(static_cast<unsigned char>(buf_[pos_]))) t.push_back(static_cast<char>(get()));
    return t;
  }
  // The rest of the current line, without its newline.
  std::string line() {
    std::string l;
    for (int c = get(); c != EOF && c != '\n'; c = get()) l.push_back(static_cast<char>(c));
    if (!l.empty() && l.back() == '\r') l.pop_back();
    return l;
  }
  // The next non-empty line.
  std::string next_line() {
    skip_space();
    return line();
  }
  long long integer(const char* what) {
    const std::string t = token();
    long long v = 0;
    const auto r = std::from_chars(t.data(), t.data() + t.size(), v);
    if (t.empty()) fail(std::string("the file ends where an integer (") + what + ") should be (truncated?)");
    if (r.ec != std::errc() || r.ptr != t.data() + t.size())
      fail(std::string("expected an integer (") + what + "), found '" + t.substr(0, 40) + "'");
    return v;
  }
  double real(const char* what) {
    const std::string t = token();
    double v = 0.0;
    const auto r = std::from_chars(t.data(), t.data() + t.size(), v);
    if (t.empty()) fail(std::string("the file ends where a number (") + what + ") should be (truncated?)");
    if (r.ec != std::errc() || r.ptr != t.data() + t.size() || !std::isfinite(v))
      fail(std::string("expected a finite number (") + what + "), found '" + t.substr(0, 40) + "'");
    return v;
  }
  void bytes(void* dst, std::size_t n, const char* what) {
    char* out = static_cast<char*>(dst);
    while (n > 0) {
      if (!fill(1)) fail(std::string("the file ends inside binary data (") + what + ")");
      const std::size_t k = std::min(n, len_ - pos_);
      for (std::size_t i = 0; i < k; ++i)
        if (buf_[pos_ + i] == '\n') ++line_;
      std::memcpy(out, buf_.data() + pos_, k);
      pos_ += k;
      offset_ += static_cast<long long>(k);
      out += k;
      n -= k;
    }
  }
  template <class T>
  T binary(const char* what) {
    T v;
    bytes(&v, sizeof v, what);
    return v;
  }
  // Skips to the line "$EndNAME".
  void skip_section(const std::string& name) {
    const std::string end = "$End" + name;
    while (!eof())
      if (next_line() == end) return;
    fail("section $" + name + " has no " + end);
  }
  void expect_end(const std::string& name) {
    const std::string l = next_line();
    if (l != "$End" + name) fail("expected $End" + name + ", found '" + l.substr(0, 40) + "'");
  }

 private:
  bool fill(std::size_t n) {
    if (len_ - pos_ >= n) return true;
    std::memmove(buf_.data(), buf_.data() + pos_, len_ - pos_);
    len_ -= pos_;
    pos_ = 0;
    len_ += std::fread(buf_.data() + len_, 1, buf_.size() - len_, file_.get());
    return len_ - pos_ >= n;
  }

  std::string path_;
  std::unique_ptr<FILE, int (*)(FILE*)> file_;
  std::vector<char> buf_ = std::vector<char>(1 << 20);
  std::size_t pos_ = 0, len_ = 0;
  long line_ = 1;
  long long size_ = 0, offset_ = 0;  // the file's size and the bytes consumed
};

// Node tag -> index into the nodes as read: a dense table when tags are compact, else a hash map.
class TagIndex {
 public:
  void reserve(long long min_tag, long long max_tag, std::size_t count) {
    if (max_tag >= min_tag && max_tag - min_tag < 4 * static_cast<long long>(count) + 1024) {
      base_ = min_tag;
      dense_.assign(static_cast<std::size_t>(max_tag - min_tag + 1), -1);
    }
  }
  bool insert(long long tag, long long index) {
    if (!dense_.empty() && tag >= base_ && tag - base_ < static_cast<long long>(dense_.size())) {
      auto& slot = dense_[tag - base_];
      if (slot >= 0) return false;
      slot = index;
      return true;
    }
    return sparse_.emplace(tag, index).second;
  }
  long long find(long long tag) const {
    if (!dense_.empty() && tag >= base_ && tag - base_ < static_cast<long long>(dense_.size())) return dense_[tag - base_];
    const auto it = sparse_.find(tag);
    return it == sparse_.end() ? -1 : it->second;
  }

 private:
  long long base_ = 0;
  std::vector<long long> dense_;
  std::unordered_map<long long, long long> sparse_;
};

// Everything gathered while reading, before the compact numbering.
struct Raw {
  double version = 0.0;
  bool binary = false;
  std::map<std::pair<int, int>, std::string> physical_names;       // (dim, tag) -> name
  std::map<std::pair<int, int>, std::vector<int>> entity_physicals;  // (dim, entity) -> physical tags (4.1)
  std::vector<double> xyz;                                          // as read
  std::vector<long long> node_tags;
  TagIndex index;
  int volume_type = 0;                     // Gmsh type of the volume elements
  std::vector<long long> vol_nodes;        // node tags, npe per element
  std::vector<long long> vol_tags;
  std::vector<GroupMask> vol_groups;       // the volume groups of each element, a bit each
  std::map<int, int> bit_of_physical;      // volume physical tag -> its bit
  std::vector<int> physical_of_bit;
  std::map<std::pair<int, int>, std::vector<long long>> group_node_tags;  // (dim, physical) -> node tags
  bool have_nodes = false, have_elements = false;
};

std::string group_name(const Raw& r, int dim, int tag) {
  const auto it = r.physical_names.find({dim, tag});
  return it != r.physical_names.end() ? it->second : std::to_string(tag);
}

// The bit of a volume physical group, given on first sight (named groups first, in tag order).
int group_bit(Source& s, Raw& r, int physical) {
  if (const auto it = r.bit_of_physical.find(physical); it != r.bit_of_physical.end()) return it->second;
  if (static_cast<int>(r.physical_of_bit.size()) >= kMaxVolumeGroups)
    s.fail("more than " + std::to_string(kMaxVolumeGroups) + " volume physical groups; Sinew supports at most " +
           std::to_string(kMaxVolumeGroups));
  const int bit = static_cast<int>(r.physical_of_bit.size());
  r.bit_of_physical[physical] = bit;
  r.physical_of_bit.push_back(physical);
  return bit;
}

// Size of the smallest record, to bound declared counts (Source::count): ASCII needs at least one
// digit and a separator per integer, binary its full width.
long long min_bytes(const Raw& r, int ascii, int binary) { return r.binary ? binary : ascii; }

void read_format(Source& s, Raw& r) {
  if (s.next_line() != "$MeshFormat") s.fail("not a Gmsh mesh: it does not start with $MeshFormat");
  const std::string v = s.token();
  const long long type = s.integer("file type"), size = s.integer("data size");
  if (v == "4.1")
    r.version = 4.1;
  else if (v == "2.2")
    r.version = 2.2;
  else
    s.fail("MSH version " + v + " is not supported; save the mesh as MSH 4.1 or 2.2");
  if (type != 0 && type != 1) s.fail("file type " + std::to_string(type) + " is neither 0 (ASCII) nor 1 (binary)");
  r.binary = type == 1;
  if (r.binary) {
    if (size != 8) s.fail("binary meshes need 8-byte sizes (data size " + std::to_string(size) + ")");
    s.line();
    if (s.binary<int>("endianness marker") != 1) s.fail("the binary mesh has the wrong byte order");
  }
  s.expect_end("MeshFormat");
}

void read_physical_names(Source& s, Raw& r) {
  const long long n = s.count(s.integer("number of physical names"), 6, "physical names");
  for (long long k = 0; k < n; ++k) {
    const int dim = static_cast<int>(s.integer("physical dimension"));
    const int tag = static_cast<int>(s.integer("physical tag"));
    std::string rest = s.line();
    const auto a = rest.find('"'), b = rest.rfind('"');
    if (a == std::string::npos || b == a) s.fail("a physical name must be quoted");
    r.physical_names[{dim, tag}] = rest.substr(a + 1, b - a - 1);
  }
  for (const auto& [key, name] : r.physical_names)
    if (key.first == 3) group_bit(s, r, key.second);
  s.expect_end("PhysicalNames");
}

// Size values (size_t in binary 4.1) and int values, ASCII or binary.
long long read_size(Source& s, const Raw& r, const char* what) {
  return r.binary ? static_cast<long long>(s.binary<std::uint64_t>(what)) : s.integer(what);
}
long long read_int(Source& s, const Raw& r, const char* what) { return r.binary ? s.binary<std::int32_t>(what) : s.integer(what); }
double read_real(Source& s, const Raw& r, const char* what) {
  if (!r.binary) return s.real(what);
  const double v = s.binary<double>(what);
  if (!std::isfinite(v)) s.fail(std::string("non-finite value (") + what + ")");
  return v;
}

void read_entities(Source& s, Raw& r) {
  long long counts[4];
  for (auto& c : counts) c = s.count(read_size(s, r, "number of entities"), min_bytes(r, 8, 28), "entities");
  for (int dim = 0; dim < 4; ++dim)
    for (long long k = 0; k < counts[dim]; ++k) {
      const int tag = static_cast<int>(read_int(s, r, "entity tag"));
      for (int c = 0; c < (dim == 0 ? 3 : 6); ++c) read_real(s, r, "entity bounding box");
      const long long nphys = s.count(read_size(s, r, "number of physical tags"), min_bytes(r, 2, 4), "physical tags");
      auto& phys = r.entity_physicals[{dim, tag}];
      for (long long p = 0; p < nphys; ++p) phys.push_back(static_cast<int>(read_int(s, r, "physical tag")));
      if (dim > 0) {
        const long long nb = s.count(read_size(s, r, "number of bounding entities"), min_bytes(r, 2, 4), "bounding entities");
        for (long long b = 0; b < nb; ++b) read_int(s, r, "bounding entity");
      }
    }
  s.expect_end("Entities");
}

void add_node(Source& s, Raw& r, long long tag, double x, double y, double z) {
  if (!r.index.insert(tag, static_cast<long long>(r.node_tags.size()))) s.fail("node " + std::to_string(tag) + " is defined twice");
  r.node_tags.push_back(tag);
  r.xyz.insert(r.xyz.end(), {x, y, z});
}

void read_nodes(Source& s, Raw& r) {
  if (r.have_nodes) s.fail("a second $Nodes section");
  r.have_nodes = true;
  if (r.version < 4.0) {
    const long long n = s.count(s.integer("number of nodes"), min_bytes(r, 8, 28), "nodes");
    r.node_tags.reserve(n);
    r.xyz.reserve(3 * n);
    if (r.binary) s.line();
    for (long long k = 0; k < n; ++k) {
      const long long tag = r.binary ? s.binary<std::int32_t>("node tag") : s.integer("node tag");
      const double x = read_real(s, r, "x"), y = read_real(s, r, "y"), z = read_real(s, r, "z");
      add_node(s, r, tag, x, y, z);
    }
    s.expect_end("Nodes");
    return;
  }
  const long long blocks = s.count(read_size(s, r, "number of node blocks"), min_bytes(r, 8, 20), "node blocks");
  const long long n = s.count(read_size(s, r, "number of nodes"), min_bytes(r, 8, 32), "nodes");
  const long long min_tag = read_size(s, r, "minimum node tag"), max_tag = read_size(s, r, "maximum node tag");
  r.index.reserve(min_tag, max_tag, static_cast<std::size_t>(n));
  r.node_tags.reserve(n);
  r.xyz.reserve(3 * n);
  std::vector<long long> tags;
  for (long long b = 0; b < blocks; ++b) {
    const int dim = static_cast<int>(read_int(s, r, "entity dimension"));
    read_int(s, r, "entity tag");
    const int parametric = static_cast<int>(read_int(s, r, "parametric flag"));
    const long long count = s.count(read_size(s, r, "nodes in block"), min_bytes(r, 8, 32), "nodes");
    tags.resize(count);
    for (auto& t : tags) t = read_size(s, r, "node tag");
    const int extra = parametric ? dim : 0;
    for (long long k = 0; k < count; ++k) {
      const double x = read_real(s, r, "x"), y = read_real(s, r, "y"), z = read_real(s, r, "z");
      for (int e = 0; e < extra; ++e) read_real(s, r, "parametric coordinate");
      add_node(s, r, tags[k], x, y, z);
    }
  }
  s.expect_end("Nodes");
}

// One element of any type: volume elements of the supported types are kept, others of dimension < 3
// give their nodes to their physical groups, and any other volume type is an error.
void take_element(Source& s, Raw& r, const GmshType& t, long long tag, const std::vector<int>& physicals,
                  const long long* nodes) {
  if (t.dim == 3) {
    if (t.id != 4 && t.id != 5)
      s.fail(std::string(t.name) + " is not supported (element " + std::to_string(tag) + ", Gmsh type " +
             std::to_string(t.id) + "): Sinew reads tet4 and hex8 volume elements");
    if (r.volume_type != 0 && r.volume_type != t.id)
      s.fail("the mesh mixes tet4 and hex8 elements (element " + std::to_string(tag) + "); Sinew needs one type");
    r.volume_type = t.id;
    r.vol_tags.push_back(tag);
    r.vol_nodes.insert(r.vol_nodes.end(), nodes, nodes + t.nodes);
    GroupMask mask = 0;
    for (int p : physicals)
      if (p != 0) mask |= GroupMask{1} << group_bit(s, r, p);
    r.vol_groups.push_back(mask);
    return;
  }
  for (int p : physicals) {
    auto& list = r.group_node_tags[{t.dim, p}];
    list.insert(list.end(), nodes, nodes + t.nodes);
  }
}

void read_elements(Source& s, Raw& r) {
  if (r.have_elements) s.fail("a second $Elements section");
  r.have_elements = true;
  std::vector<long long> nodes(128);
  if (r.version < 4.0) {
    const long long n = s.count(s.integer("number of elements"), 8, "elements");
    if (!r.binary) {
      for (long long k = 0; k < n; ++k) {
        const long long tag = s.integer("element tag");
        const int type = static_cast<int>(s.integer("element type"));
        const GmshType* t = gmsh_type(type);
        if (!t) s.fail("element " + std::to_string(tag) + " has unknown Gmsh type " + std::to_string(type));
        const long long ntags = s.count(s.integer("number of tags"), 2, "element tags");
        std::vector<int> physicals;
        for (long long j = 0; j < ntags; ++j) {
          const long long v = s.integer("tag");
          if (j == 0 && v != 0) physicals.push_back(static_cast<int>(v));
        }
        for (int a = 0; a < t->nodes; ++a) nodes[a] = s.integer("node of an element");
        take_element(s, r, *t, tag, physicals, nodes.data());
      }
    } else {
      s.line();
      for (long long done = 0; done < n;) {
        const int type = s.binary<std::int32_t>("element type");
        const int count = s.binary<std::int32_t>("elements in block");
        const int ntags = s.binary<std::int32_t>("number of tags");
        const GmshType* t = gmsh_type(type);
        if (!t) s.fail("unknown Gmsh element type " + std::to_string(type));
        if (count <= 0 || ntags < 0 || ntags > 1000 || done + count > n) s.fail("a corrupt element block header");
        s.count(count, 4LL * (1 + ntags + t->nodes), "elements");
        std::vector<std::int32_t> rec(1 + ntags + t->nodes);
        for (int k = 0; k < count; ++k) {
          s.bytes(rec.data(), rec.size() * sizeof(std::int32_t), "element");
          std::vector<int> physicals;
          if (ntags > 0 && rec[1] != 0) physicals.push_back(rec[1]);
          for (int a = 0; a < t->nodes; ++a) nodes[a] = rec[1 + ntags + a];
          take_element(s, r, *t, rec[0], physicals, nodes.data());
        }
        done += count;
      }
    }
    s.expect_end("Elements");
    return;
  }
  const long long blocks = s.count(read_size(s, r, "number of element blocks"), min_bytes(r, 8, 20), "element blocks");
  for (int k = 0; k < 3; ++k) read_size(s, r, "element count or tag range");
  std::vector<std::uint64_t> rec;
  for (long long b = 0; b < blocks; ++b) {
    const int dim = static_cast<int>(read_int(s, r, "entity dimension"));
    const int entity = static_cast<int>(read_int(s, r, "entity tag"));
    const int type = static_cast<int>(read_int(s, r, "element type"));
    const long long count = read_size(s, r, "elements in block");
    const GmshType* t = gmsh_type(type);
    if (!t) s.fail("unknown Gmsh element type " + std::to_string(type));
    s.count(count, min_bytes(r, 2, 8) * (1 + t->nodes), "elements");
    if (t->dim != dim) s.fail(std::string(t->name) + " elements in an entity of dimension " + std::to_string(dim));
    const auto it = r.entity_physicals.find({dim, entity});
    const std::vector<int> physicals = it == r.entity_physicals.end() ? std::vector<int>() : it->second;
    rec.resize(1 + t->nodes);
    for (long long k = 0; k < count; ++k) {
      if (r.binary) {
        s.bytes(rec.data(), rec.size() * sizeof(std::uint64_t), "element");
      } else {
        for (auto& v : rec) v = static_cast<std::uint64_t>(s.integer("element tag or node"));
      }
      for (int a = 0; a < t->nodes; ++a) nodes[a] = static_cast<long long>(rec[1 + a]);
      take_element(s, r, *t, static_cast<long long>(rec[0]), physicals, nodes.data());
    }
  }
  s.expect_end("Elements");
}

Raw read_raw(const std::string& path, bool groups_only) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw InputError(path + ": mesh file not found", InputErrorKind::File);
  if (std::filesystem::is_directory(path, ec)) throw InputError(path + ": is a directory, not a mesh file", InputErrorKind::File);
  if (std::filesystem::file_size(path, ec) == 0) throw InputError(path + ": the mesh file is empty", InputErrorKind::BadMesh);
  Source s(path);
  Raw r;
  read_format(s, r);
  while (!s.eof()) {
    const std::string l = s.next_line();
    if (l.empty()) continue;
    if (l[0] != '$') s.fail("expected a section ($Name), found '" + l.substr(0, 40) + "'");
    const std::string name = l.substr(1);
    if (name == "PhysicalNames")
      read_physical_names(s, r);
    else if (name == "Entities" && r.version > 4.0)
      read_entities(s, r);
    else if (name == "PartitionedEntities")
      s.fail("partitioned meshes are not supported; save the mesh without partitions (Sinew partitions it)");
    else if (groups_only && (name == "Nodes" || name == "Elements"))
      break;
    else if (name == "Nodes")
      read_nodes(s, r);
    else if (name == "Elements")
      read_elements(s, r);
    else
      s.skip_section(name);
  }
  if (groups_only) return r;
  if (!r.have_nodes) throw InputError(path + ": the mesh has no $Nodes section", InputErrorKind::BadMesh);
  if (r.vol_tags.empty())
    throw InputError(path + ": the mesh has no tet4 or hex8 volume elements (a surface mesh? mesh it in 3D)",
                     InputErrorKind::BadMesh);
  return r;
}

// Orientation and degeneracy: the reference Jacobian at every quadrature point. Reorders a negatively
// oriented element (returns true); throws for a degenerate or tangled one.
template <class E>
bool orient(const std::string& path, long long tag, double* X, int* conn) {
  auto jacobians = [&](double& lo, double& hi) {
    lo = HUGE_VAL;
    hi = -HUGE_VAL;
    for (int q = 0; q < E::points; ++q) {
      double dN[E::nodes][3];
      E::gradients(q, dN);
      Mat3 J = Mat3::zero();
      for (int a = 0; a < E::nodes; ++a)
        for (int i = 0; i < 3; ++i)
          for (int d = 0; d < 3; ++d) J(i, d) += X[3 * a + i] * dN[a][d];
      const double v = det(J);
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
  };
  double size = 0.0;  // the longest distance from node 0, cubed: the scale of a Jacobian
  for (int a = 1; a < E::nodes; ++a) {
    double d2 = 0.0;
    for (int i = 0; i < 3; ++i) d2 += (X[3 * a + i] - X[i]) * (X[3 * a + i] - X[i]);
    size = std::max(size, d2);
  }
  size = std::pow(size, 1.5);
  double lo, hi;
  jacobians(lo, hi);
  bool flipped = false;
  if (hi < 0.0) {  // mirrored: swap to the other orientation
    const int pairs[2][2] = {{1, 2}, {-1, -1}};
    if (E::nodes == 4) {
      std::swap(conn[pairs[0][0]], conn[pairs[0][1]]);
      for (int i = 0; i < 3; ++i) std::swap(X[3 * 1 + i], X[3 * 2 + i]);
    } else {
      for (const auto& [a, b] : {std::pair{1, 3}, std::pair{5, 7}}) {
        std::swap(conn[a], conn[b]);
        for (int i = 0; i < 3; ++i) std::swap(X[3 * a + i], X[3 * b + i]);
      }
    }
    flipped = true;
    jacobians(lo, hi);
  }
  if (!(lo > 1e-10 * size))
    throw InputError(path + ": element " + std::to_string(tag) +
                         (hi > 1e-10 * size ? " is tangled (its volume changes sign inside it)" : " is degenerate (zero volume)"),
                     InputErrorKind::BadMesh);
  return flipped;
}

// The same element listed twice. MSH 2.2 writes an element once per volume group it belongs to (with
// a new tag each time): copies in different groups are merged into one element in all of them. Copies
// in the same groups would be assembled twice: an error, as is one tag used for two elements.
long long merge_duplicates(const std::string& path, Raw& r, int npe) {
  const std::size_t ne = r.vol_tags.size();
  std::vector<long long> sorted(static_cast<std::size_t>(npe) * ne);
  std::vector<std::pair<std::uint64_t, std::size_t>> key(ne);
  for (std::size_t e = 0; e < ne; ++e) {
    long long* s = &sorted[npe * e];
    std::copy_n(&r.vol_nodes[npe * e], npe, s);
    std::sort(s, s + npe);
    std::uint64_t h = 1469598103934665603ull;  // FNV-1a over the sorted node tags
    for (int a = 0; a < npe; ++a) h = (h ^ static_cast<std::uint64_t>(s[a])) * 1099511628211ull;
    key[e] = {h, e};
  }
  std::sort(key.begin(), key.end());
  std::vector<char> drop(ne, 0);
  long long merged = 0;
  for (std::size_t i = 0; i < ne;) {
    std::size_t j = i + 1;
    while (j < ne && key[j].first == key[i].first) ++j;
    for (std::size_t a = i; a < j; ++a)
      for (std::size_t b = a + 1; b < j; ++b) {
        const std::size_t keep = std::min(key[a].second, key[b].second), copy = std::max(key[a].second, key[b].second);
        if (drop[keep] || drop[copy] || !std::equal(&sorted[npe * keep], &sorted[npe * keep] + npe, &sorted[npe * copy])) continue;
        if ((r.vol_groups[copy] & ~r.vol_groups[keep]) == 0)
          throw InputError(path + ": elements " + std::to_string(r.vol_tags[keep]) + " and " + std::to_string(r.vol_tags[copy]) +
                               " have the same nodes (the element is listed twice and would count twice)",
                           InputErrorKind::BadMesh);
        r.vol_groups[keep] |= r.vol_groups[copy];
        drop[copy] = 1;
        ++merged;
      }
    i = j;
  }
  std::vector<std::pair<long long, std::size_t>> tags;
  tags.reserve(ne);
  for (std::size_t e = 0; e < ne; ++e)
    if (!drop[e]) tags.emplace_back(r.vol_tags[e], e);
  std::sort(tags.begin(), tags.end());
  for (std::size_t k = 1; k < tags.size(); ++k)
    if (tags[k].first == tags[k - 1].first)
      throw InputError(path + ": element tag " + std::to_string(tags[k].first) + " is used by two different elements",
                       InputErrorKind::BadMesh);
  if (merged == 0) return 0;
  std::size_t out = 0;
  for (std::size_t e = 0; e < ne; ++e) {
    if (drop[e]) continue;
    r.vol_tags[out] = r.vol_tags[e];
    r.vol_groups[out] = r.vol_groups[e];
    std::copy_n(&r.vol_nodes[npe * e], npe, &r.vol_nodes[npe * out]);
    ++out;
  }
  r.vol_tags.resize(out);
  r.vol_groups.resize(out);
  r.vol_nodes.resize(npe * out);
  return merged;
}

MeshFile compact(const std::string& path, Raw& r) {
  MeshFile m;
  m.path = path;
  m.format = std::string("Gmsh MSH ") + (r.version > 4.0 ? "4.1" : "2.2") + (r.binary ? " binary" : " ASCII");
  m.type = r.volume_type == 5 ? ElementType::Hex8 : ElementType::Tet4;
  const int npe = nodes_per_element(m.type);
  m.merged = merge_duplicates(path, r, npe);
  const std::size_t ne = r.vol_tags.size();
  // Nodes used by volume elements, numbered in file order.
  std::vector<int> compact_of(r.node_tags.size(), -1);
  for (std::size_t e = 0; e < ne; ++e)
    for (int a = 0; a < npe; ++a) {
      const long long tag = r.vol_nodes[npe * e + a];
      const long long i = r.index.find(tag);
      if (i < 0)
        throw InputError(path + ": element " + std::to_string(r.vol_tags[e]) + " references node " + std::to_string(tag) +
                             ", which the $Nodes section does not define",
                         InputErrorKind::BadMesh);
      compact_of[i] = 0;
    }
  int n = 0;
  for (auto& c : compact_of)
    if (c == 0) c = n++;
  m.node_tag.resize(n);
  m.xyz.resize(3 * static_cast<std::size_t>(n));
  for (std::size_t i = 0; i < compact_of.size(); ++i)
    if (compact_of[i] >= 0) {
      m.node_tag[compact_of[i]] = r.node_tags[i];
      for (int d = 0; d < 3; ++d) m.xyz[3 * compact_of[i] + d] = r.xyz[3 * i + d];
    }
  r.xyz.clear();
  r.xyz.shrink_to_fit();
  // Volume elements, oriented, with their volume group.
  m.conn.resize(npe * ne);
  m.element_tag = r.vol_tags;
  m.element_groups = r.vol_groups;  // bit g: the g-th volume group (named ones first, in tag order)
  for (int p : r.physical_of_bit) m.element_group_names.push_back(group_name(r, 3, p));
  double X[3 * 8];
  for (std::size_t e = 0; e < ne; ++e) {
    int* c = &m.conn[npe * e];
    for (int a = 0; a < npe; ++a) {
      c[a] = compact_of[r.index.find(r.vol_nodes[npe * e + a])];
      for (int d = 0; d < 3; ++d) X[3 * a + d] = m.xyz[3 * static_cast<std::size_t>(c[a]) + d];
    }
    const bool flipped = m.type == ElementType::Hex8 ? orient<Hex8>(path, m.element_tag[e], X, c) : orient<Tet4>(path, m.element_tag[e], X, c);
    if (flipped) ++m.reoriented;
  }
  // Node groups from the lower-dimensional physical groups, on the nodes the volume mesh uses.
  std::map<std::string, std::set<int>> groups;
  for (const auto& [key, tags] : r.group_node_tags) {
    auto& g = groups[group_name(r, key.first, key.second)];
    for (long long tag : tags) {
      const long long i = r.index.find(tag);
      if (i < 0)
        throw InputError(path + ": physical group '" + group_name(r, key.first, key.second) + "' references node " +
                             std::to_string(tag) + ", which the $Nodes section does not define",
                         InputErrorKind::BadMesh);
      if (compact_of[i] >= 0) g.insert(compact_of[i]);
    }
  }
  for (const auto& [name, nodes] : groups) {
    m.node_group_names.push_back(name);
    m.node_group_nodes.emplace_back(nodes.begin(), nodes.end());
  }
  // What reading changed, for the run's header (a user should know the mesh is not the file verbatim).
  if (m.reoriented > 0)
    m.notes.push_back(std::to_string(m.reoriented) + " negatively oriented element" + (m.reoriented > 1 ? "s" : "") +
                      " reordered to positive orientation");
  if (m.merged > 0)
    m.notes.push_back(std::to_string(m.merged) + " repeated cop" + (m.merged > 1 ? "ies" : "y") +
                      " of elements in several volume groups merged (each element counts once)");
  if (static_cast<std::size_t>(n) < compact_of.size())
    m.notes.push_back(std::to_string(compact_of.size() - n) + " node" + (compact_of.size() - n > 1 ? "s" : "") +
                      " no volume element uses left out");
  return m;
}

}  // namespace

MeshFile read_mesh_file(const std::string& path) {
  Raw r = read_raw(path, false);
  return compact(path, r);
}

MeshGroups read_mesh_groups(const std::string& path) {
  const Raw r = read_raw(path, true);
  MeshGroups g;
  std::set<std::string> seen;
  for (const auto& [key, name] : r.physical_names) (key.first == 3 ? g.element_groups : g.node_groups).push_back(name);
  // Physical groups without a name (4.1 entities): named by their number.
  for (const auto& [key, phys] : r.entity_physicals)
    for (int p : phys)
      if (!r.physical_names.count({key.first, p})) {
        auto& list = key.first == 3 ? g.element_groups : g.node_groups;
        if (std::find(list.begin(), list.end(), std::to_string(p)) == list.end()) list.push_back(std::to_string(p));
      }
  return g;
}

InputError unknown_group(const std::string& where, const std::string& name, std::vector<std::string> node_groups,
                         std::vector<std::string> element_groups) {
  std::sort(node_groups.begin(), node_groups.end());
  std::sort(element_groups.begin(), element_groups.end());
  std::vector<std::string> all = node_groups;
  all.insert(all.end(), element_groups.begin(), element_groups.end());
  std::string msg = where + ": the mesh has no group '" + name + "'";
  if (all.empty()) return InputError(msg + " (it has no physical groups at all)");
  const std::string near = closest_name(name, all);
  if (!near.empty()) msg += " (did you mean '" + near + "'?)";
  if (!node_groups.empty()) msg += "; its node groups: " + or_list(node_groups);
  if (!element_groups.empty()) msg += "; its volume groups: " + or_list(element_groups);
  return InputError(msg);
}

}  // namespace sinew
