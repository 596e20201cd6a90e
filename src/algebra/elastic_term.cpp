// ElasticTerm: material blocks and the element loop per block (terms/elastic.hpp).
#include "assembly.hpp"

#include <sinew/algebra/system.hpp>
#include <sinew/algebra/terms/elastic.hpp>
#include <sinew/core/errors.hpp>
#include <sinew/discretization/colouring.hpp>
#include <sinew/discretization/mesh_file.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>

namespace sinew {

ElasticTerm::ElasticTerm(const Mesh& mesh, const ElementData& elements, const MaterialAssignment& materials)
    : mesh_(mesh), elements_(elements) {
  // One block per law: the default law first, then one per region in the order given; an element
  // belongs to the last region listed that contains it.
  const std::size_t ne = mesh_.local_elements();
  std::vector<int> block_of(ne, 0);
  std::vector<MaterialSpec> laws{materials.default_law};
  const auto& names = mesh_.element_group_names;
  for (const auto& [name, law] : materials.regions) {
    const auto it = std::find(names.begin(), names.end(), name);
    if (it == names.end()) throw unknown_group("Material/" + name, name, {}, names);
    const int group = static_cast<int>(it - names.begin());
    for (std::size_t e = 0; e < ne; ++e)
      if (mesh_.in_group(e, group)) block_of[e] = static_cast<int>(laws.size());
    laws.push_back(law);
  }
  const int chunk = detail::assembly_chunk_size();
  const std::vector<int> conn = chunk > 0 ? detail::host_connectivity(mesh_) : std::vector<int>{};
  for (std::size_t b = 0; b < laws.size(); ++b) {
    std::vector<int> ids;
    for (std::size_t e = 0; e < ne; ++e)
      if (block_of[e] == static_cast<int>(b)) ids.push_back(static_cast<int>(e));
    detail::ElementOrder order = detail::order_elements(ids, mesh_, conn, chunk);
    blocks_.push_back(Block{laws[b], order.elements, order.chunks, order.colour_begin});
  }
}

double ElasticTerm::stiffness_scale() const {
  double s = 0.0;
  for (const auto& b : blocks_) s = std::max(s, b.law.mu_L + std::fabs(b.law.lambda_L));
  return s;
}

std::vector<long long> ElasticTerm::owned_region_elements() const {
  std::vector<long long> n;
  for (std::size_t b = 1; b < blocks_.size(); ++b) {
    auto h = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), blocks_[b].elements);
    long long k = 0;
    for (std::size_t i = 0; i < h.extent(0); ++i) k += static_cast<std::size_t>(h(i)) < mesh_.n_owned_elements;
    n.push_back(k);
  }
  return n;
}

std::vector<double> ElasticTerm::element_density() const {
  std::vector<double> rho(mesh_.local_elements(), blocks_.front().law.density);
  for (const auto& b : blocks_) {
    auto h = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), b.elements);
    for (std::size_t k = 0; k < h.extent(0); ++k) rho[h(k)] = b.law.density;
  }
  return rho;
}

void ElasticTerm::add(const TermInput& in, TermOutput& out) const {
  detail::AssemblyRequest r;
  r.geometry = element_geometry(mesh_, elements_);
  r.u = in.u;
  r.target.force = out.force;
  r.target.matrix = out.matrix;
  r.target.owned_dofs = out.owned_dofs;
  r.want_force = in.want_force;
  r.want_matrix = in.want_matrix;
  r.fields = out.fields;
  const bool hex = mesh_.type == ElementType::Hex8;
  AssemblyTotals t;
  t.min_J = HUGE_VAL;
  for (const Block& b : blocks_) {
    if (b.elements.extent(0) == 0) continue;
    Projection p = in.projection.value_or(b.law.projection);
    const detail::Chunks chunks{b.chunks, b.colour_begin};
    // "Exact where not inverted" keeps the law's own projection for the inverted points.
    if (p == Projection::ExactUninvertedClamp || p == Projection::ExactUninvertedAbs)
      p = b.law.projection == Projection::Abs ? Projection::ExactUninvertedAbs
          : b.law.projection == Projection::None ? Projection::None : Projection::ExactUninvertedClamp;
#if defined(KOKKOS_ENABLE_SERIAL) && defined(KOKKOS_ENABLE_OPENMP)
    if (in.backend == Backend::Serial) {
      t.add(hex ? detail::assemble_hex8<Kokkos::Serial>(b.law, p, b.elements, chunks, r)
                : detail::assemble_tet4<Kokkos::Serial>(b.law, p, b.elements, chunks, r));
      continue;
    }
#endif
    t.add(hex ? detail::assemble_hex8<Kokkos::DefaultExecutionSpace>(b.law, p, b.elements, chunks, r)
              : detail::assemble_tet4<Kokkos::DefaultExecutionSpace>(b.law, p, b.elements, chunks, r));
  }
  EvaluationTotals& o = out.totals;
  out.energy += t.energy;
  o.volume += t.volume;
  o.min_J = std::min(o.min_J, t.min_J);
  o.inverted += t.inverted;
  o.undefined += t.undefined;
}

}  // namespace sinew
