#include <sinew/core/errors.hpp>
#include <sinew/core/validation.hpp>
#include <sinew/driver/config.hpp>
#include <sinew/materials/parameters.hpp>

#include <Teuchos_ParameterList.hpp>
#include <Teuchos_XMLParameterListHelpers.hpp>

#include <fstream>
#include <sstream>

namespace sinew {

namespace {
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
    if (!probe) throw InputError(path + ": cannot open scene file");
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
    throw InputError(path + ": malformed XML parameter list: " + what);
  }
  return make_scene(scene.params, path);
}

SceneConfig make_scene(Teuchos::RCP<Teuchos::ParameterList> params, const std::string& name) {
  SceneConfig scene;
  scene.file = name;
  scene.params = params;
  try {
    require_known_entries(*scene.params, valid_top_level(), "the top-level list");
    scene.material = material_from_parameters(scene.params->sublist("Material"));
  } catch (const InputError& e) {
    throw InputError(name + ": " + e.what());
  }
  return scene;
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
