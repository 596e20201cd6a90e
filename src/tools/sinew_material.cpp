// sinew-material: the response of one material point along a load path, as CSV.
//
// Paths: uniaxial (stress-free lateral faces: the lateral stretch minimizes the energy, P_yy = P_zz = 0),
// shear (simple shear F = I + g e_x e_y^T), hydrostatic (F = s I, from 1 down through inversion),
// F (one user-given deformation gradient).
#include <sinew/core/errors.hpp>
#include <sinew/core/exit_codes.hpp>
#include <sinew/core/xml_input.hpp>
#include <sinew/materials/parameters.hpp>

#include <Kokkos_Core.hpp>
#include <Teuchos_ParameterList.hpp>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

using namespace sinew;

namespace {

const char* kUsage =
    "usage: sinew-material [options]\n"
    "  --model NAME        material model (default stable-neohookean); --list shows all\n"
    "  --E VALUE           Young's modulus (default 1e5)\n"
    "  --nu VALUE          Poisson's ratio (default 0.45)\n"
    "  --projection P      none | clamp | abs (default clamp)\n"
    "  --param KEY=VALUE   any other 'Material' entry, e.g. --param 'Fung exponent=2'\n"
    "  --path P            uniaxial | shear | hydrostatic | F (default uniaxial)\n"
    "  --min X --max X     range of the load parameter (stretch, shear, or scale)\n"
    "  --steps N           number of intervals (default 48)\n"
    "  --F a,b,c,...       nine entries of F, row by row (with --path F)\n"
    "  --output FILE       write the CSV there instead of stdout\n"
    "  --plot FILE.png     also plot J and the smallest Hessian eigenvalues (needs python3-matplotlib)\n"
    "CSV columns: stretch,J,psi,P00..P22 (row-major),lateral,min_eig_raw,min_eig_projected\n";

// Smallest eigenvalue of a symmetric 9x9 matrix (Jacobi).
double min_eig(Mat9 H) {
  double ev[9], Q[81];
  jacobi_eigen<9>(H.a, ev, Q);
  double m = ev[0];
  for (double e : ev) m = e < m ? e : m;
  return m;
}

struct Row {
  double t, lateral;
  Mat3 F;
};

// Lateral stretch t of the uniaxial-stress state diag(s, t, t): the t in (0, 4] that minimizes the
// energy, found on a grid and refined by golden section. Minimizing (rather than solving P_yy = 0)
// also finds the collapsed state t -> 0 where corotational has no stress-free root (Sec. 5.2).
template <class Model>
double solve_lateral(const Model& m, double s) {
  auto psi = [&](double t) { return m.energy(Mat3::diag(s, t, t)); };
  const int n = 400;
  const double lo = 1e-9, hi = 4.0;
  int best = 0;
  double best_e = psi(lo);
  for (int k = 1; k <= n; ++k) {
    const double e = psi(lo + (hi - lo) * k / n);
    if (e < best_e) {
      best_e = e;
      best = k;
    }
  }
  double a = lo + (hi - lo) * std::max(best - 1, 0) / n, b = lo + (hi - lo) * std::min(best + 1, n) / n;
  const double g = 0.5 * (std::sqrt(5.0) - 1.0);
  double c = b - g * (b - a), d = a + g * (b - a);
  double fc = psi(c), fd = psi(d);
  for (int it = 0; it < 200 && b - a > 1e-13 * std::max(1.0, b); ++it) {
    if (fc < fd) {
      b = d;
      d = c;
      fd = fc;
      c = b - g * (b - a);
      fc = psi(c);
    } else {
      a = c;
      c = d;
      fc = fd;
      d = a + g * (b - a);
      fd = psi(d);
    }
  }
  // A minimum located by comparing energies is only accurate to sqrt(eps) in t; polish it with Newton
  // steps on the lateral stress P_yy(t) = 0, kept only while they reduce |P_yy|.
  double t = 0.5 * (a + b);
  auto Pyy = [&](double x) { return m.pk1(Mat3::diag(s, x, x))(1, 1); };
  for (int it = 0; it < 8; ++it) {
    const double f = Pyy(t), h = 1e-7 * std::max(t, 1e-6);
    const double df = (Pyy(t + h) - Pyy(t - h)) / (2.0 * h);
    if (!(std::fabs(df) > 0.0)) break;
    const double tn = t - f / df;
    if (!(tn > 0.0) || !(std::fabs(Pyy(tn)) < std::fabs(f))) break;
    t = tn;
  }
  return t;
}

// The command line, checked.
struct Options {
  std::string path = "uniaxial", out_file, plot_file, fstr;
  double tmin = NAN, tmax = NAN;
  int steps = 48;
  Teuchos::ParameterList material{"Material"};
  bool done = false;  // --list or --help answered already
};

Options parse_options(int argc, char** argv) {
  Options o;
  std::string model = "stable-neohookean", projection = "clamp";
  double E = 1e5, nu = 0.45;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) throw UsageError("option " + a + " needs a value");
      return argv[++i];
    };
    auto number = [&](const std::string& v) {
      if (!strict_number(v, false)) throw UsageError("option " + a + ": '" + v + "' is not a finite number");
      return std::strtod(v.c_str(), nullptr);
    };
    if (a == "--model") model = next();
    else if (a == "--E") E = number(next());
    else if (a == "--nu") nu = number(next());
    else if (a == "--projection") projection = next();
    else if (a == "--path") o.path = next();
    else if (a == "--min") o.tmin = number(next());
    else if (a == "--max") o.tmax = number(next());
    else if (a == "--steps") {
      const std::string v = next();
      if (!strict_number(v, true)) throw UsageError("--steps: '" + v + "' is not a whole number");
      o.steps = std::atoi(v.c_str());
    } else if (a == "--F") o.fstr = next();
    else if (a == "--output") o.out_file = next();
    else if (a == "--plot") o.plot_file = next();
    else if (a == "--param") {
      const std::string kv = next();
      const auto eq = kv.find('=');
      if (eq == std::string::npos) throw UsageError("--param expects KEY=VALUE, got '" + kv + "'");
      o.material.set(kv.substr(0, eq), number(kv.substr(eq + 1)));
    } else if (a == "--list") {
      for (const auto& n : material_model_names()) std::cout << n << "\n";
      o.done = true;
    } else if (a == "-h" || a == "--help") {
      std::cout << kUsage;
      o.done = true;
    } else {
      throw UsageError("unknown option '" + a + "'");
    }
  }
  if (o.steps < 1 || o.steps > 1000000) throw UsageError("--steps must be in [1, 1e6]");
  if (!o.plot_file.empty() && o.out_file.empty()) throw UsageError("--plot needs --output FILE.csv");
  o.material.set("Model", model);
  o.material.set("Young modulus", E);
  o.material.set("Poisson ratio", nu);
  o.material.set("Projection", projection);
  return o;
}

