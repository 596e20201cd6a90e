// Muscles in a scene: regions of the mesh whose elements get fibres (a direction per element) and the
// fibre energy of materials/fiber.hpp on top of their isotropic law, with an activation in [0, 1] that
// follows the run (the load fraction t in [0, 1], as bones and prescribed motions do: the load steps
// of a quasi-static run, the time over the whole run of a dynamic one).
//
//   <ParameterList name="Muscles">
//     <ParameterList name="biceps">
//       <Parameter name="Region" type="string" value="group biceps"/>
//       <Parameter name="Fiber points" type="Array(double)" value="{0,0,0, 0,0,0.1, 0.01,0,0.25}"/>
//       <Parameter name="Maximum stress" type="double" value="3.0e5"/>
//       <Parameter name="Activation times" type="Array(double)" value="{0.0, 0.5, 1.0}"/>
//       <Parameter name="Activation values" type="Array(double)" value="{0.0, 1.0, 1.0}"/>
//     </ParameterList>
//   </ParameterList>
//
// Fibres: one constant 'Fiber direction'; or a line of action 'Fiber points' (a polyline: each element
// takes the direction of the segment nearest its centroid); or a 'Fiber file' (CSV lines 'element, x,
// y, z', the element as the mesh file numbers it, or the lattice's element id). Activation: a constant
// 'Activation' reached at the end of the run (ramped with t), keys ('Activation times', 'Activation
// values', linear between them and held beyond), an 'Activation file' (CSV lines 't, activation'), or a
// 'Line of action' between two bone points that fires the muscle as it shortens:
//   alpha(t) = clamp((L0 - L(t)) / (Shortening L0), 0, 1).
// No activation: a passive fibre (its stiffness only).
//
// The term is this file, the law (materials/fiber.hpp), the element loop (algebra/terms/muscle.hpp and
// src/algebra/muscle.cpp) and a line in term_registry.hpp.
#pragma once

#include <sinew/algebra/terms/muscle.hpp>
#include <sinew/core/collective.hpp>
#include <sinew/core/errors.hpp>
#include <sinew/core/xml_input.hpp>
#include <sinew/discretization/mesh_file.hpp>
#include <sinew/scenes/region.hpp>
#include <sinew/scenes/skeleton.hpp>
#include <sinew/scenes/term_kind.hpp>

#include <Teuchos_CommHelpers.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>

namespace sinew {

// Two points on bones (or fixed, with no bone) whose distance fires a muscle.
struct LineOfActionParameters {
  std::string origin_bone, insertion_bone;
  std::array<double, 3> origin{}, insertion{};
  double shortening = 0.2;

  template <class V>
  void visit(V& v) {
    v.entry("Origin bone", origin_bone, std::string(""), "the bone that carries the origin (empty: fixed in space)");
    v.entry("Origin", origin, {0.0, 0.0, 0.0}, "the origin at rest (reference coordinates)");
    v.entry("Insertion bone", insertion_bone, std::string(""), "the bone that carries the insertion (empty: fixed)");
    v.entry("Insertion", insertion, {0.0, 0.0, 0.0}, "the insertion at rest (reference coordinates)");
    v.entry("Shortening", shortening, 0.2,
            "the line's shortening, as a fraction of its rest length, at which the activation reaches 1 (it rises "
            "linearly from 0 at the rest length)",
            Range::open_closed(0.0, 1.0));
  }
  template <class Context>
  void check(const Context& c) const {
    double d2 = 0.0;
    for (int k = 0; k < 3; ++k) d2 += (insertion[k] - origin[k]) * (insertion[k] - origin[k]);
    if (!(d2 > 0.0)) c.fail("'Origin' and 'Insertion' must differ (a line of action needs a length)");
  }
};

struct MuscleParameters {
  std::string region, fiber_file, activation_file;
  std::optional<std::array<double, 3>> direction;
  std::vector<double> fiber_points, activation_times, activation_values;
  std::optional<double> activation;
  double stiffness = 0.0, max_stress = 0.0, limit = 0.0;
  LineOfActionParameters line;

