// Scene files: strict XML reading, then every section parsed and checked from its declaration.
#include <sinew/core/parameters.hpp>
#include <sinew/core/xml_input.hpp>
#include <sinew/driver/config.hpp>

#include <sstream>

namespace sinew {

SceneConfig make_scene(const Teuchos::RCP<Teuchos::ParameterList>& params, const std::string& name) {
  SceneConfig c;
  c.file = name;
  try {
    c.params = parse_section<SceneFileParameters>(*params, "the top-level list");
  } catch (const InputError& e) {
    throw e.prefixed(name + ": ");
  }
  return c;
}

SceneConfig read_scene(const std::string& path) { return make_scene(read_parameter_file(path), path); }

std::string parameter_reference() {
  std::ostringstream os;
  os << "Every entry of a Sinew scene file: name (type, default) and meaning, [allowed range].\n\n";
  print_section<SceneFileParameters>(os, "Scene file");
  return os.str();
}

std::string describe(const SceneConfig& c) {
  const SceneFileParameters& p = c.params;
  std::ostringstream os;
  os.precision(6);
  os << "scene: " << p.scene << " (" << c.file << ")\n";
  if (!p.description.empty()) os << "  " << p.description << "\n";
  os << "mesh: " << p.mesh.type << ", " << to_string(p.mesh.element) << ", " << p.mesh.cells[0] << " x "
     << p.mesh.cells[1] << " x " << p.mesh.cells[2] << " cells\n";
  os << "material: " << describe(p.material.law.spec()) << "\n";
  for (const auto& [region, law] : p.material.regions) os << "  region " << region << ": " << describe(law.spec()) << "\n";
  os << "loading: " << p.loading.steps << " step" << (p.loading.steps > 1 ? "s" : "") << ", "
     << p.loading.conditions.size() << " boundary condition" << (p.loading.conditions.size() == 1 ? "" : "s") << "\n";
  for (const auto& [name, bc] : p.loading.conditions)
    os << "  " << name << ": " << bc.region << ", components " << bc.components << "\n";
  os << "solver: |F| < " << p.solver.absolute_tolerance << ", at most " << p.solver.max_iterations
     << " Newton iterations, line search " << p.solver.line_search << " on the " << p.solver.merit << ", CG with "
     << p.solver.preconditioner << "\n";
  os << "output: " << (p.output.directory.empty() ? "results/" + p.scene : p.output.directory) << "\n";
  return os.str();
}

}  // namespace sinew
