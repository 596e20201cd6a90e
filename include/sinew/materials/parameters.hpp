// Reading and validating material parameters (host only).
#pragma once

#include <sinew/materials/models.hpp>

namespace Teuchos {
class ParameterList;
}

namespace sinew {

// Lame constants from Young's modulus and Poisson's ratio; throws InputError naming the parameter when
// E <= 0 or nu is outside (-1, 0.5).
void lame_from_young_poisson(double E, double nu, double& mu_L, double& lambda_L);

// Young's modulus and Poisson's ratio of a spec's small-strain response.
double young_modulus(const MaterialSpec& spec);
double poisson_ratio(const MaterialSpec& spec);

// The accepted entries of a "Material" sublist, with defaults, documentation and validators.
Teuchos::ParameterList valid_material_parameters();

// Builds a MaterialSpec from a "Material" sublist: validates names, types and ranges (unknown keys and
// impossible values throw InputError naming the entry) and checks that the model's own parameters
// keep it rest-stable and positive (e.g. Fung's lambda > 0).
MaterialSpec material_from_parameters(const Teuchos::ParameterList& list);

// One line describing the resolved material, e.g. for logs.
std::string describe(const MaterialSpec& spec);

}  // namespace sinew