  template <class V>
  void visit(V& v) {
    v.entry("Region", region, std::string(""),
            "the muscle's elements (required): all, or 'group NAME[, NAME]' (volume groups of the mesh file)");
    v.optional("Fiber direction", direction, "the fibres' direction at rest, the same in every element (normalized)");
    v.entry("Fiber points", fiber_points, std::vector<double>{},
            "a polyline x0, y0, z0, x1, y1, z1, ... (at least two points): each element's fibre runs along the segment "
            "nearest its centroid");
    v.entry("Fiber file", fiber_file, std::string(""),
            "CSV lines 'element, x, y, z': each element's fibre direction (every element of the region; a relative path "
            "is taken from the scene file's folder)");
    v.entry("Fiber stiffness", stiffness, 0.0,
            "k of the passive fibre energy k/2 (lambda - 1)^2 in stretch (lambda > 1), in stress units (0: the isotropic "
            "law alone resists)",
            Range::non_negative());
    v.entry("Maximum stress", max_stress, 3.0e5,
            "sigma: the active fibre stress at full activation, at and beyond the rest length (a skeletal muscle's peak "
            "isometric stress is about 0.3 MPa)",
            Range::non_negative());
    v.entry("Contraction limit", limit, 0.6,
            "lambda_min: the fibre stretch at which the active stress has fallen to 0 (a smoothstep from the rest "
            "length): an activated muscle shortens towards it and never past it",
            Range::open(0.0, 1.0));
    v.optional("Activation", activation, "a constant activation reached at the end of the run, ramped with the load",
               Range::closed(0.0, 1.0));
    v.entry("Activation times", activation_times, std::vector<double>{},
            "the load fractions of activation keys, increasing in [0, 1] (with 'Activation values')", Range::closed(0.0, 1.0));
    v.entry("Activation values", activation_values, std::vector<double>{}, "the activation at each key, in [0, 1]",
            Range::closed(0.0, 1.0));
    v.entry("Activation file", activation_file, std::string(""),
            "CSV lines 't, activation' (t the load fraction, increasing), instead of keys (a relative path is taken from "
            "the scene file's folder)");
    v.section("Line of action", line, "an activation from the shortening of a line between two bone points");
  }
  template <class Context>
  void check(const Context& c) const {
    if (region.empty()) c.fail("missing entry 'Region'", InputErrorKind::MissingEntry);
    if (region != "all" && region.rfind("group ", 0) != 0)
      c.fail("'Region' must be all or 'group NAME[, NAME]' (volume groups), got \"" + region + "\"");
    const int fibres = (direction ? 1 : 0) + (c.given("Fiber points") ? 1 : 0) + (c.given("Fiber file") ? 1 : 0);
    if (fibres == 0)
      c.fail("a muscle needs its fibres: give 'Fiber direction', 'Fiber points' or 'Fiber file'", InputErrorKind::MissingEntry);
    if (fibres > 1) c.fail("give one of 'Fiber direction', 'Fiber points', 'Fiber file'");
    if (direction && !((*direction)[0] * (*direction)[0] + (*direction)[1] * (*direction)[1] + (*direction)[2] * (*direction)[2] > 0.0))
      c.fail("'Fiber direction' must be a non-zero vector");
    if (c.given("Fiber points")) {
      if (fiber_points.size() % 3 != 0 || fiber_points.size() < 6)
        c.fail("'Fiber points' needs at least two points, three numbers each; got " + std::to_string(fiber_points.size()) +
               " numbers");
      for (std::size_t k = 3; k < fiber_points.size(); k += 3) {
        double d2 = 0.0;
        for (int d = 0; d < 3; ++d) d2 += (fiber_points[k + d] - fiber_points[k - 3 + d]) * (fiber_points[k + d] - fiber_points[k - 3 + d]);
        if (!(d2 > 0.0)) c.fail("'Fiber points' " + std::to_string(k / 3 - 1) + " and " + std::to_string(k / 3) + " coincide");
      }
    }
    const bool keys = c.given("Activation times") || c.given("Activation values");
    const int sources = (activation ? 1 : 0) + (keys ? 1 : 0) + (c.given("Activation file") ? 1 : 0) + (c.given("Line of action") ? 1 : 0);
    if (sources > 1) c.fail("give one of 'Activation', 'Activation times' and 'Activation values', 'Activation file', 'Line of action'");
    if (keys) {
      if (activation_times.size() != activation_values.size() || activation_times.empty())
        c.fail("'Activation times' and 'Activation values' need the same number of entries (at least one); got " +
               std::to_string(activation_times.size()) + " and " + std::to_string(activation_values.size()));
      for (std::size_t k = 1; k < activation_times.size(); ++k)
        if (!(activation_times[k] > activation_times[k - 1])) c.fail("'Activation times' must increase");
    }
  }
};

struct MusclesParameters {
  NamedSections<MuscleParameters> muscles;

