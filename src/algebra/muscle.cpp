// MuscleTerm (terms/muscle.hpp): the fibre energy's element loop.
#include "assembly.hpp"

#include <sinew/algebra/terms/muscle.hpp>

#include <Teuchos_CommHelpers.hpp>

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace sinew {

namespace {

// Energy and fibre-stretch range over owned elements.
struct FiberTotals {
  double energy = 0.0, min_stretch = HUGE_VAL, max_stretch = -HUGE_VAL;
};

template <class Element, class Target>
struct FiberLoop {
  using memory_space = typename Target::memory_space;
  using value_type = FiberTotals;
  FiberLaw law;
  double activation = 0.0;
  Projection projection = Projection::Clamp;
  ElementGeometry<memory_space> geometry;
  Kokkos::View<const int*, memory_space> elements;
  Kokkos::View<const double* [3], memory_space> fibers;
  Kokkos::View<const double*, memory_space> u;
  Target target;
  bool want_force = false, want_matrix = false;
  // Coloured chunks, as ElementLoop's (element_kernel.hpp): work item i is chunk chunk_first + i.
  Kokkos::View<const int*, memory_space> chunks;
  int chunk_first = 0;

  KOKKOS_INLINE_FUNCTION void init(value_type& t) const { t = FiberTotals(); }
  KOKKOS_INLINE_FUNCTION void join(value_type& a, const value_type& b) const {
    a.energy += b.energy;
    a.min_stretch = b.min_stretch < a.min_stretch ? b.min_stretch : a.min_stretch;
    a.max_stretch = b.max_stretch > a.max_stretch ? b.max_stretch : a.max_stretch;
  }
#if KOKKOS_VERSION < 40000
  KOKKOS_INLINE_FUNCTION void join(volatile value_type& a, const volatile value_type& b) const {
    a.energy += b.energy;
    a.min_stretch = b.min_stretch < a.min_stretch ? b.min_stretch : a.min_stretch;
    a.max_stretch = b.max_stretch > a.max_stretch ? b.max_stretch : a.max_stretch;
  }
#endif

  KOKKOS_INLINE_FUNCTION void operator()(const int i, value_type& totals) const {
    if (chunks.extent(0) == 0) {
      element(i, totals);
      return;
    }
    for (int k = chunks(chunk_first + i); k < chunks(chunk_first + i + 1); ++k) element(k, totals);
  }

  // Entry i of `elements` (and of `fibers`).
  KOKKOS_INLINE_FUNCTION void element(const int i, value_type& totals) const {
    constexpr int NPE = Element::nodes, NDOF = 3 * NPE;
    const int e = elements(i);
    int dof[NDOF];
    double ue[NDOF];
    gather<Element>(geometry, u, e, dof, ue);
    FiberPoint model;
    model.law = law;
    model.activation = activation;
    for (int k = 0; k < 3; ++k) model.a[k] = fibers(i, k);
    ElementResult<Element> r;
    clear_result(want_matrix, r);
    const bool owned = e < geometry.n_owned;
    for (int q = 0; q < Element::points; ++q) {
      PointState<Element> s;
      evaluate_point<Element>(model, geometry, e, q, ue, s);
      if (owned) {
        totals.energy += s.w * s.psi;
        const double lambda = model.stretch(s.F);
        totals.min_stretch = lambda < totals.min_stretch ? lambda : totals.min_stretch;
        totals.max_stretch = lambda > totals.max_stretch ? lambda : totals.max_stretch;
      }
      if (want_force) add_point_force<NPE>(r.f, model.pk1(s.F), s.dN, s.w);
      if (want_matrix) add_point_stiffness<NPE>(r.K, model.projected_hessian(s.F, projection), s.dN, s.w);
    }
    if (want_matrix) mirror_stiffness(r);
    scatter<Element>(target, dof, r, want_force, want_matrix);
  }
};

template <class Element>
FiberTotals dispatch(const FiberLoop<Element, detail::Target>& loop, int n, const detail::Chunks& chunks, Backend backend) {
#if defined(KOKKOS_ENABLE_SERIAL) && defined(KOKKOS_ENABLE_OPENMP)
  if (backend == Backend::Serial) return detail::run_element_loop<Kokkos::Serial>(loop, n, chunks);
#endif
  (void)backend;
  return detail::run_element_loop<Kokkos::DefaultExecutionSpace>(loop, n, chunks);
}

}  // namespace

MuscleTerm::MuscleTerm(Teuchos::RCP<const Teuchos::Comm<int>> comm, const Mesh& mesh, const ElementData& elements,
                       std::vector<MuscleBlock> muscles)
    : comm_(std::move(comm)), mesh_(mesh), elements_(elements) {
  const int chunk = detail::assembly_chunk_size();
  const std::vector<int> conn = chunk > 0 ? detail::host_connectivity(mesh) : std::vector<int>{};
  for (auto& m : muscles) {
    if (const std::string why = m.law.invalid(); !why.empty()) throw std::invalid_argument("muscle " + m.name + ": " + why);
    if (m.fibers.size() != m.elements.size()) throw std::invalid_argument("muscle " + m.name + ": one fibre per element");
    if (!m.activation) throw std::invalid_argument("muscle " + m.name + ": no activation");
    for (const auto& a : m.fibers)
      if (!(std::fabs(std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]) - 1.0) < 1e-9))
        throw std::invalid_argument("muscle " + m.name + ": a fibre is not a unit vector");
    detail::ElementOrder order = detail::order_elements(m.elements, mesh, conn, chunk);
    Block b;
    b.elements = order.elements;
    b.chunks = order.chunks;
    b.colour_begin = order.colour_begin;
    b.fibers = Kokkos::View<double* [3]>("muscle fibres", m.elements.size());
    auto hf = Kokkos::create_mirror_view(b.fibers);
    for (std::size_t k = 0; k < order.position.size(); ++k)
      for (int d = 0; d < 3; ++d) hf(k, d) = m.fibers[order.position[k]][d];
    Kokkos::deep_copy(b.fibers, hf);
    b.spec = std::move(m);
    blocks_.push_back(std::move(b));
  }
}

