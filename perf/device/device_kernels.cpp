// Sinew's material and element kernels on every Kokkos execution space compiled in (Cuda, OpenMP,
// Serial), from the same headers the solver uses (materials/, discretization/element_kernel.hpp,
// local_csr.hpp: Kokkos only, no Trilinos), in one program:
//
//   device_kernels --test   every model x {hex8, tet4} x {per element, per point}: energy, force and
//                           stiffness values of each space against Serial per element, to 1e-12
//                           relative; exit 1 on a mismatch
//   device_kernels --bench  materials per second (energy + PK1 + projected Hessian) per model, and
//                           elements per second (energy + force + stiffness, atomic CSR scatter) per
//                           element type, on each space, with the device named
//
// Built two ways: by the normal build against Trilinos' Kokkos (host spaces; CI runs --test), and by
// perf/device/CMakeLists.txt with nvcc against the standalone CUDA Kokkos of ../shared/deps (CI
// compiles it; it runs where a GPU is lent: docs/device.md).
#include <sinew/discretization/element_kernel.hpp>
#include <sinew/discretization/local_csr.hpp>
#include <sinew/materials/models.hpp>

#include <Kokkos_Core.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <set>
#include <string>
#include <vector>

using namespace sinew;

namespace {

// ---- a jittered box of n^3 hex8 cells, or 6 tet4 per cell, with its geometry and CSR graph --------
struct HostMesh {
  int nodes = 0, elements = 0, npe = 0;
  std::vector<double> X;  // 3 per node
  std::vector<int> conn;
  std::vector<int> row_map, entries;  // DOF graph
};

double jitter(int i, int d) { return 0.15 * (std::sin(12.9898 * i + 78.233 * d) * 0.5); }

HostMesh make_box(int n, bool tets) {
  HostMesh m;
  const int p = n + 1;
  m.nodes = p * p * p;
  m.X.resize(3 * m.nodes);
  for (int k = 0; k < p; ++k)
    for (int j = 0; j < p; ++j)
      for (int i = 0; i < p; ++i) {
        const int a = i + p * (j + p * k);
        const bool inside = i > 0 && i < n && j > 0 && j < n && k > 0 && k < n;
        const int ijk[3] = {i, j, k};
        for (int d = 0; d < 3; ++d) m.X[3 * a + d] = (ijk[d] + (inside ? jitter(a, d) : 0.0)) / n;
      }
  auto node = [&](int i, int j, int k) { return i + p * (j + p * k); };
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const int h[8] = {node(i, j, k),         node(i + 1, j, k),         node(i + 1, j + 1, k),         node(i, j + 1, k),
                          node(i, j, k + 1),     node(i + 1, j, k + 1),     node(i + 1, j + 1, k + 1),     node(i, j + 1, k + 1)};
        if (!tets) {
          m.conn.insert(m.conn.end(), h, h + 8);
          continue;
        }
        // Six tets around the 0-6 diagonal (Kuhn), each made positively oriented.
        const int paths[6][2] = {{1, 2}, {2, 3}, {3, 7}, {7, 4}, {4, 5}, {5, 1}};
        for (const auto& q : paths) {
          int t[4] = {h[0], h[q[0]], h[q[1]], h[6]};
          double e[3][3];
          for (int r = 0; r < 3; ++r)
            for (int d = 0; d < 3; ++d) e[r][d] = m.X[3 * t[r + 1] + d] - m.X[3 * t[0] + d];
          const double v = e[0][0] * (e[1][1] * e[2][2] - e[1][2] * e[2][1]) - e[0][1] * (e[1][0] * e[2][2] - e[1][2] * e[2][0]) +
                           e[0][2] * (e[1][0] * e[2][1] - e[1][1] * e[2][0]);
          if (v < 0) std::swap(t[1], t[2]);
          m.conn.insert(m.conn.end(), t, t + 4);
        }
      }
  m.npe = tets ? 4 : 8;
  m.elements = static_cast<int>(m.conn.size()) / m.npe;
  std::vector<std::set<int>> adj(m.nodes);
  for (int e = 0; e < m.elements; ++e)
    for (int a = 0; a < m.npe; ++a)
      for (int b = 0; b < m.npe; ++b) adj[m.conn[m.npe * e + a]].insert(m.conn[m.npe * e + b]);
  m.row_map.push_back(0);
  for (int a = 0; a < m.nodes; ++a)
    for (int i = 0; i < 3; ++i) {
      for (int b : adj[a])
        for (int j = 0; j < 3; ++j) m.entries.push_back(3 * b + j);
      m.row_map.push_back(static_cast<int>(m.entries.size()));
    }
  return m;
}

