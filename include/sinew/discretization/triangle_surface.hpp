// Closed triangle surfaces (a character's skin, a bone) and the hex lattice that fills one, as the
// paper builds its bone-driven characters (Sec. 6, Fig. 1: a character embedded in a hexahedral
// lattice):
//   read_triangle_surface   Wavefront OBJ (polygons fanned into triangles) or STL (ASCII or binary,
//                           coincident vertices merged), checked to be closed: every edge on exactly
//                           two triangles, or an error naming an open edge; then oriented consistently
//                           and outward (exporters do not always keep one orientation)
//   InsideTest              whether a point lies inside (parity of the crossings of a ray along +x)
//   voxelize                the lattice of cells of a given size whose centres lie inside, as a mesh
//                           file that distribute_mesh spreads over the ranks like any other
//   embed                   each surface vertex bound to a lattice cell by trilinear weights, so that
//                           the skin follows the flesh (written per output step, io/surface.hpp)
#pragma once

#include <sinew/discretization/aabb_tree.hpp>
#include <sinew/discretization/mesh.hpp>
#include <sinew/discretization/mesh_file.hpp>

#include <array>
#include <string>
#include <vector>

namespace sinew {

struct TriangleSurface {
  std::string path;
  std::vector<std::array<double, 3>> vertices;
  std::vector<std::array<int, 3>> triangles;
  std::array<double, 3> lower{}, upper{};  // bounding box
  void set_bounds();                        // lower and upper from the vertices (at least one)
};

// Throws InputError (kind File for an unreadable file, BadMesh for a broken or open surface).
TriangleSurface read_triangle_surface(const std::string& path);

class InsideTest {
 public:
  explicit InsideTest(const TriangleSurface& s);
  bool inside(const std::array<double, 3>& p) const;

 private:
  const TriangleSurface& s_;
  int bins_ = 1;
  double y0_ = 0.0, z0_ = 0.0, dy_ = 1.0, dz_ = 1.0;
  std::vector<std::vector<int>> bin_;  // triangles whose y-z bounding box meets each (y, z) bin
};

// The hex8 lattice of cells of size h (aligned with the surface's bounding box) whose centres lie
// inside. Throws InputError when no cell does.
struct Lattice {
  MeshFile mesh;
  std::array<double, 3> origin{};
  std::array<int, 3> cells{};
  double h = 0.0;
  std::vector<int> cell_element;  // per lattice cell: its element, or -1 outside
};
// Inside by the parity of a ray's crossings (a closed surface), or by the generalized winding number
// w(p) = sum of the triangles' solid angles / 4 pi > 1/2 (Jacobson et al. 2013): robust to a skin
// made of open pieces that abut or overlap, as characters' skins are (outward triangles assumed).
enum class InsideRule { Parity, Winding };
Lattice voxelize(const TriangleSurface& s, double h, InsideRule rule = InsideRule::Parity);
// The generalized winding number of a point with respect to a triangle soup (every triangle's exact
// solid angle: O(triangles) per point).
double winding_number(const TriangleSurface& s, const std::array<double, 3>& p);

// The same number in O(log triangles) per point (Barill et al. 2018, "Fast winding numbers for soups
// and clouds"): the triangles in a bounding-volume hierarchy, and a subtree whose triangles are all
// farther than beta times their radius from the point counted by the second-order expansion of its
// solid angle about its area-weighted centroid, from the sums
//   N = sum of a_i n_i                       (area-weighted normals: the dipole)
//   T = sum of a_i n_i (x_i - c)^T           (its first moment)
// as  w = [ N.r / |r|^3 + tr(T) / |r|^3 - 3 r.T r / |r|^5 ] / (4 pi),   r = c - p.
// Nearer subtrees are descended down to exact triangles. The error falls as the expansion's third-order
// remainder, beta^-3: on a 5k-triangle human at points 3 mm off its skin 0.042 (beta = 2), 0.016 (3),
// 0.0054 (4), 0.0010 (6); voxelization thresholds w at 1/2 with the default beta = 3.
class FastWindingNumber {
 public:
  explicit FastWindingNumber(const TriangleSurface& s, double beta = 3.0);
  double operator()(const std::array<double, 3>& p) const;

 private:
  struct Far {
    std::array<double, 3> c{}, N{};
    double T[3][3] = {};
    double r2 = 0.0;  // (beta x radius)^2: nearer points descend
  };
  const TriangleSurface& s_;
  geom::AabbTree tree_;
  std::vector<Far> far_;
};

// Binds every surface vertex to the kept cell that contains it (or the nearest one, for a vertex in a
// cell whose centre was outside) by the trilinear weights of the cell's eight nodes.
// Vertices farther than two cells from every kept cell are an error (a feature too thin for the
// cells), unless far_vertices is given: then each takes the cell of the nearest placed vertex along
// the surface's edges (a finger follows its hand, not a thigh nearer in space), its trilinear map
// extrapolated (exact for the affine part of the cell's motion), and they are counted there.
EmbeddedSurface embed(const TriangleSurface& s, const Lattice& lattice, long long* far_vertices = nullptr);

}  // namespace sinew