  template <class V>
  void visit(V& v) {
    v.other_sublists(muscles, "one sublist per muscle, named as you like (Region, fibres, law, activation)");
  }
};

namespace muscle_detail {

// Piecewise linear through (t_k, a_k), held beyond the ends.
inline double interpolate(const std::vector<double>& t, const std::vector<double>& a, double x) {
  if (x <= t.front()) return a.front();
  if (x >= t.back()) return a.back();
  const std::size_t k = static_cast<std::size_t>(std::upper_bound(t.begin(), t.end(), x) - t.begin());
  const double s = (x - t[k - 1]) / (t[k] - t[k - 1]);
  return (1.0 - s) * a[k - 1] + s * a[k];
}

// The numbers of each line of a CSV file (a first line that is not numbers is a header); throws
// InputError naming the file and the line when a line has not `columns` numbers.
inline std::vector<std::vector<double>> read_csv(const std::string& path, std::size_t columns, const std::string& where) {
  std::ifstream in(path);
  if (!in) throw InputError(where + ": cannot read '" + path + "'", InputErrorKind::File);
  std::vector<std::vector<double>> rows;
  int line_no = 0;
  for (std::string line; std::getline(in, line);) {
    ++line_no;
    if (line.find_first_not_of(" \t\r") == std::string::npos || line[line.find_first_not_of(" \t")] == '#') continue;
    std::replace(line.begin(), line.end(), ',', ' ');
    std::istringstream ss(line);
    std::vector<std::string> items;
    for (std::string item; ss >> item;) items.push_back(item);
    // A first line of words is a header; otherwise every item is a number as the motion file and the
    // XML take them (core/xml_input.hpp: plain decimal, finite).
    const auto is_word = [](const std::string& s) {
      char* end = nullptr;
      std::strtod(s.c_str(), &end);
      return end == s.c_str() || *end != '\0';
    };
    if (line_no == 1 && std::any_of(items.begin(), items.end(), is_word)) continue;
    const std::string at = where + ": '" + path + "' line " + std::to_string(line_no) + ": ";
    if (items.size() != columns) throw InputError(at + "expected " + std::to_string(columns) + " numbers");
    std::vector<double> row;
    for (const std::string& item : items) {
      if (!strict_number(item, false)) throw InputError(at + "'" + item + "' is not a finite number");
      row.push_back(std::strtod(item.c_str(), nullptr));
    }
    rows.push_back(std::move(row));
  }
  if (rows.empty()) throw InputError(where + ": '" + path + "' holds no line of numbers", InputErrorKind::File);
  return rows;
}

// The muscle's local elements (owned and ghost).
inline std::vector<int> elements_of(const Mesh& mesh, const std::string& region, const std::string& where) {
  std::vector<int> out;
  const std::size_t ne = mesh.local_elements();
  if (region == "all") {
    for (std::size_t e = 0; e < ne; ++e) out.push_back(static_cast<int>(e));
    return out;
  }
  std::vector<int> groups;
  RegionParameters names;  // its 'group NAME, NAME' syntax, as boundary conditions read it
  names.region = region;
  for (const std::string& name : names.groups()) {
    const auto& eg = mesh.element_group_names;
    const auto it = std::find(eg.begin(), eg.end(), name);
    if (it == eg.end()) throw unknown_group(where + ": 'Region'", name, {}, eg);
    groups.push_back(static_cast<int>(it - eg.begin()));
  }
  for (std::size_t e = 0; e < ne; ++e)
    if (std::any_of(groups.begin(), groups.end(), [&](int g) { return mesh.in_group(e, g); })) out.push_back(static_cast<int>(e));
  return out;
}

inline std::array<double, 3> unit(std::array<double, 3> v) {
  const double n = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  for (double& x : v) x /= n;
  return v;
}

// Each element's unit fibre (the same on every rank for an element several ranks hold).
inline std::vector<std::array<double, 3>> fibres_of(const Mesh& mesh, const MuscleParameters& p, const std::vector<int>& elements,
                                                    const std::string& where) {
  std::vector<std::array<double, 3>> out;
  if (p.direction) {
    out.assign(elements.size(), unit(*p.direction));
    return out;
  }
  if (!p.fiber_file.empty()) {
    std::map<long long, std::array<double, 3>> given;
    for (const auto& row : read_csv(p.fiber_file, 4, where + ": 'Fiber file'")) {
      const std::array<double, 3> v{row[1], row[2], row[3]};
      if (!(v[0] * v[0] + v[1] * v[1] + v[2] * v[2] > 0.0))
        throw InputError(where + ": 'Fiber file' '" + p.fiber_file + "': element " + std::to_string(static_cast<long long>(row[0])) +
                         " has a zero fibre direction");
      given[static_cast<long long>(row[0])] = unit(v);
    }
    for (int e : elements) {
      const auto it = given.find(mesh.element_label(e));
      if (it == given.end())
        throw InputError(where + ": 'Fiber file' '" + p.fiber_file + "' gives no fibre for element " +
                         std::to_string(mesh.element_label(e)) + " of the region", InputErrorKind::MissingEntry);
      out.push_back(it->second);
    }
    return out;
  }
  // The polyline: the segment nearest each element's centroid.
  auto X = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.X);
  auto conn = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.conn);
  const int npe = nodes_per_element(mesh.type);
  const auto& P = p.fiber_points;
  for (int e : elements) {
    double c[3] = {0.0, 0.0, 0.0};
    for (int a = 0; a < npe; ++a)
      for (int d = 0; d < 3; ++d) c[d] += X(conn(e, a), d) / npe;
    double best = HUGE_VAL;
    std::array<double, 3> dir{};
    for (std::size_t k = 3; k < P.size(); k += 3) {
      const std::array<double, 3> a{P[k - 3], P[k - 2], P[k - 1]}, b{P[k], P[k + 1], P[k + 2]};
      const double d = segment_distance(c, a, b);
      if (d < best) {
        best = d;
        dir = unit({b[0] - a[0], b[1] - a[1], b[2] - a[2]});
      }
    }
    out.push_back(dir);
  }
  return out;
}

