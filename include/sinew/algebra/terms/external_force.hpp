// The potential of external forces constant in space: a body force b per reference volume and gravity
// g (an acceleration, times each element's density rho). Both are linear in u,
//   E = - sum_a (V_a b + m_a g) . u_a,   V_a = int N_a dV,   m_a = int rho N_a dV,
// the consistent nodal loads (exact for constant b and g, with the elements' own quadrature). The
// Hessian is zero.
#pragma once

#include <sinew/algebra/energy_term.hpp>

#include <array>
#include <vector>

namespace sinew {

class ExternalForceTerm final : public EnergyTerm {
 public:
  // Lumped volume and mass of the owned nodes.
  ExternalForceTerm(const std::vector<double>& nodal_volume, const std::vector<double>& nodal_mass);

  const char* name() const override { return "external"; }
  void add(const TermInput& in, TermOutput& out) const override;
  // Linear in u: node relaxation may freeze its share of a node's gradient.
  bool allows_node_relaxation(std::vector<char>&) const override { return true; }
  // The loads at load fraction t: t times the full ones when ramped (quasi-static), else in full.
  void set_load(double t) override;
  // g + V_a b / m_a at each node with mass: exact for the consistent mass matrix too (its rows sum to
  // m_a), for uniform density.
  bool add_load_acceleration(Vector& a) const override;

  // The full loads and whether set_load ramps them.
  void set_full(const std::array<double, 3>& b, const std::array<double, 3>& g, bool ramped);
  // The loads now (until the next set_load).
  void set_body_force(const std::array<double, 3>& b) { body_ = b; }
  void set_gravity(const std::array<double, 3>& g) { gravity_ = g; }
  bool active() const;

 private:
  Kokkos::View<double*, DeviceMemory> volume_, mass_;
  std::array<double, 3> body_{{0.0, 0.0, 0.0}}, gravity_{{0.0, 0.0, 0.0}};
  std::array<double, 3> full_body_{{0.0, 0.0, 0.0}}, full_gravity_{{0.0, 0.0, 0.0}};
  bool ramped_ = true;
};

}  // namespace sinew
