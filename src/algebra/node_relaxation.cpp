// ElasticTerm::relax: nonlinear Gauss-Seidel on a few nodes (terms/elastic.hpp, System::relax_nodes).
//
// Near the 48k-cell human's creases (issue 25) the residual of a Newton iterate sits on a handful of
// nodes: in step 5 of the crouch the five largest nodal forces held 50-94% of |F|^2 in every iteration,
// on surface nodes that belong to one to seven elements, and the Newton direction moved one of them by
// up to 5 cm while the 99.9th percentile of the nodes moved 1.6 mm, so the line search cut the whole
// step to 1/4 for them and the exact Hessian fell back. A nonlinear elimination (Cai and Keyes, SISC
// 2002: solve the local nonlinearity before the global Newton step) here is a few damped Newton
// iterations per node on its own three displacements, the rest of the mesh held: the energy of the
// elements around the node, with the rest of the total energy's gradient at that node frozen (exact for
// the external-force term, which is linear; System::relax_nodes refuses other terms).
#include "assembly.hpp"

#include <sinew/algebra/terms/elastic.hpp>
#include <sinew/core/sym_eigen.hpp>

#include <algorithm>
#include <cmath>

namespace sinew {

namespace {

// One node's patch: its elements and the node's place in each.
struct Patch {
  std::vector<int> elements, slot, block;
};

template <class Element>
struct PatchEvaluator {
  static constexpr int NPE = Element::nodes;
  ElementGeometry<DeviceMemory> geometry;
  Kokkos::View<const int**, DeviceMemory> conn;
  const std::vector<MaterialSpec>* laws;