// The activation as a function of the load fraction.
inline std::function<double(double)> activation_of(const MuscleParameters& p, const Skeleton& skeleton, const std::string& where,
                                                   bool line) {
  if (p.activation) {
    const double a = *p.activation;
    return [a](double t) { return std::clamp(a * t, 0.0, 1.0); };
  }
  if (!p.activation_times.empty()) {
    const auto t = p.activation_times, a = p.activation_values;
    return [t, a](double x) { return interpolate(t, a, x); };
  }
  if (!p.activation_file.empty()) {
    std::vector<double> t, a;
    int k = 0;
    for (const auto& row : read_csv(p.activation_file, 2, where + ": 'Activation file'")) {
      ++k;
      if (!t.empty() && !(row[0] > t.back()))
        throw InputError(where + ": 'Activation file' '" + p.activation_file + "': times must increase (row " + std::to_string(k) + ")");
      if (!(row[1] >= 0.0 && row[1] <= 1.0))
        throw InputError(where + ": 'Activation file' '" + p.activation_file + "': activation " + std::to_string(row[1]) +
                         " at row " + std::to_string(k) + " lies outside [0, 1]");
      t.push_back(row[0]);
      a.push_back(row[1]);
    }
    return [t, a](double x) { return interpolate(t, a, x); };
  }
  if (line) {
    auto bone = [&](const std::string& name) -> int {
      if (name.empty()) return -1;
      std::vector<std::string> names;
      for (std::size_t b = 0; b < skeleton.size(); ++b) {
        if (skeleton.name(b) == name) return static_cast<int>(b);
        names.push_back(skeleton.name(b));
      }
      std::string msg = where + ": 'Line of action': no bone \"" + name + "\"";
      msg += names.empty() ? " (the scene has no Skeleton)" : "; bones: " + or_list(names);
      throw InputError(msg);
    };
    const int bo = bone(p.line.origin_bone), bi = bone(p.line.insertion_bone);
    const auto o = p.line.origin, q = p.line.insertion;
    const double s = p.line.shortening;
    const Skeleton* sk = &skeleton;
    auto length = [sk, bo, bi, o, q](double t) {
      const auto a = bo < 0 ? o : sk->transform(bo, t).apply(o);
      const auto b = bi < 0 ? q : sk->transform(bi, t).apply(q);
      return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
    };
    const double L0 = length(0.0);
    return [length, L0, s](double t) { return std::clamp((L0 - length(t)) / (s * L0), 0.0, 1.0); };
  }
  return [](double) { return 0.0; };
}

}  // namespace muscle_detail

