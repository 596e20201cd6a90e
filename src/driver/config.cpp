#include <sinew/core/errors.hpp>
#include <sinew/core/validation.hpp>
#include <sinew/driver/config.hpp>
#include <sinew/io/output.hpp>
#include <sinew/scenes/scene.hpp>
#include <sinew/solver/nonlinear_solver.hpp>
#include <sinew/materials/parameters.hpp>

#include <Teuchos_ParameterList.hpp>
#include <Teuchos_FileInputSource.hpp>
#include <Teuchos_XMLParameterListHelpers.hpp>

#include <cstdlib>

#include <fstream>
#include <sstream>

namespace sinew {

namespace {

// Teuchos converts numbers with stream extraction, which stops at the first bad character and so
// accepts "1.0e5x" as 1e5. Check every numeric value of the XML strictly before trusting the list.
bool strict_number(const std::string& text, bool integer) {
  const char* b = text.c_str();
  while (*b == ' ' || *b == '\t') ++b;
  if (*b == '\0') return false;
  char* end = nullptr;
  if (integer)
    (void)std::strtoll(b, &end, 10);
  else
    (void)std::strtod(b, &end);
  while (*end == ' ' || *end == '\t') ++end;
  return end != b && *end == '\0';
}

void check_numbers(const Teuchos::XMLObject& node, const std::string& path, const std::string& where) {
  if (node.getTag() == "Parameter" && node.hasAttribute("type") && node.hasAttribute("value")) {
    const std::string type = node.getAttribute("type"), value = node.getAttribute("value");
    const std::string name = node.hasAttribute("name") ? node.getAttribute("name") : "?";
    auto bad = [&](const std::string& item) {
      throw InputError(path + ": malformed XML parameter list: '" + name + "' in " + where + " is declared " + type +
                           " but its value '" + item + "' is not one",
                       InputErrorKind::MalformedXml);
    };
    if (type == "double" || type == "int") {
      if (!strict_number(value, type == "int")) bad(value);
    } else if (type == "Array(double)" || type == "Array(int)") {
      std::string inner = value;
      const auto l = inner.find('{'), r = inner.rfind('}');
      if (l == std::string::npos || r == std::string::npos || r < l) bad(value);
      inner = inner.substr(l + 1, r - l - 1);
      std::stringstream ss(inner);
      for (std::string item; std::getline(ss, item, ',');)
        if (!strict_number(item, type == "Array(int)")) bad(item);
    }
  }
  const std::string here = node.getTag() == "ParameterList" && node.hasAttribute("name") ? node.getAttribute("name") : where;
  for (int i = 0; i < node.numChildren(); ++i) check_numbers(node.getChild(i), path, here);
}

Teuchos::ParameterList valid_top_level() {
  Teuchos::ParameterList v("Sinew");
  v.set("Scene", std::string("custom"), "scene name, used in output file names");
  v.set("Description", std::string(""), "free text");
  v.sublist("Mesh", false, "mesh generator and resolution");
  v.sublist("Material", false, "hyperelastic model and its parameters");
  v.sublist("Loading", false, "boundary conditions and load steps");
  v.sublist("Solver", false, "NOX / Belos / MueLu parameters");
  v.sublist("Output", false, "HDF5/XDMF output and logs");
  return v;
}
}  // namespace

SceneConfig read_scene(const std::string& path) {
  {
    std::ifstream probe(path);
    if (!probe) throw InputError(path + ": cannot open scene file", InputErrorKind::File);
  }
  SceneConfig scene;
  scene.file = path;
  try {
    scene.params = Teuchos::getParametersFromXmlFile(path);
  } catch (const std::exception& e) {
    std::string what = e.what();
    // Teuchos' messages carry a source location banner; keep the informative last line.
    auto nl = what.find_last_of('\n', what.size() > 1 ? what.size() - 2 : 0);
    if (nl != std::string::npos && nl + 1 < what.size()) what = what.substr(nl + 1);
    throw InputError(path + ": malformed XML parameter list: " + what, InputErrorKind::MalformedXml);
  }
  check_numbers(Teuchos::FileInputSource(path).getObject(), path, "the top-level list");
  return make_scene(scene.params, path);
}

SceneConfig make_scene(Teuchos::RCP<Teuchos::ParameterList> params, const std::string& name) {
  SceneConfig scene;
  scene.file = name;
  scene.params = params;
  try {
    require_known_entries(*scene.params, valid_top_level(), "the top-level list");
    // The few entries without a sensible default.
    if (!scene.params->isSublist("Mesh")) throw InputError("missing sublist 'Mesh'", InputErrorKind::MissingEntry);
    if (!scene.params->sublist("Mesh").isParameter("Elements"))
      throw InputError("Mesh: missing entry 'Elements' (cells along x, y, z)", InputErrorKind::MissingEntry);
    if (!scene.params->isSublist("Material")) throw InputError("missing sublist 'Material'", InputErrorKind::MissingEntry);
    if (!scene.params->sublist("Material").isParameter("Model"))
      throw InputError("Material: missing entry 'Model'", InputErrorKind::MissingEntry);
    scene.material = material_from_parameters(scene.params->sublist("Material"));
  } catch (const InputError& e) {
    throw e.prefixed(name + ": ");
  }
  return scene;
}

std::string parameter_reference() {
  std::ostringstream os;
  auto section = [&](const std::string& title, const Teuchos::ParameterList& l) {
    os << "== " << title << " ==\n";
    l.print(os, Teuchos::ParameterList::PrintOptions().indent(2).showTypes(true).showDoc(true));
    os << "\n";
  };
  section("top level", valid_top_level());
  section("Mesh", valid_mesh_parameters());
  section("Material", valid_material_parameters());
  section("Loading", valid_loading_parameters());
  section("Loading / Boundary conditions / <name>", valid_boundary_condition_parameters());
  section("Solver (plus sublists 'NOX' and 'Stratimikos' passed to Trilinos)", valid_solver_parameters());
  section("Output", valid_output_parameters());
  return os.str();
}

std::string describe(const SceneConfig& scene) {
  std::ostringstream os;
  os << "scene: " << get_or<std::string>(*scene.params, "Scene", "custom") << " (" << scene.file << ")\n";
  os << "material: " << describe(scene.material) << "\n";
  for (const char* sub : {"Mesh", "Loading", "Solver", "Output"}) {
    if (!scene.params->isSublist(sub)) continue;
    os << sub << ":\n";
    scene.params->sublist(sub).print(os, Teuchos::ParameterList::PrintOptions().indent(2).showTypes(false));
  }
  return os.str();
}

}  // namespace sinew