// dN/dX and w det J per quadrature point, from the reference element's gradients.
template <class Element>
void geometry(const HostMesh& m, std::vector<double>& dNdX, std::vector<double>& wdetJ) {
  constexpr int NPE = Element::nodes, Q = Element::points;
  dNdX.assign(static_cast<std::size_t>(m.elements) * Q * NPE * 3, 0.0);
  wdetJ.assign(static_cast<std::size_t>(m.elements) * Q, 0.0);
  for (int e = 0; e < m.elements; ++e)
    for (int q = 0; q < Q; ++q) {
      double dN[NPE][3];
      Element::gradients(q, dN);
      Mat3 Jm;  // dX/dxi
      for (int i = 0; i < 3; ++i)
        for (int d = 0; d < 3; ++d) {
          double s = 0.0;
          for (int a = 0; a < NPE; ++a) s += m.X[3 * m.conn[NPE * e + a] + i] * dN[a][d];
          Jm(i, d) = s;
        }
      const double dJ = det(Jm);
      // inverse by cofactors: (J^-1)_{d i}
      Mat3 inv;
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) {
          const int r1 = (c + 1) % 3, r2 = (c + 2) % 3, c1 = (r + 1) % 3, c2 = (r + 2) % 3;
          inv(r, c) = (Jm(r1, c1) * Jm(r2, c2) - Jm(r1, c2) * Jm(r2, c1)) / dJ;
        }
      const std::size_t pq = static_cast<std::size_t>(e) * Q + q;
      wdetJ[pq] = Element::weight(q) * dJ;
      for (int a = 0; a < NPE; ++a)
        for (int J = 0; J < 3; ++J) {
          double s = 0.0;
          for (int d = 0; d < 3; ++d) s += dN[a][d] * inv(d, J);
          dNdX[(pq * NPE + a) * 3 + J] = s;
        }
    }
}

template <class View, class T>
View to_view(const std::string& name, const std::vector<T>& v) {
  typename View::HostMirror h(name, v.size());
  std::memcpy(h.data(), v.data(), v.size() * sizeof(T));
  View d(name, v.size());
  Kokkos::deep_copy(d, h);
  return d;
}

template <class T, class V>
std::vector<T> to_host(const V& v) {
  auto h = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), v);
  return std::vector<T>(h.data(), h.data() + h.size());
}

struct AssemblyResult {
  AssemblyTotals totals;
  std::vector<double> force, values;
  double seconds = 0.0;  // per assembly, best of the repetitions
};

// One space, one model, one element type: the element loop, `reps` times.
enum class Variant { PerElement, PerPoint };

