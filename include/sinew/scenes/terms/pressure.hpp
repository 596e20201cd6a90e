// Surface loads on regions of the boundary, a classic finite-element load: a pressure p along the
// inward normal and a traction t (force per area), both dead loads on the reference surface,
//
//   E = - sum_a f_a . u_a,   f_a = sum over the region's boundary faces of int_face N_a (t - p n) dA,
//
// n the outward unit normal at rest, N_a the face's own shape functions: the consistent nodal loads
// (a tet4 face: (t A - p n A) / 3 per node; a hex8 face: bilinear, 2 x 2 Gauss points, exact for a
// planar face, and for the pressure on any face, n dA = x_xi x x_eta dxi deta being polynomial). A
// region's face is a boundary face whose nodes all lie in the region. Linear in u: the Hessian is zero
// (PSD), and node relaxation may freeze its share. Ramped with the load in a quasi-static run, in full from the start of a dynamic one (as
// the body force). The term is this one file and a line in term_registry.hpp.
//
//   <ParameterList name="Pressure">
//     <ParameterList name="lid">
//       <Parameter name="Region" type="string" value="face z+"/>
//       <Parameter name="Pressure" type="double" value="50"/>
//     </ParameterList>
//   </ParameterList>
#pragma once

#include <sinew/core/errors.hpp>
#include <sinew/discretization/boundary.hpp>
#include <sinew/scenes/region.hpp>
#include <sinew/scenes/term_kind.hpp>

#include <Teuchos_CommHelpers.hpp>
#include <Tpetra_Export.hpp>
#include <Tpetra_Vector.hpp>

#include <array>
#include <cmath>
#include <stdexcept>
#include <unordered_map>

namespace sinew {

// One loaded region.
struct PressureLoadParameters {
  RegionParameters region;
  double pressure = 0.0;
  std::array<double, 3> traction{};

  template <class V>
  void visit(V& v) {
    v.inline_section(region);
    v.entry("Pressure", pressure, 0.0,
            "force per area along the inward normal of the surface at rest (positive pushes into the body), in full "
            "at the last load step");
    v.entry("Traction", traction, {0.0, 0.0, 0.0}, "force per area at rest, in full at the last load step");
  }
  template <class Context>
  void check(const Context& c) const {
    if (!c.given("Pressure") && !c.given("Traction")) c.fail("give 'Pressure' or 'Traction' (or both)", InputErrorKind::MissingEntry);
  }
};

struct PressureParameters {
  NamedSections<PressureLoadParameters> loads;

  template <class V>
  void visit(V& v) {
    v.other_sublists(loads, "one sublist per loaded region of the boundary, named as you like (Region, Pressure, Traction)");
  }
};

class PressureTerm final : public EnergyTerm {
 public:
  // load: the full nodal loads f on the owned DOFs; resultant: their sum over all ranks.
  PressureTerm(Kokkos::View<double*, DeviceMemory> load, const std::array<double, 3>& resultant, bool ramped)
      : load_(load), resultant_(resultant), ramped_(ramped) {}

  const char* name() const override { return "pressure"; }
  void add(const TermInput& in, TermOutput& out) const override {
    if (scale_ == 0.0) return;
    const auto f = load_;
    const auto u = in.u;
    const auto force = out.force;
    const bool want_force = in.want_force;
    const double s = scale_;
    double energy = 0.0;
    Kokkos::parallel_reduce(
        "sinew::pressure", Kokkos::RangePolicy<>(0, static_cast<int>(f.extent(0))),
        KOKKOS_LAMBDA(const int r, double& e) {
          e -= s * f(r) * u(r);
          if (want_force) force(r) -= s * f(r);
        },
        energy);
    out.energy += energy;
  }
  void set_load(double t) override { scale_ = ramped_ ? t : 1.0; }
  bool allows_node_relaxation(std::vector<char>&) const override { return true; }
  // The resultant force applied now (its magnitude).
  std::vector<std::string> log_columns() const override { return {"pressure_force"}; }
  std::vector<double> log_values(const EvaluationTotals&) const override {
    return {scale_ * std::sqrt(resultant_[0] * resultant_[0] + resultant_[1] * resultant_[1] + resultant_[2] * resultant_[2])};
  }
  const std::array<double, 3>& resultant() const { return resultant_; }

 private:
  Kokkos::View<double*, DeviceMemory> load_;
  std::array<double, 3> resultant_;
  bool ramped_ = true;
  double scale_ = 0.0;
};

struct PressureLoads {
  using Parameters = PressureParameters;
  static constexpr const char* section = "Pressure";
  static constexpr const char* doc = "pressures and tractions on regions of the boundary surface (dead loads)";
  static bool active(const Parameters& p) { return !p.loads.empty(); }
  static void resolve_paths(Parameters& p, const std::function<void(std::string&)>& resolve) {
    for (auto& [name, load] : p.loads) resolve(load.region.surface);
  }

