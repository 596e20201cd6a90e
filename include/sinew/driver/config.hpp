// Reading a scene file: a Teuchos XML parameter list, validated before any work starts.
#pragma once

#include <sinew/materials/models.hpp>

#include <Teuchos_RCP.hpp>

#include <string>

namespace Teuchos {
class ParameterList;
}

namespace sinew {

struct SceneConfig {
  std::string file;
  Teuchos::RCP<Teuchos::ParameterList> params;  // the whole list as read (defaults filled in)
  MaterialSpec material;
};

// Reads and validates a scene file. Throws InputError naming the file and the entry at fault.
SceneConfig read_scene(const std::string& path);

// Validates a parameter list already in memory; `name` stands for the file in messages.
SceneConfig make_scene(Teuchos::RCP<Teuchos::ParameterList> params, const std::string& name);

// Every accepted entry of a scene file, with defaults and documentation (sinew --parameters).
std::string parameter_reference();

// Human-readable summary of a scene for the start of a run.
std::string describe(const SceneConfig& scene);

}  // namespace sinew