template <class Exec, class Element, class Model>
AssemblyResult assemble(const Model& model, const HostMesh& m, const std::vector<double>& u_host, int reps,
                        Variant variant = Variant::PerElement) {
  using Mem = typename Exec::memory_space;
  std::vector<double> dNdX_h, wdetJ_h;
  geometry<Element>(m, dNdX_h, wdetJ_h);
  // The views' default layouts (LayoutLeft on a GPU): filled through mirrors, index by index.
  Kokkos::View<int**, Mem> conn("conn", m.elements, Element::nodes);
  Kokkos::View<double***, Mem> dNdX("dNdX", static_cast<std::size_t>(m.elements) * Element::points, Element::nodes, 3);
  {
    auto c = Kokkos::create_mirror_view(conn);
    for (int e = 0; e < m.elements; ++e)
      for (int a = 0; a < Element::nodes; ++a) c(e, a) = m.conn[Element::nodes * e + a];
    Kokkos::deep_copy(conn, c);
    auto h = Kokkos::create_mirror_view(dNdX);
    for (std::size_t pq = 0; pq < dNdX.extent(0); ++pq)
      for (int a = 0; a < Element::nodes; ++a)
        for (int J = 0; J < 3; ++J) h(pq, a, J) = dNdX_h[(pq * Element::nodes + a) * 3 + J];
    Kokkos::deep_copy(dNdX, h);
  }
  ElementGeometry<Mem> g;
  g.conn = conn;
  g.dNdX = dNdX;
  g.wdetJ = to_view<Kokkos::View<double*, Mem>>("wdetJ", wdetJ_h);
  g.n_owned = m.elements;
  std::vector<int> ids(m.elements);
  for (int e = 0; e < m.elements; ++e) ids[e] = e;
  LocalCsr<Mem> A;
  A.row_map = to_view<Kokkos::View<int*, Mem>>("row_map", m.row_map);
  A.entries = to_view<Kokkos::View<int*, Mem>>("entries", m.entries);
  A.values = Kokkos::View<double*, Mem>("values", m.entries.size());
  Kokkos::View<double*, Mem> force("force", 3 * m.nodes);
  using Target = CrsTarget<LocalCsr<Mem>, Kokkos::View<double*, Mem>>;
  auto setup = [&](auto& loop) {
    loop.model = model;
    loop.projection = Projection::Clamp;
    loop.geometry = g;
    loop.elements = to_view<Kokkos::View<int*, Mem>>("elements", ids);
    loop.u = to_view<Kokkos::View<double*, Mem>>("u", u_host);
    loop.target = Target{A, force, 3 * m.nodes};
    loop.want_force = loop.want_matrix = true;
  };
  ElementLoop<Element, Model, Target> per_element;
  PointLoop<Element, Model, Target> per_point;
  setup(per_element);
  setup(per_point);
  AssemblyResult r;
  r.seconds = HUGE_VAL;
  for (int k = 0; k < reps; ++k) {
    Kokkos::deep_copy(A.values, 0.0);
    Kokkos::deep_copy(force, 0.0);
    Exec().fence();
    const auto t0 = std::chrono::steady_clock::now();
    if (variant == Variant::PerElement)
      Kokkos::parallel_reduce("sinew_element_loop", Kokkos::RangePolicy<Exec>(0, m.elements), per_element, r.totals);
    else
      Kokkos::parallel_reduce("sinew_point_loop", Kokkos::RangePolicy<Exec>(0, per_point.work_items()), per_point, r.totals);
    Exec().fence();
    r.seconds = std::min(r.seconds, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  r.force = to_host<double>(force);
  r.values = to_host<double>(A.values);
  return r;
}

// Energy + PK1 + projected Hessian at a spread of deformation gradients (a fifth inverted).
template <class Model, class Mem>
struct MaterialEval {
  Model model;
  Kokkos::View<double*, Mem> out;
  KOKKOS_INLINE_FUNCTION void operator()(const int i) const {
    const double a = 0.6 + 0.8 * ((i * 37) % 101) / 100.0, b = 0.2 * (((i * 53) % 97) / 96.0 - 0.5);
    Mat3 F = Mat3::diag(a, 1.0 / std::sqrt(a), (i % 5 == 0 ? -1.0 : 1.0) / std::sqrt(a));
    F(0, 1) = b;
    F(1, 2) = -b;
    const Mat3 P = model.pk1(F);
    const Mat9 H = model.projected_hessian(F, Projection::Clamp);
    out(i) = model.energy(F) + P[0] + H.a[0] + H.a[80];
  }
};

template <class Exec, class Model>
double material_rate(const Model& model, int n, int reps) {
  using Mem = typename Exec::memory_space;
  MaterialEval<Model, Mem> f{model, Kokkos::View<double*, Mem>("out", n)};
  double best = HUGE_VAL;
  for (int k = 0; k < reps; ++k) {
    Exec().fence();
    const auto t0 = std::chrono::steady_clock::now();
    Kokkos::parallel_for("sinew_material_eval", Kokkos::RangePolicy<Exec>(0, n), f);
    Exec().fence();
    best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  return n / best;
}

double rel(const std::vector<double>& a, const std::vector<double>& b) {
  double d = 0.0, s = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    d = std::max(d, std::fabs(a[i] - b[i]));
    s = std::max(s, std::fabs(b[i]));
  }
  return a.size() == b.size() ? d / std::max(s, 1e-300) : HUGE_VAL;
}

MaterialSpec spec_of(std::size_t k) {
  MaterialSpec spec = material_defaults(static_cast<MaterialModel>(k), 1.0, 24.5);  // nu = 0.49
  options_of<StVKKikuuwe>(spec).kappa = 1e4;
  return spec;
}

std::vector<double> displacement(const HostMesh& m) {
  // A twist and a squeeze, enough to invert a few elements of the coarse box.
  std::vector<double> u(3 * m.nodes);
  for (int a = 0; a < m.nodes; ++a) {
    const double x = m.X[3 * a] - 0.5, y = m.X[3 * a + 1] - 0.5, z = m.X[3 * a + 2];
    const double t = 1.2 * z, c = std::cos(t), s = std::sin(t);
    u[3 * a] = c * x - s * y - x + 0.2 * std::sin(7.0 * a);
    u[3 * a + 1] = s * x + c * y - y + 0.1 * std::cos(5.0 * a);
    u[3 * a + 2] = -0.3 * z * z + 0.15 * std::sin(3.0 * a);
  }
  return u;
}

struct SpaceRun {
  std::string name;
  AssemblyResult (*hex)(const MaterialSpec&, const HostMesh&, const std::vector<double>&, int, Variant);
  AssemblyResult (*tet)(const MaterialSpec&, const HostMesh&, const std::vector<double>&, int, Variant);
  double (*material)(const MaterialSpec&, int, int);
  int concurrency;
};

template <class Exec>
SpaceRun space_run(const std::string& name) {
  SpaceRun s;
  s.name = name;
  s.hex = [](const MaterialSpec& sp, const HostMesh& m, const std::vector<double>& u, int reps, Variant v) {
    return with_material(sp, [&](const auto& model) { return assemble<Exec, Hex8>(model, m, u, reps, v); });
  };
  s.tet = [](const MaterialSpec& sp, const HostMesh& m, const std::vector<double>& u, int reps, Variant v) {
    return with_material(sp, [&](const auto& model) { return assemble<Exec, Tet4>(model, m, u, reps, v); });
  };
  s.material = [](const MaterialSpec& sp, int n, int reps) {
    return with_material(sp, [&](const auto& model) { return material_rate<Exec>(model, n, reps); });
  };
  s.concurrency = Exec().concurrency();
  return s;
}

std::vector<SpaceRun> spaces() {
  std::vector<SpaceRun> s;
#ifdef KOKKOS_ENABLE_SERIAL
  s.push_back(space_run<Kokkos::Serial>("Serial"));  // first: the reference
#endif
#ifdef KOKKOS_ENABLE_OPENMP
  s.push_back(space_run<Kokkos::OpenMP>("OpenMP"));
#endif
#ifdef KOKKOS_ENABLE_CUDA
  s.push_back(space_run<Kokkos::Cuda>("Cuda"));
#endif
  return s;
}

std::string device_name() {
#ifdef KOKKOS_ENABLE_CUDA
  cudaDeviceProp p;
  if (cudaGetDeviceProperties(&p, Kokkos::Cuda().cuda_device()) == cudaSuccess) return p.name;
#endif
  return "none (host spaces only)";
}

int test(int cells) {
  const auto S = spaces();
  int failures = 0;
  double worst = 0.0;
  for (const bool tets : {false, true}) {
    const HostMesh m = make_box(cells, tets);
    const auto u = displacement(m);
    for (std::size_t k = 0; k < material_model_names().size(); ++k) {
      const MaterialSpec sp = spec_of(k);
      AssemblyResult ref;
      for (std::size_t s = 0; s < S.size(); ++s)
        for (const Variant v : {Variant::PerElement, Variant::PerPoint}) {
          const AssemblyResult r = tets ? S[s].tet(sp, m, u, 1, v) : S[s].hex(sp, m, u, 1, v);
          if (s == 0 && v == Variant::PerElement) {
            ref = r;
            if (r.totals.inverted == 0) {  // the inverted branch of every model must be exercised
              std::printf("FAIL %s %s: the test state should have inverted points (energy %g)\n", material_model_names()[k].c_str(),
                          tets ? "tet4" : "hex8", r.totals.energy);
              ++failures;
            }
            continue;
          }
          // Neo-Hookean's energy is +inf at inverted points, on every space alike.
          const bool both_inf = std::isinf(r.totals.energy) && std::isinf(ref.totals.energy);
          const double de =
              both_inf ? 0.0 : std::fabs(r.totals.energy - ref.totals.energy) / std::max(std::fabs(ref.totals.energy), 1e-300);
          const double dv = std::fabs(r.totals.volume - ref.totals.volume) / ref.totals.volume;
          const double df = rel(r.force, ref.force), dK = rel(r.values, ref.values);
          // nvcc contracts a*b+c into FMAs where the host compiler does not: min J differs in the last
          // bits, so it is compared like everything else, relative to its size.
          const double dJ = std::fabs(r.totals.min_J - ref.totals.min_J) / std::max(std::fabs(ref.totals.min_J), 1e-300);
          const double d = std::max({de, dv, df, dK, dJ});
          worst = std::max(worst, d);
          const bool ok = d < 1e-12 && r.totals.inverted == ref.totals.inverted;
          failures += !ok;
          const std::string what = std::string(tets ? "tet4 " : "hex8 ") + S[s].name + (v == Variant::PerPoint ? " per point" : "");
          std::printf("%s %-28s %-22s vs Serial: energy %.1e volume %.1e force %.1e matrix %.1e min J %.1e inverted %lld/%lld\n",
                      ok ? "ok  " : "FAIL", material_model_names()[k].c_str(), what.c_str(), de, dv, df, dK, dJ, r.totals.inverted,
                      ref.totals.inverted);
        }
    }
  }
  std::printf("%s: %d mismatches; largest relative difference %.2e (limit 1e-12); spaces:", failures ? "FAILED" : "PASSED",
              failures, worst);
  for (const auto& s : S) std::printf(" %s", s.name.c_str());
  std::printf("; device: %s\n", device_name().c_str());
  return failures ? 1 : 0;
}

int bench(int cells, int points, int reps) {
  const auto S = spaces();
  std::printf("device: %s\n", device_name().c_str());
  for (const auto& s : S) std::printf("space %s: concurrency %d\n", s.name.c_str(), s.concurrency);
  std::printf("\nmaterials per second (energy + PK1 + projected Hessian), %d points, best of %d\n", points, reps);
  std::printf("%-28s", "model");
  for (const auto& s : S) std::printf(" %14s", s.name.c_str());
  std::printf("\n");
  for (std::size_t k = 0; k < material_model_names().size(); ++k) {
    std::printf("%-28s", material_model_names()[k].c_str());
    for (const auto& s : S) std::printf(" %14.4g", s.material(spec_of(k), points, reps));
    std::printf("\n");
  }
  const MaterialSpec snh = spec_of(0);
  for (const bool tets : {false, true}) {
    const HostMesh m = make_box(cells, tets);
    const auto u = displacement(m);
    std::printf("\n%s elements per second (stable-neohookean: energy + force + 24x24/12x12 stiffness, atomic CSR scatter), "
                "%d elements, best of %d\n", tets ? "tet4" : "hex8", m.elements, reps);
    double base = 0.0;
    for (const auto& s : S)
      for (const Variant v : {Variant::PerElement, Variant::PerPoint}) {
        const AssemblyResult r = tets ? s.tet(snh, m, u, reps, v) : s.hex(snh, m, u, reps, v);
        const double rate = m.elements / r.seconds;
        if (base == 0.0) base = rate;
        std::printf("  %-8s %-11s %12.4g elements/s  (%.2fx Serial per element)\n", s.name.c_str(),
                    v == Variant::PerElement ? "per element" : "per point", rate, rate / base);
      }
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Kokkos::ScopeGuard kokkos(argc, argv);
  std::string mode = "--test";
  int cells = 0, points = 1 << 20, reps = 5;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--test" || a == "--bench")
      mode = a;
    else if (a == "--cells" && i + 1 < argc)
      cells = std::atoi(argv[++i]);
    else if (a == "--points" && i + 1 < argc)
      points = std::atoi(argv[++i]);
    else if (a == "--reps" && i + 1 < argc)
      reps = std::atoi(argv[++i]);
    else if (a.rfind("--kokkos", 0) != 0) {
      std::fprintf(stderr, "usage: device_kernels [--test | --bench] [--cells N] [--points N] [--reps N]\n");
      return 2;
    }
  }
  if (cells < 1) cells = mode == "--test" ? 4 : 40;
  if (points < 1 || reps < 1) {
    std::fprintf(stderr, "device_kernels: --points and --reps must be positive\n");
    return 2;
  }
  return mode == "--test" ? test(cells) : bench(cells, points, reps);
}
