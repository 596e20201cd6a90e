// Helpers for tests that run whole scenes: differences between displacement vectors, a scene from XML
// text, and the reference file that the 1-thread variant writes and the others compare against.
#pragma once

#include <sinew/core/xml_input.hpp>
#include <sinew/driver/config.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <sstream>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

namespace sinew::test {

inline double max_abs(const std::vector<double>& v) {
  double m = 0.0;
  for (double x : v) m = std::max(m, std::fabs(x));
  return m;
}

inline double max_diff(const std::vector<double>& a, const std::vector<double>& b) {
  EXPECT_EQ(a.size(), b.size());
  double m = 0.0;
  for (std::size_t i = 0; i < std::min(a.size(), b.size()); ++i) m = std::max(m, std::fabs(a[i] - b[i]));
  return m;
}

// The cells of one column of a CSV file with a header row (a run's log.csv or newton.csv), row by row;
// empty when the file or the column is missing.
inline std::vector<std::string> csv_column(const std::string& path, const std::string& name) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  std::vector<std::string> header;
  for (std::stringstream ss(line); std::getline(ss, line, ',');) header.push_back(line);
  const auto at = std::find(header.begin(), header.end(), name) - header.begin();
  std::vector<std::string> out;
  if (at == static_cast<long>(header.size())) return out;
  while (std::getline(in, line)) {
    std::stringstream ss(line);
    std::string cell;
    for (long k = 0; std::getline(ss, cell, ','); ++k)
      if (k == at) out.push_back(cell);
  }
  return out;
}

// max |a - b| / max |a|
inline double rel_diff(const std::vector<double>& a, const std::vector<double>& b) {
  return max_diff(a, b) / std::max(max_abs(a), 1e-300);
}

// A Wavefront OBJ as Sinew writes it (v, vn, f with v//vn).
struct Obj {
  std::vector<std::array<double, 3>> v, vn;
  std::vector<std::array<int, 3>> f;  // 0-based
};

inline Obj read_obj(const std::string& path) {
  Obj o;
  std::ifstream in(path);
  EXPECT_TRUE(in.good()) << path;
  for (std::string line; std::getline(in, line);) {
    std::istringstream ss(line);
    std::string kind;
    ss >> kind;
    if (kind == "v" || kind == "vn") {
      std::array<double, 3> p;
      ss >> p[0] >> p[1] >> p[2];
      (kind == "v" ? o.v : o.vn).push_back(p);
    } else if (kind == "f") {
      std::array<int, 3> t;
      for (int a = 0; a < 3; ++a) {
        std::string item;
        ss >> item;
        t[a] = std::stoi(item.substr(0, item.find('/'))) - 1;
        EXPECT_EQ(item, std::to_string(t[a] + 1) + "//" + std::to_string(t[a] + 1));
      }
      o.f.push_back(t);
    }
  }
  return o;
}

// The opening of a scene on a mesh file with one stable Neo-Hookean law: the Sinew list with its Scene
// name, the Mesh and Material sections; the caller adds the other sections and the closing tag.
inline std::string file_scene_head(const std::string& scene, const std::string& mesh_file, double E = 1000.0, double nu = 0.45) {
  return R"x(<ParameterList name="Sinew">
  <Parameter name="Scene" type="string" value=")x" + scene + R"x("/>
  <ParameterList name="Mesh">
    <Parameter name="Type" type="string" value="file"/>
    <Parameter name="File" type="string" value=")x" + mesh_file + R"x("/>
  </ParameterList>
  <ParameterList name="Material">
    <Parameter name="Model" type="string" value="stable-neohookean"/>
    <Parameter name="Young modulus" type="double" value=")x" + std::to_string(E) + R"x("/>
    <Parameter name="Poisson ratio" type="double" value=")x" + std::to_string(nu) + R"x("/>
  </ParameterList>)x";
}

// A scene's Output section that writes no files but the logs (tests compare states in memory);
// `extra` adds entries (a checkpoint).
inline std::string logs_only_output(const std::string& extra = R"x(<Parameter name="Checkpoint every" type="int" value="0"/>)x") {
  return R"x(<ParameterList name="Output">
    <Parameter name="HDF5" type="bool" value="false"/>
    <Parameter name="Surface OBJ" type="bool" value="false"/>
    )x" + extra + R"x(
  </ParameterList>)x";
}

// A scene from XML text, its output sent to `out`.
inline SceneConfig config(const std::string& xml, const std::string& out) {
  SceneConfig c = make_scene(read_parameter_text(xml, "test scene"), "test scene");
  c.params.output.directory = out;
  return c;
}

// Whether CTest asked this run to write or compare a reference (SINEW_REFERENCE_MODE/FILE).
inline bool reference_requested() { return std::getenv("SINEW_REFERENCE_MODE") && std::getenv("SINEW_REFERENCE_FILE"); }

// With SINEW_REFERENCE_MODE=write, rank 0 writes u (by global DOF) to SINEW_REFERENCE_FILE; with
// "compare", u must equal the file's values to `tolerance` relative. Nothing without the variables.
inline void agree_with_reference(const std::vector<double>& u, int rank, double tolerance) {
  if (!reference_requested()) return;
  const std::string mode = std::getenv("SINEW_REFERENCE_MODE"), file = std::getenv("SINEW_REFERENCE_FILE");
  if (mode == "write") {
    if (rank == 0) {
      std::ofstream out(file);
      out.precision(17);
      for (double x : u) out << x << "\n";
    }
    return;
  }
  std::ifstream in(file);
  ASSERT_TRUE(in.good()) << "reference " << file << " missing";
  std::vector<double> ref;
  for (double x; in >> x;) ref.push_back(x);
  const double d = rel_diff(ref, u);
  EXPECT_LT(d, tolerance);
  if (rank == 0) std::printf("[ info ] against the 1-thread reference: max |u - u_ref| / max |u_ref| = %.2e\n", d);
}

}  // namespace sinew::test
