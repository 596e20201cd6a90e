// Regions: which nodes a boundary condition or a bone takes. One declaration serves both (inlined in
// their sections), and one resolver turns it into this rank's nodes, the same on every rank for a node
// that several ranks hold.
//   face x- ... face z+   the nodes on a face of the mesh's bounding box
//   box                   the nodes within [Box lower, Box upper]
//   corners               four non-coplanar corners of the bounding box (pins rigid motion only)
//   all                   every node
//   group NAME[, NAME]    physical groups of a mesh file (their union): a surface, curve or point
//                         group's nodes, or the nodes of a volume group's elements
//   segment               the nodes within Radius of the segment from Segment start to Segment end
//   inside                the nodes inside the closed triangle surface 'Surface' (.obj, .stl): a bone
//                         given as a surface, for voxelized bodies
#pragma once

#include <sinew/core/errors.hpp>
#include <sinew/core/range.hpp>
#include <sinew/discretization/mesh.hpp>

#include <array>
#include <string>
#include <vector>

namespace sinew {

struct RegionParameters {
  std::string region, surface;
  std::array<double, 3> box_lower{}, box_upper{}, segment_start{}, segment_end{};
  double radius = 0.0;

  template <class V>
  void visit(V& v) {
    v.entry("Region", region, std::string(""),
            "which nodes (required): 'face x-' ... 'face z+' (a face of the bounding box), box, corners (four "
            "non-coplanar corners of the bounding box), all, 'group NAME' (a physical group of the mesh file), "
            "segment (within 'Radius' of a segment), inside (a closed 'Surface')");
    v.entry("Box lower", box_lower, {0.0, 0.0, 0.0}, "box region: lower corner");
    v.entry("Box upper", box_upper, {0.0, 0.0, 0.0}, "box region: upper corner");
    v.entry("Segment start", segment_start, {0.0, 0.0, 0.0}, "segment region: one end");
    v.entry("Segment end", segment_end, {0.0, 0.0, 0.0}, "segment region: the other end");
    v.entry("Radius", radius, 0.0, "segment region: the distance from the segment within which nodes are taken",
            Range::non_negative());
    v.entry("Surface", surface, std::string(""),
            "inside region: a closed triangle surface (.obj or .stl; a relative path is taken from the scene file's folder)");
  }
  // The syntax of 'Region' (names of groups are checked against the mesh later).
  template <class Context>
  void check(const Context& c) const {
    if (region.empty()) c.fail("missing entry 'Region'", InputErrorKind::MissingEntry);
    if (region.rfind("face ", 0) == 0) {
      const std::string f = region.substr(5);
      if (f.size() != 2 || f[0] < 'x' || f[0] > 'z' || (f[1] != '-' && f[1] != '+'))
        c.fail("'Region' face '" + f + "' is not one of x-, x+, y-, y+, z-, z+");
    } else if (region.rfind("group ", 0) == 0) {
      for (const auto& g : groups())
        if (g.empty()) c.fail("'Region' needs group names: 'group NAME' or 'group NAME, NAME'");
    } else if (region == "segment") {
      if (!(radius > 0.0)) c.fail("a segment region needs 'Radius' > 0");
    } else if (region == "inside") {
      if (surface.empty()) c.fail("an inside region needs 'Surface' (a closed .obj or .stl)", InputErrorKind::MissingEntry);
    } else if (region != "box" && region != "corners" && region != "all") {
      c.fail("unknown 'Region' \"" + region + "\" (face x-..z+, box, corners, all, group NAME, segment, inside)");
    }
    if (region != "inside" && c.given("Surface")) c.fail("'Surface' applies to an inside region only");
    if (region == "box")
      for (int k = 0; k < 3; ++k)
        if (!(box_upper[k] >= box_lower[k])) c.fail("'Box upper' must not lie below 'Box lower' in any coordinate");
  }
  // The groups a 'group NAME, NAME' region names (none for other regions).
  std::vector<std::string> groups() const {
    std::vector<std::string> out;
    if (region.rfind("group ", 0) != 0) return out;
    std::string rest = region.substr(6) + ",";
    for (std::size_t a = 0, b; (b = rest.find(',', a)) != std::string::npos; a = b + 1) {
      std::string name = rest.substr(a, b - a);
      name.erase(0, name.find_first_not_of(' '));
      name.erase(name.find_last_not_of(' ') + 1);
      out.push_back(name);
    }
    return out;
  }
};

// The distance from X to the segment from a to b (segment regions; the skeleton's skinning weights).
double segment_distance(const double* X, const std::array<double, 3>& a, const std::array<double, 3>& b);

// The local nodes (owned and ghost) of a region, identical on every rank that holds a node. Collective.
// Throws InputError naming `where` for a group the mesh does not have (listing those it has).
std::vector<int> select_region(const Mesh& mesh, const Teuchos::Comm<int>& comm, const RegionParameters& r,
                               const std::string& where);

}  // namespace sinew
