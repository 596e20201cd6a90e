// Volume meshes from files, read by one rank with Sinew's own streaming readers (written from the
// formats' documentation; the GPL Gmsh SDK is never linked):
//   Gmsh MSH 4.1 and 2.2, ASCII and binary: tet4 (type 4) and hex8 (type 5) volume elements; physical
//   groups become regions: volume groups select elements, surface, curve and point groups select nodes.
// Any other volume element type is an error naming it ("tet10 is not supported"), never dropped.
// Negatively oriented elements are reordered (and counted); degenerate ones are an error naming the
// element. Nodes no volume element uses are left out.
#pragma once

#include <sinew/core/errors.hpp>
#include <sinew/discretization/mesh.hpp>

#include <string>
#include <vector>

namespace sinew {

// A volume mesh as one rank holds it right after reading: compact node and element numbering in file
// order (global ids 0..n-1), with the file's own tags kept for messages and output.
struct MeshFile {
  std::string path, format;              // e.g. "Gmsh MSH 4.1 binary"
  ElementType type = ElementType::Tet4;
  std::vector<double> xyz;               // 3 per node
  std::vector<long long> node_tag;       // the file's tag of each node
  std::vector<int> conn;                 // nodes_per_element(type) node indices per element
  std::vector<long long> element_tag;    // the file's tag of each element
  std::vector<GroupMask> element_groups; // per element, bit g: in element_group_names[g]
  std::vector<std::string> element_group_names;
  std::vector<std::string> node_group_names;
  std::vector<std::vector<int>> node_group_nodes;  // per node group: sorted node indices
  long long reoriented = 0;              // negatively oriented elements that were reordered
  long long merged = 0;                  // copies of an element merged into one (MSH 2.2 writes an
                                         // element once per volume group it belongs to)
  std::vector<std::string> notes;        // what the reader changed, one line each, for the run's header

  std::size_t nodes() const { return node_tag.size(); }
  std::size_t elements() const { return element_tag.size(); }
};

// Reads a mesh file (the format from its content). Throws InputError (kind File for a file that
// cannot be read, BadMesh for a broken or unsupported mesh) naming the file, and the line, element
// or node at fault.
MeshFile read_mesh_file(const std::string& path);

// The names of the physical groups of a mesh file, by what they select, read without the nodes and
// elements (for `sinew --check`).
struct MeshGroups {
  std::vector<std::string> element_groups, node_groups;
};
MeshGroups read_mesh_groups(const std::string& path);

// The error for a group name the mesh does not have, listing the names it has (sorted), with the
// closest one as a suggestion. Empty node_groups: only volume groups are meant (material regions).
InputError unknown_group(const std::string& where, const std::string& name, std::vector<std::string> node_groups,
                         std::vector<std::string> element_groups);

}  // namespace sinew