// The deformation gradients along the chosen path.
std::vector<Row> load_path(const MaterialSpec& spec, Options& o) {
  std::vector<Row> rows;
  if (o.path == "F") {
    Mat3 F;
    std::stringstream ss(o.fstr);
    std::string item;
    int k = 0;
    while (std::getline(ss, item, ',')) {
      if (!strict_number(item, false)) throw UsageError("--F: '" + item + "' is not a finite number");
      if (k < 9) F(k / 3, k % 3) = std::strtod(item.c_str(), nullptr);
      ++k;
    }
    if (k != 9) throw UsageError("--F needs nine comma-separated numbers, row by row (got " + std::to_string(k) + ")");
    rows.push_back({1.0, NAN, F});
    return rows;
  }
  if (o.path != "uniaxial" && o.path != "shear" && o.path != "hydrostatic")
    throw UsageError("unknown --path '" + o.path + "' (uniaxial, shear, hydrostatic, F)");
  // Default ranges: stretch 1 -> 3.4 (the paper's stretch test), shear 0 -> 2, scale 1 -> -0.5 (through
  // collapse into inversion).
  if (std::isnan(o.tmin)) o.tmin = o.path == "shear" ? 0.0 : 1.0;
  if (std::isnan(o.tmax)) o.tmax = o.path == "hydrostatic" ? -0.5 : (o.path == "shear" ? 2.0 : 3.4);
  for (int k = 0; k <= o.steps; ++k) {
    const double t = o.tmin + (o.tmax - o.tmin) * k / o.steps;
    Row r{t, NAN, Mat3::identity()};
    if (o.path == "uniaxial") {
      r.lateral = with_material(spec, [&](auto m) { return solve_lateral(m, t); });
      r.F = Mat3::diag(t, r.lateral, r.lateral);
    } else if (o.path == "shear") {
      r.F(0, 1) = t;
    } else {
      r.F = Mat3::diag(t, t, t);
    }
    rows.push_back(r);
  }
  return rows;
}

void write_csv(std::ostream& os, const MaterialSpec& spec, const std::vector<Row>& rows) {
  os.precision(10);
  os << "stretch,J,psi,P00,P01,P02,P10,P11,P12,P20,P21,P22,lateral,min_eig_raw,min_eig_projected\n";
  with_material(spec, [&](auto m) {
    for (const Row& r : rows) {
      const Mat3 P = m.pk1(r.F);
      os << r.t << "," << det(r.F) << "," << m.energy(r.F);
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) os << "," << P(i, j);
      os << "," << r.lateral << "," << min_eig(m.hessian(r.F)) << ","
         << min_eig(m.projected_hessian(r.F, spec.projection == Projection::None ? Projection::Clamp : spec.projection))
         << "\n";
    }
  });
}

int run(int argc, char** argv) {
  Options o = parse_options(argc, argv);
  if (o.done) return 0;
  const MaterialSpec spec = material_from_parameters(o.material);
  const std::vector<Row> rows = load_path(spec, o);
  if (o.out_file.empty()) {
    write_csv(std::cout, spec, rows);
  } else {
    std::ofstream file(o.out_file);
    if (!file) throw InputError("cannot write '" + o.out_file + "'", InputErrorKind::File);
    write_csv(file, spec, rows);
    file.close();
    if (!file) throw InputError("writing '" + o.out_file + "' failed", InputErrorKind::File);
  }
  std::cerr << "sinew-material: " << describe(spec) << ", path " << o.path << ", " << rows.size() << " points\n";
  if (!o.plot_file.empty()) {
    // Debian's python3 carries python3-matplotlib (scripts/deps.sh); another python3 earlier in PATH may not.
    const std::string py = std::ifstream("/usr/bin/python3").good() ? "/usr/bin/python3" : "python3";
    const std::string cmd = py + " \"" SINEW_SOURCE_DIR "/scripts/plot_material.py\" \"" + o.out_file + "\" \"" +
                            o.plot_file + "\" \"" + describe(spec) + "\"";
    if (std::system(cmd.c_str()) != 0) throw std::runtime_error("plotting failed (is python3-matplotlib installed?)");
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return run_guarded("sinew-material", true, [&] { return run(argc, argv); });
}
