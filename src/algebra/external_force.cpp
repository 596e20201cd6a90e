// ExternalForceTerm (terms/external_force.hpp).
#include <sinew/algebra/terms/external_force.hpp>

#include <Tpetra_Vector.hpp>

namespace sinew {

namespace {
Kokkos::View<double*, DeviceMemory> device_copy(const std::vector<double>& v, const char* label) {
  Kokkos::View<double*, DeviceMemory> d(std::string(label), v.size());
  auto h = Kokkos::create_mirror_view(d);
  for (std::size_t k = 0; k < v.size(); ++k) h(k) = v[k];
  Kokkos::deep_copy(d, h);
  return d;
}
}  // namespace

ExternalForceTerm::ExternalForceTerm(const std::vector<double>& nodal_volume, const std::vector<double>& nodal_mass)
    : volume_(device_copy(nodal_volume, "nodal volume")), mass_(device_copy(nodal_mass, "nodal mass")) {}

bool ExternalForceTerm::active() const {
  for (int i = 0; i < 3; ++i)
    if (body_[i] != 0.0 || gravity_[i] != 0.0) return true;
  return false;
}

void ExternalForceTerm::add(const TermInput& in, TermOutput& out) const {
  if (!active()) return;
  const auto V = volume_, m = mass_;
  const auto u = in.u;
  const auto f = out.force;
  const bool want_force = in.want_force;
  const double b0 = body_[0], b1 = body_[1], b2 = body_[2], g0 = gravity_[0], g1 = gravity_[1], g2 = gravity_[2];
  double energy = 0.0;
  Kokkos::parallel_reduce(
      "sinew::external_force", Kokkos::RangePolicy<>(0, static_cast<int>(V.extent(0))),
      KOKKOS_LAMBDA(const int n, double& e) {
        const double load[3] = {V(n) * b0 + m(n) * g0, V(n) * b1 + m(n) * g1, V(n) * b2 + m(n) * g2};
        for (int c = 0; c < 3; ++c) {
          e -= load[c] * u(3 * n + c);
          if (want_force) f(3 * n + c) -= load[c];
        }
      },
      energy);
  out.energy += energy;
}

bool ExternalForceTerm::add_load_acceleration(Vector& a) const {
  if (!active()) return false;
  // Host mirrors of the nodal volumes and masses: the views themselves where memory is host-accessible.
  const auto V = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), volume_);
  const auto m = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mass_);
  auto h = a.getLocalViewHost(Tpetra::Access::ReadWrite);
  for (std::size_t n = 0; n < m.extent(0); ++n) {
    if (!(m(n) > 0.0)) continue;
    for (int c = 0; c < 3; ++c) h(3 * n + c, 0) += gravity_[c] + V(n) * body_[c] / m(n);
  }
  return true;
}

void ExternalForceTerm::set_full(const std::array<double, 3>& b, const std::array<double, 3>& g, bool ramped) {
  full_body_ = b;
  full_gravity_ = g;
  ramped_ = ramped;
}

void ExternalForceTerm::set_load(double t) {
  const double ramp = ramped_ ? t : 1.0;
  for (int c = 0; c < 3; ++c) {
    body_[c] = ramp * full_body_[c];
    gravity_[c] = ramp * full_gravity_[c];
  }
}

}  // namespace sinew
