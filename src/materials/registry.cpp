// Material names, XML parameters and their validation.
#include <sinew/core/errors.hpp>
#include <sinew/core/validation.hpp>
#include <sinew/materials/parameters.hpp>

#include <Teuchos_ParameterList.hpp>

#include <cmath>
#include <sstream>

namespace sinew {

namespace {
const std::vector<std::string> kProjectionNames = {"none", "clamp", "abs"};

std::string fmt(double v) {
  std::ostringstream os;
  os.precision(6);
  os << v;
  return os.str();
}
}  // namespace

const std::vector<std::string>& material_model_names() {
  static const std::vector<std::string> names = {
      StableNeoHookean::name, StableNeoHookeanNoBarrier::name, NeoHookean::name, FilteredNeoHookean::name,
      Corotational::name,     FixedCorotational::name,         StVK::name,       "stvk-kikuuwe",
      Fung::name,             ArrudaBoyce::name};
  return names;
}

std::string to_string(MaterialModel m) { return material_model_names().at(static_cast<std::size_t>(m)); }
std::string to_string(Projection p) { return kProjectionNames.at(static_cast<std::size_t>(p)); }

double young_modulus(const MaterialSpec& s) { return s.mu_L * (3.0 * s.lambda_L + 2.0 * s.mu_L) / (s.lambda_L + s.mu_L); }
double poisson_ratio(const MaterialSpec& s) { return s.lambda_L / (2.0 * (s.lambda_L + s.mu_L)); }

void lame_from_young_poisson(double E, double nu, double& mu_L, double& lambda_L) {
  if (!(E > 0.0) || !std::isfinite(E))
    throw InputError("Material: 'Young modulus' must be positive and finite, got " + fmt(E));
  if (!(nu > -1.0 && nu < 0.5))
    throw InputError("Material: 'Poisson ratio' must lie in (-1, 0.5), got " + fmt(nu));
  mu_L = E / (2.0 * (1.0 + nu));
  lambda_L = E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
}

Teuchos::ParameterList valid_material_parameters() {
  Teuchos::ParameterList v("Material");
  std::string models;
  for (const auto& n : material_model_names()) models += (models.empty() ? "" : ", ") + n;
  v.set("Model", std::string(StableNeoHookean::name), "hyperelastic model: " + models);
  v.set("Young modulus", 1.0e5, "Young's modulus E > 0 (stress units); or give 'Lame mu' and 'Lame lambda'");
  v.set("Poisson ratio", 0.45, "Poisson's ratio nu in (-1, 0.5)");
  v.set("Lame mu", 0.0, "Lame shear modulus (instead of E and nu)");
  v.set("Lame lambda", 0.0, "Lame first parameter (instead of E and nu)");
  v.set("Projection", std::string("clamp"), "Hessian PSD projection: none, clamp (Smith et al. 2018), abs (Chen et al. 2024)");
  v.set("Fung fraction", 0.5, "fung: share f in [0, 1) of the small-strain shear modulus in the exponential term");
  v.set("Fung exponent", 1.0, "fung: hardening exponent mu1 > 0 of Eq. 53");
  v.set("Arruda-Boyce beta1", 0.05, "arruda-boyce: beta1 >= 0 of Eq. 58");
  v.set("Arruda-Boyce beta2", 0.005, "arruda-boyce: beta2 >= 0 of Eq. 58");
  v.set("Kikuuwe kappa", -1.0, "stvk-kikuuwe: compression stiffness kappa > 0 of Eq. 51 (default 1e4 E)");
  v.set("Filter threshold", 0.25, "filtered-neohookean: singular-value threshold s_f in (0, 1)");
  return v;
}

MaterialSpec material_from_parameters(const Teuchos::ParameterList& in) {
  const Teuchos::ParameterList valid = valid_material_parameters();
  require_known_entries(in, valid, "Material");
  // Defaults come from the valid list, so documentation and behaviour cannot drift apart.
  auto num = [&](const char* key) { return get_or<double>(in, key, valid.get<double>(key)); };
  auto str = [&](const char* key) { return get_or<std::string>(in, key, valid.get<std::string>(key)); };
  MaterialSpec s;

  const std::string model = str("Model");
  const auto& names = material_model_names();
  bool found = false;
  for (std::size_t k = 0; k < names.size(); ++k)
    if (names[k] == model) {
      s.model = static_cast<MaterialModel>(k);
      found = true;
    }
  if (!found) {
    std::string msg = "Material: unknown 'Model' \"" + model + "\"";
    const std::string near = closest_name(model, names);
    if (!near.empty()) msg += " (did you mean \"" + near + "\"?)";
    msg += "; known models:";
    for (const auto& n : names) msg += " " + n;
    throw InputError(msg);
  }

  const bool has_en = in.isParameter("Young modulus") || in.isParameter("Poisson ratio");
  const bool has_lame = in.isParameter("Lame mu") || in.isParameter("Lame lambda");
  if (has_en && has_lame)
    throw InputError("Material: give either 'Young modulus'/'Poisson ratio' or 'Lame mu'/'Lame lambda', not both");
  if (has_lame) {
    if (!in.isParameter("Lame mu") || !in.isParameter("Lame lambda"))
      throw InputError("Material: 'Lame mu' and 'Lame lambda' must be given together");
    s.mu_L = in.get<double>("Lame mu");
    s.lambda_L = in.get<double>("Lame lambda");
    if (!(s.mu_L > 0.0) || !std::isfinite(s.mu_L)) throw InputError("Material: 'Lame mu' must be positive, got " + fmt(s.mu_L));
    if (!(3.0 * s.lambda_L + 2.0 * s.mu_L > 0.0) || !std::isfinite(s.lambda_L))
      throw InputError("Material: 'Lame lambda' must give a positive bulk modulus (lambda > -2/3 mu), got " +
                       fmt(s.lambda_L));
  } else {
    lame_from_young_poisson(num("Young modulus"), num("Poisson ratio"), s.mu_L,
                            s.lambda_L);
  }

  const std::string proj = str("Projection");
  found = false;
  for (std::size_t k = 0; k < kProjectionNames.size(); ++k)
    if (kProjectionNames[k] == proj) {
      s.projection = static_cast<Projection>(k);
      found = true;
    }
  if (!found) throw InputError("Material: 'Projection' must be one of none, clamp, abs; got \"" + proj + "\"");

  s.fung_fraction = num("Fung fraction");
  s.fung_exponent = num("Fung exponent");
  s.ab_beta1 = num("Arruda-Boyce beta1");
  s.ab_beta2 = num("Arruda-Boyce beta2");
  s.filter_threshold = num("Filter threshold");
  // Default kappa scales with the stiffness: 1e4 E (the term is tiny near J = 1, see Eq. 51).
  s.kikuuwe_kappa = in.isParameter("Kikuuwe kappa") ? num("Kikuuwe kappa") : 1.0e4 * young_modulus(s);

  switch (s.model) {
    case MaterialModel::Fung: {
      if (!(s.fung_fraction >= 0.0 && s.fung_fraction < 1.0))
        throw InputError("Material: 'Fung fraction' must lie in [0, 1), got " + fmt(s.fung_fraction));
      if (!(s.fung_exponent > 0.0))
        throw InputError("Material: 'Fung exponent' must be positive, got " + fmt(s.fung_exponent));
      const Fung f = Fung::from_lame(s.mu_L, s.lambda_L, s.fung_fraction, s.fung_exponent);
      if (!(f.lambda > 0.0))
        throw InputError("Material: 'Fung exponent' " + fmt(s.fung_exponent) + " with 'Fung fraction' " +
                         fmt(s.fung_fraction) + " leaves a non-positive volume stiffness lambda = " + fmt(f.lambda) +
                         " at rest; lower one of them (f * mu1 must stay below 1 + lambda_L/mu_L)");
      break;
    }
    case MaterialModel::ArrudaBoyce: {
      if (!(s.ab_beta1 >= 0.0)) throw InputError("Material: 'Arruda-Boyce beta1' must be >= 0, got " + fmt(s.ab_beta1));
      if (!(s.ab_beta2 >= 0.0)) throw InputError("Material: 'Arruda-Boyce beta2' must be >= 0, got " + fmt(s.ab_beta2));
      const ArrudaBoyce a = ArrudaBoyce::from_lame(s.mu_L, s.lambda_L, s.ab_beta1, s.ab_beta2);
      if (!(a.lambda > 0.0))
        throw InputError("Material: 'Arruda-Boyce beta1'/'beta2' leave a non-positive volume stiffness lambda = " +
                         fmt(a.lambda) + " at rest");
      break;
    }
    case MaterialModel::StVKKikuuwe:
      if (!(s.kikuuwe_kappa > 0.0)) throw InputError("Material: 'Kikuuwe kappa' must be positive, got " + fmt(s.kikuuwe_kappa));
      break;
    case MaterialModel::FilteredNeoHookean:
      if (!(s.filter_threshold > 0.0 && s.filter_threshold < 1.0))
        throw InputError("Material: 'Filter threshold' must lie in (0, 1), got " + fmt(s.filter_threshold));
      break;
    case MaterialModel::StableNeoHookean: {
      // Eq. 15-16 need lambda > 0 after reparameterization for alpha to exist.
      if (!(s.lambda_L + 5.0 / 6.0 * s.mu_L > 0.0))
        throw InputError("Material: stable-neohookean needs lambda_L + 5/6 mu_L > 0 (nu > -0.3125 roughly)");
      break;
    }
    case MaterialModel::StableNeoHookeanNoBarrier:
      if (!(s.lambda_L + s.mu_L > 0.0)) throw InputError("Material: stable-neohookean-nobarrier needs lambda_L + mu_L > 0");
      break;
    default: break;
  }
  return s;
}

std::string describe(const MaterialSpec& s) {
  std::ostringstream os;
  os.precision(6);
  os << to_string(s.model) << " (E = " << young_modulus(s) << ", nu = " << poisson_ratio(s) << ", mu_L = " << s.mu_L << ", lambda_L = " << s.lambda_L
     << ", projection " << to_string(s.projection);
  switch (s.model) {
    case MaterialModel::Fung: os << ", fraction " << s.fung_fraction << ", mu1 " << s.fung_exponent; break;
    case MaterialModel::ArrudaBoyce: os << ", beta1 " << s.ab_beta1 << ", beta2 " << s.ab_beta2; break;
    case MaterialModel::StVKKikuuwe: os << ", kappa " << s.kikuuwe_kappa; break;
    case MaterialModel::FilteredNeoHookean: os << ", threshold " << s.filter_threshold; break;
    default: break;
  }
  os << ")";
  return os.str();
}

}  // namespace sinew