  // Collective. Throws InputError naming the load whose region holds no boundary face (or is not one
  // of the mesh's groups).
  static std::shared_ptr<EnergyTerm> make(const Parameters& p, const TermContext& c) {
    const System& sys = c.system;
    const Mesh& mesh = sys.mesh();
    std::unordered_map<GlobalId, int> local;
    for (std::size_t n = 0; n < mesh.local_nodes(); ++n) local[mesh.node_gid[n]] = static_cast<int>(n);
    auto X = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.X);
    // Each rank loads the faces it counts (all their nodes are local here), into its overlap DOFs.
    const LocalBoundary boundary = local_boundary(mesh);
    Vector overlap(sys.overlap_dofs());
    {
      auto f = overlap.getLocalViewHost(Tpetra::Access::OverwriteAll);
      Kokkos::deep_copy(f, 0.0);
      for (const auto& [name, load] : p.loads) {
        const std::string where = "Pressure/" + name;
        std::vector<char> in(mesh.local_nodes(), 0);
        for (int n : select_region(mesh, c.comm, load.region, where)) in[n] = 1;
        long long faces = 0, all = 0;
        // A hex8 face is two consecutive boundary triangles (boundary.hpp).
        const bool hex = mesh.type == ElementType::Hex8;
        const std::size_t per_face = hex ? 2 : 1;
        for (std::size_t k = 0; k + per_face <= boundary.triangles.size(); k += per_face) {
          const auto& t0 = boundary.triangles[k];
          std::array<GlobalId, 4> g{t0[0], t0[1], t0[2], -1};
          if (hex && !quad_of_triangles(t0, boundary.triangles[k + 1], g))
            throw std::logic_error("PressureLoads: the boundary's hex8 faces are not consecutive triangle pairs");
          const int corners = hex ? 4 : 3;
          int v[4] = {0, 0, 0, 0};
          bool inside = true;
          for (int a = 0; a < corners; ++a) {
            v[a] = local.at(g[a]);
            inside = inside && in[v[a]];
          }
          if (!inside) continue;
          ++faces;
          if (!hex) {
            double e1[3], e2[3];
            for (int d = 0; d < 3; ++d) {
              e1[d] = X(v[1], d) - X(v[0], d);
              e2[d] = X(v[2], d) - X(v[0], d);
            }
            // e1 x e2 = 2 A n (outward: the boundary's faces are counter-clockwise seen from outside).
            const double n2[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
            const double area = 0.5 * std::sqrt(n2[0] * n2[0] + n2[1] * n2[1] + n2[2] * n2[2]);
            for (int a = 0; a < 3; ++a)
              for (int d = 0; d < 3; ++d) f(3 * v[a] + d, 0) += (load.traction[d] * area - load.pressure * 0.5 * n2[d]) / 3.0;
            continue;
          }
          // Bilinear quad, corners counter-clockwise (xi, eta) = (-1,-1), (1,-1), (1,1), (-1,1).
          static constexpr double xi_a[4] = {-1.0, 1.0, 1.0, -1.0}, eta_a[4] = {-1.0, -1.0, 1.0, 1.0};
          const double q = 1.0 / std::sqrt(3.0);
          for (double xi : {-q, q})
            for (double eta : {-q, q}) {
              double x_xi[3] = {0, 0, 0}, x_eta[3] = {0, 0, 0}, N[4];
              for (int a = 0; a < 4; ++a) {
                N[a] = 0.25 * (1.0 + xi_a[a] * xi) * (1.0 + eta_a[a] * eta);
                for (int d = 0; d < 3; ++d) {
                  x_xi[d] += 0.25 * xi_a[a] * (1.0 + eta_a[a] * eta) * X(v[a], d);
                  x_eta[d] += 0.25 * eta_a[a] * (1.0 + xi_a[a] * xi) * X(v[a], d);
                }
              }
              // n dA = x_xi x x_eta dxi deta (Gauss weights 1).
              const double nda[3] = {x_xi[1] * x_eta[2] - x_xi[2] * x_eta[1], x_xi[2] * x_eta[0] - x_xi[0] * x_eta[2],
                                     x_xi[0] * x_eta[1] - x_xi[1] * x_eta[0]};
              const double da = std::sqrt(nda[0] * nda[0] + nda[1] * nda[1] + nda[2] * nda[2]);
              for (int a = 0; a < 4; ++a)
                for (int d = 0; d < 3; ++d) f(3 * v[a] + d, 0) += N[a] * (load.traction[d] * da - load.pressure * nda[d]);
            }
        }
        Teuchos::reduceAll(c.comm, Teuchos::REDUCE_SUM, faces, Teuchos::outArg(all));
        if (all == 0)
          throw InputError(where + ": region \"" + load.region.region + "\" holds no face of the boundary surface",
                           InputErrorKind::EmptyRegion);
      }
    }
    // Ghost nodes' shares to their owners.
    Vector owned(sys.owned_dofs());
    owned.doExport(overlap, Tpetra::Export<LO, GO, NodeType>(sys.overlap_dofs(), sys.owned_dofs()), Tpetra::ADD);
    Kokkos::View<double*, DeviceMemory> load("pressure load", owned.getLocalLength());
    auto h = Kokkos::create_mirror_view(load);
    double sum[3] = {0.0, 0.0, 0.0}, total[3];
    {
      auto o = owned.getLocalViewHost(Tpetra::Access::ReadOnly);
      for (std::size_t r = 0; r < h.extent(0); ++r) {
        h(r) = o(r, 0);
        sum[r % 3] += o(r, 0);
      }
    }
    Kokkos::deep_copy(load, h);
    Teuchos::reduceAll(c.comm, Teuchos::REDUCE_SUM, 3, sum, total);
    return std::make_shared<PressureTerm>(load, std::array<double, 3>{total[0], total[1], total[2]}, !c.dynamic);
  }
};

}  // namespace sinew