void MuscleTerm::set_load(double t) {
  for (auto& b : blocks_) b.activation_now = b.spec.activation(t);
}

void MuscleTerm::add(const TermInput& in, TermOutput& out) const {
  const bool hex = mesh_.type == ElementType::Hex8;
  for (const Block& b : blocks_) {
    const int n = static_cast<int>(b.elements.extent(0));
    if (n == 0) {
      b.min_stretch = HUGE_VAL;
      b.max_stretch = -HUGE_VAL;
      continue;
    }
    auto fill = [&](auto& loop) {
      loop.law = b.spec.law;
      loop.activation = b.activation_now;
      // The fibre term's projection follows the run's choice for the elastic laws (clamp by default);
      // its exact Hessian is PSD (fiber.hpp), so every choice gives the same matrix here.
      loop.projection = in.projection.value_or(Projection::Clamp);
      loop.geometry = element_geometry(mesh_, elements_);
      loop.elements = b.elements;
      loop.fibers = b.fibers;
      loop.u = in.u;
      loop.target.matrix = out.matrix;
      loop.target.force = out.force;
      loop.target.owned_dofs = out.owned_dofs;
      loop.target.atomic = true;
      loop.want_force = in.want_force;
      loop.want_matrix = in.want_matrix;
    };
    FiberTotals t;
    if (hex) {
      FiberLoop<Hex8, detail::Target> loop;
      fill(loop);
      t = dispatch(loop, n, detail::Chunks{b.chunks, b.colour_begin}, in.backend);
    } else {
      FiberLoop<Tet4, detail::Target> loop;
      fill(loop);
      t = dispatch(loop, n, detail::Chunks{b.chunks, b.colour_begin}, in.backend);
    }
    out.energy += t.energy;
    b.min_stretch = t.min_stretch;
    b.max_stretch = t.max_stretch;
  }
}

std::array<double, 2> MuscleTerm::stretch_range(std::size_t m) const {
  // A rank holding none of the muscle's owned elements contributes the identities (+inf, -inf).
  const double mine[2] = {blocks_[m].min_stretch, -blocks_[m].max_stretch};
  double all[2];
  Teuchos::reduceAll(*comm_, Teuchos::REDUCE_MIN, 2, mine, all);  // both in one: max = -min(-x)
  return {all[0], -all[1]};
}

std::vector<std::string> MuscleTerm::log_columns() const {
  std::vector<std::string> c;
  for (const auto& b : blocks_)
    for (const char* what : {"activation_", "fiber_stretch_min_", "fiber_stretch_max_"}) c.push_back(what + b.spec.name);
  return c;
}

std::vector<double> MuscleTerm::log_values(const EvaluationTotals&) const {
  std::vector<double> v;
  for (std::size_t m = 0; m < blocks_.size(); ++m) {
    const auto r = stretch_range(m);
    v.insert(v.end(), {blocks_[m].activation_now, r[0], r[1]});
  }
  return v;
}

std::vector<std::string> MuscleTerm::summary(const EvaluationTotals&) const {
  std::vector<std::string> lines;
  for (std::size_t m = 0; m < blocks_.size(); ++m) {
    const auto r = stretch_range(m);
    std::ostringstream os;
    os.precision(3);
    os << "muscle " << blocks_[m].spec.name << ": activation " << blocks_[m].activation_now << ", fibre stretch " << r[0]
       << " .. " << r[1] << " (contraction limit " << blocks_[m].spec.law.limit << ")";
    lines.push_back(os.str());
  }
  return lines;
}

void MuscleTerm::element_fields(std::vector<TermState::Nodal>& fields) const {
  const std::size_t owned = mesh_.n_owned_elements;
  TermState::Nodal fiber{"fiber", 3, std::vector<double>(3 * owned, 0.0)}, act{"activation", 1, std::vector<double>(owned, 0.0)};
  for (const auto& b : blocks_)
    for (std::size_t k = 0; k < b.spec.elements.size(); ++k) {
      const auto e = static_cast<std::size_t>(b.spec.elements[k]);
      if (e >= owned) continue;
      for (int d = 0; d < 3; ++d) fiber.values[3 * e + d] = b.spec.fibers[k][d];
      act.values[e] = b.activation_now;
    }
  fields.push_back(std::move(fiber));
  fields.push_back(std::move(act));
}

}  // namespace sinew
