// Soft bone attachment: each node a bone holds is pulled towards where the bone carries it by a
// spring, instead of being prescribed there (a Dirichlet condition). Production flesh tools attach
// tissue to bones this way; it lets the flesh next to a joint give a little where two bones' nodes
// would otherwise crush it, and a node a bone takes by mistake (a stray lattice node) pull rather than
// tear.
//
//   E = sum_n k_n / 2 |X_n + u_n - T_b(t) X_n|^2,   k_n = kappa V_n,
//
// V_n the node's lumped volume (so that the springs do not depend on the mesh's density), T_b(t) the
// bone's rigid motion at the load, kappa a stiffness per volume per length (the scene's default: 100
// (mu_L + lambda_L) / h^2, a node's spring a hundred times a cell's stiffness). Gradient k_n (x_n -
// T_b X_n); Hessian k_n I per node: diagonal, positive, exact. Targets are set by set_load(t).
#pragma once

#include <sinew/algebra/system.hpp>

#include <Teuchos_CommHelpers.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

namespace sinew {

static_assert(Kokkos::SpaceAccessibility<Kokkos::HostSpace, DeviceMemory>::accessible,
              "BoneSpringTerm's loop runs on the host: it needs host-accessible memory (CUDA UVM)");

class BoneSpringTerm final : public EnergyTerm {
 public:
  struct Bone {
    std::string name;
    std::vector<int> nodes;  // local nodes (owned and ghost; only owned ones count)
    std::function<std::array<double, 3>(const std::array<double, 3>& X, double t)> place;  // T_b(t) X
  };

  // kappa > 0. A node held by two bones gets both springs.
  BoneSpringTerm(const System& system, std::vector<Bone> bones, double kappa) : system_(system), bones_(std::move(bones)) {
    if (!(kappa > 0.0)) throw std::logic_error("BoneSpringTerm: the stiffness must be positive");
    const Mesh& mesh = system.mesh();
    auto X = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.X);
    for (std::size_t b = 0; b < bones_.size(); ++b)
      for (int n : bones_[b].nodes) {
        if (static_cast<std::size_t>(n) >= mesh.n_owned_nodes) continue;
        springs_.push_back({static_cast<int>(b), n, kappa * system.nodal_volume()[n], {X(n, 0), X(n, 1), X(n, 2)}, {}});
      }
    set_load(0.0);
  }

  const char* name() const override { return "bone_springs"; }

  void add(const TermInput& in, TermOutput& out) const override {
    const auto u = in.u;
    const auto f = out.force;
    const auto A = out.matrix;
    double energy = 0.0;
    for (const Spring& s : springs_) {
      double d2 = 0.0;
      for (int c = 0; c < 3; ++c) {
        const int row = 3 * s.node + c;  // owned: its row is its column (owned columns come first)
        const double d = s.X[c] + u(row) - s.target[c];
        d2 += d * d;
        if (in.want_force) f(row) += s.k * d;
        if (in.want_matrix) A.sumIntoValues(row, &row, 1, &s.k, true, true);
      }
      energy += 0.5 * s.k * d2;
    }
    out.energy += energy;
  }

  void set_load(double t) override {
    for (Spring& s : springs_) s.target = bones_[s.bone].place(s.X, t);
  }

  // The largest distance of a held node from where its bone carries it (collective), at u.
  double largest_offset(const Vector& u) const {
    auto uh = u.getLocalViewHost(Tpetra::Access::ReadOnly);
    double mine = 0.0, all = 0.0;
    for (const Spring& s : springs_) {
      double d2 = 0.0;
      for (int c = 0; c < 3; ++c) {
        const double d = s.X[c] + uh(3 * s.node + c, 0) - s.target[c];
        d2 += d * d;
      }
      mine = std::max(mine, std::sqrt(d2));
    }
    Teuchos::reduceAll(*system_.comm(), Teuchos::REDUCE_MAX, mine, Teuchos::outArg(all));
    return all;
  }
  // The root-mean-square offset of the held nodes, sqrt(2 E / sum k_n) (weighted by their springs),
  // from the energy share the step ended with.
  std::vector<std::string> log_columns() const override { return {"bone_spring_rms_offset"}; }
  std::vector<double> log_values(const EvaluationTotals& totals) const override {
    double k = 0.0, all = 0.0;
    for (const Spring& s : springs_) k += s.k;
    Teuchos::reduceAll(*system_.comm(), Teuchos::REDUCE_SUM, k, Teuchos::outArg(all));
    const double e = totals.share(name());
    return {all > 0.0 ? std::sqrt(std::max(0.0, 2.0 * e / all)) : 0.0};
  }

 private:
  struct Spring {
    int bone, node;
    double k;
    std::array<double, 3> X, target;
  };
  const System& system_;
  std::vector<Bone> bones_;
  std::vector<Spring> springs_;
};

}  // namespace sinew