struct Muscles {
  using Parameters = MusclesParameters;
  static constexpr const char* section = "Muscles";
  static constexpr const char* doc =
      "muscles: fibres in regions of the mesh, a passive fibre stiffness and an active stress scaled by an activation";
  static bool active(const Parameters& p) { return !p.muscles.empty(); }
  static void resolve_paths(Parameters& p, const std::function<void(std::string&)>& resolve) {
    for (auto& [name, m] : p.muscles) {
      resolve(m.fiber_file);
      resolve(m.activation_file);
    }
  }

  // Collective. Throws InputError naming the muscle whose region holds no element, whose fibre file
  // misses one of its elements, or whose line of action names an unknown bone.
  static std::shared_ptr<EnergyTerm> make(const Parameters& p, const TermContext& c) {
    const System& sys = c.system;
    const Mesh& mesh = sys.mesh();
    std::vector<MuscleBlock> blocks;
    for (const auto& [name, m] : p.muscles) {
      const std::string where = "Muscles/" + name;
      MuscleBlock b;
      b.name = name;
      b.law.stiffness = m.stiffness;
      b.law.max_stress = m.max_stress;
      b.law.limit = m.limit;
      collectively(raw_comm(c.comm), [&] {
        b.elements = muscle_detail::elements_of(mesh, m.region, where);
        b.fibers = muscle_detail::fibres_of(mesh, m, b.elements, where);
        // A given line of action has distinct ends (its check); an absent one keeps both at the origin.
        b.activation = muscle_detail::activation_of(m, c.skeleton, where, m.line.origin != m.line.insertion);
      });
      long long mine = 0, all = 0;
      for (int e : b.elements) mine += static_cast<std::size_t>(e) < mesh.n_owned_elements;
      Teuchos::reduceAll(c.comm, Teuchos::REDUCE_SUM, mine, Teuchos::outArg(all));
      if (all == 0) throw InputError(where + ": region \"" + m.region + "\" holds no element", InputErrorKind::EmptyRegion);
      blocks.push_back(std::move(b));
    }
    return std::make_shared<MuscleTerm>(sys.comm(), mesh, sys.element_data(), std::move(blocks));
  }
};

}  // namespace sinew