  // Energy of the patch at u (overlap DOFs) and, when `want`, the node's gradient g and its exact 3x3
  // Hessian block H; false where the energy is undefined.
  bool operator()(const std::vector<double>& u, const Patch& p, bool want, double& E, double g[3], double H[3][3],
                  long long* inverted = nullptr) const {
    E = 0.0;
    if (inverted) *inverted = 0;
    for (int i = 0; i < 3; ++i) {
      g[i] = 0.0;
      for (int j = 0; j < 3; ++j) H[i][j] = 0.0;
    }
    for (std::size_t k = 0; k < p.elements.size(); ++k) {
      const int e = p.elements[k], a = p.slot[k];
      double ue[3 * NPE];
      for (int b = 0; b < NPE; ++b)
        for (int i = 0; i < 3; ++i) ue[3 * b + i] = u[3 * conn(e, b) + i];
      const MaterialSpec& law = (*laws)[p.block[k]];
      ElementResult<Element> r;
      with_material(law, [&](auto model) {
        compute_element<Element>(model, Projection::None, geometry, e, ue, want, want, r, law.mean_dilatation);
      });
      if (r.totals.undefined > 0 || !std::isfinite(r.totals.energy)) return false;
      if (inverted) *inverted += r.totals.inverted;
      E += r.totals.energy;
      if (want)
        for (int i = 0; i < 3; ++i) {
          g[i] += r.f[3 * a + i];
          for (int j = 0; j < 3; ++j) H[i][j] += r.K[3 * a + i][3 * a + j];
        }
    }
    return true;
  }
};

// d = -H^-1 g with H's eigenvalues kept above a small fraction of its largest (H is symmetric);
// false when H has no positive eigenvalue.
bool damped_newton_direction(const double H[3][3], const double g[3], double d[3]) {
  double A[9], ev[3], Q[9];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) A[3 * i + j] = H[i][j];
  jacobi_eigen<3>(A, ev, Q);
  const double top = std::max({ev[0], ev[1], ev[2]});
  if (!(top > 0.0)) return false;
  for (int i = 0; i < 3; ++i) d[i] = 0.0;
  for (int k = 0; k < 3; ++k) {
    // A negative eigenvalue is taken by its magnitude (a step down that curvature), a tiny one raised.
    const double e = std::max(std::fabs(ev[k]), 1e-6 * top);
    double qg = 0.0;
    for (int i = 0; i < 3; ++i) qg += Q[3 * i + k] * g[i];
    for (int i = 0; i < 3; ++i) d[i] -= Q[3 * i + k] * qg / e;
  }
  return true;
}

template <class Element>
NodeRelaxationTotals relax_with(const Mesh& mesh, const ElementData& ed, const std::vector<MaterialSpec>& laws,
                                const std::vector<int>& block_of, std::vector<double>& u, const std::vector<int>& nodes,
                                const std::vector<double>& force, const NodeRelaxationSettings& s) {
  NodeRelaxationTotals t;
  PatchEvaluator<Element> eval{element_geometry(mesh, ed), mesh.conn, &laws};
  // The patches of the nodes asked for, from one pass over the local elements.
  const std::size_t ne = mesh.local_elements();
  std::vector<int> which(mesh.local_nodes(), -1);
  for (std::size_t k = 0; k < nodes.size(); ++k) which[nodes[k]] = static_cast<int>(k);
  std::vector<Patch> patches(nodes.size());
  for (std::size_t e = 0; e < ne; ++e)
    for (int a = 0; a < Element::nodes; ++a) {
      const int k = which[mesh.conn(e, a)];
      if (k < 0) continue;
      patches[k].elements.push_back(static_cast<int>(e));
      patches[k].slot.push_back(a);
      patches[k].block.push_back(block_of[e]);
    }
  // The rest of the total energy's gradient at each node, frozen: the force rows minus the patch's own.
  // A node with an inverted point around it is left to Newton, and no local step may invert one: a
  // node's own minimum next to inverted elements can be a tangled one (a scrambled 4^3 cube relaxed
  // there ended with one inverted point and -3.6% volume instead of back at rest).
  std::vector<double> bias(3 * nodes.size());
  std::vector<char> skip(nodes.size(), 0), moved(nodes.size(), 0);
  for (std::size_t k = 0; k < nodes.size(); ++k) {
    double E, g[3], H[3][3];
    long long inverted = 0;
    if (!eval(u, patches[k], true, E, g, H, &inverted) || inverted > 0) skip[k] = 1;
    for (int i = 0; i < 3; ++i) bias[3 * k + i] = force[3 * k + i] - g[i];
  }
  for (int sweep = 0; sweep < s.sweeps; ++sweep)
    for (std::size_t k = 0; k < nodes.size(); ++k) {
      if (skip[k]) continue;
      double* x = &u[3 * nodes[k]];
      const Patch& p = patches[k];
      double g0 = -1.0;
      for (int it = 0; it < s.iterations; ++it) {
        double E0, g[3], H[3][3];
        if (!eval(u, p, true, E0, g, H)) break;
        for (int i = 0; i < 3; ++i) g[i] += bias[3 * k + i];
        const double gn = std::sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
        if (g0 < 0.0) g0 = gn;
        if (!(gn > s.tolerance) || gn < s.reduction * g0) break;
        double d[3];
        if (!damped_newton_direction(H, g, d)) break;
        const double slope = g[0] * d[0] + g[1] * d[1] + g[2] * d[2];
        if (!(slope < 0.0)) break;
        const double x0[3] = {x[0], x[1], x[2]};
        bool accepted = false;
        for (double step = 1.0; step > 1e-4; step *= 0.5) {
          for (int i = 0; i < 3; ++i) x[i] = x0[i] + step * d[i];
          double E1, gg[3], HH[3][3];
          long long inverted = 0;
          const double bias_work = step * (bias[3 * k] * d[0] + bias[3 * k + 1] * d[1] + bias[3 * k + 2] * d[2]);
          if (eval(u, p, false, E1, gg, HH, &inverted) && inverted == 0 && E1 + bias_work <= E0 + 1e-4 * step * slope) {
            accepted = true;
            t.decrease += E0 - E1 - bias_work;
            break;
          }
        }
        ++t.iterations;
        if (!accepted) {
          for (int i = 0; i < 3; ++i) x[i] = x0[i];
          break;
        }
        moved[k] = 1;
      }
    }
  t.nodes = std::count(moved.begin(), moved.end(), 1);
  return t;
}

}  // namespace

NodeRelaxationTotals ElasticTerm::relax(std::vector<double>& u, const std::vector<int>& nodes, const std::vector<double>& force,
                                        const NodeRelaxationSettings& s) const {
  if (!Kokkos::SpaceAccessibility<Kokkos::HostSpace, DeviceMemory>::accessible) return {};
  std::vector<MaterialSpec> laws;
  std::vector<int> block_of(mesh_.local_elements(), 0);
  for (std::size_t b = 0; b < blocks_.size(); ++b) {
    laws.push_back(blocks_[b].law);
    auto h = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), blocks_[b].elements);
    for (std::size_t k = 0; k < h.extent(0); ++k) block_of[h(k)] = static_cast<int>(b);
  }
  return mesh_.type == ElementType::Hex8 ? relax_with<Hex8>(mesh_, elements_, laws, block_of, u, nodes, force, s)
                                         : relax_with<Tet4>(mesh_, elements_, laws, block_of, u, nodes, force, s);
}

}  // namespace sinew
