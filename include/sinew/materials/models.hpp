// Run-time selection of a material model from the list in model_list.hpp. A MaterialSpec holds what the
// user asked for (model, Lame constants, the model's options, projection); `with_material(spec, fn)`
// builds the concrete model struct and calls fn with it, so each kernel is instantiated once per model
// and no virtual call or switch runs per quadrature point.
#pragma once

#include <sinew/materials/model_list.hpp>

#include <cstddef>
#include <string>
#include <tuple>
#include <vector>

namespace sinew {

#define SINEW_MODEL_ENUM(M) M,
enum class MaterialModel { SINEW_MATERIAL_MODELS(SINEW_MODEL_ENUM) };
#undef SINEW_MODEL_ENUM

#define SINEW_MODEL_COUNT(M) +1
inline constexpr std::size_t kMaterialModelCount = 0 SINEW_MATERIAL_MODELS(SINEW_MODEL_COUNT);
#undef SINEW_MODEL_COUNT

// Every model's Options, in list order (only the chosen model's are used). Slot 0 is a placeholder
// so that the list expands without a leading comma: model k's options sit in slot k + 1.
#define SINEW_MODEL_OPTIONS(M) , M::Options
using MaterialOptions = std::tuple<std::nullptr_t SINEW_MATERIAL_MODELS(SINEW_MODEL_OPTIONS)>;
#undef SINEW_MODEL_OPTIONS

// The enum value of a model struct.
template <class M>
constexpr MaterialModel model_of();
#define SINEW_MODEL_OF(M) \
  template <>             \
  constexpr MaterialModel model_of<M>() { return MaterialModel::M; }
SINEW_MATERIAL_MODELS(SINEW_MODEL_OF)
#undef SINEW_MODEL_OF

// Every model's options at their declared defaults.
inline MaterialOptions default_material_options() {
#define SINEW_MODEL_DEFAULTS(M) , default_section<M::Options>()
  return MaterialOptions{nullptr SINEW_MATERIAL_MODELS(SINEW_MODEL_DEFAULTS)};
#undef SINEW_MODEL_DEFAULTS
}

struct MaterialSpec {
  MaterialModel model = MaterialModel::StableNeoHookean;
  double mu_L = 0.0, lambda_L = 0.0;  // Lame constants the model reproduces at small strain
  MaterialOptions options = default_material_options();
  Projection projection = Projection::Clamp;
  // The share of the law's volume term on each hex8's mean dilatation (mean_dilatation.hpp), the rest
  // per point; 0: all per point (the paper's element).
  double mean_dilatation = 0.0;
  // Mass density per reference volume: not part of the law, but of the material (gravity, inertia).
  double density = 1000.0;
};

// The options of model M in a spec.
template <class M>
typename M::Options& options_of(MaterialSpec& s) {
  return std::get<static_cast<std::size_t>(model_of<M>()) + 1>(s.options);
}
template <class M>
const typename M::Options& options_of(const MaterialSpec& s) {
  return std::get<static_cast<std::size_t>(model_of<M>()) + 1>(s.options);
}

// A spec of `model` with Lame constants (mu_L, lambda_L), every option at its default, clamp projection.
inline MaterialSpec material_defaults(MaterialModel model, double mu_L, double lambda_L) {
  MaterialSpec s;
  s.model = model;
  s.mu_L = mu_L;
  s.lambda_L = lambda_L;
  return s;
}

template <class Fn>
decltype(auto) with_material(const MaterialSpec& s, Fn&& fn) {
  switch (s.model) {
#define SINEW_MODEL_CASE(M) \
  case MaterialModel::M: return fn(M::make(s.mu_L, s.lambda_L, options_of<M>(s)));
    SINEW_MATERIAL_MODELS(SINEW_MODEL_CASE)
#undef SINEW_MODEL_CASE
  }
  return fn(StableNeoHookean::make(s.mu_L, s.lambda_L, options_of<StableNeoHookean>(s)));
}

// Names used in XML ("Model" entry) and on the command line, in list order.
inline const std::vector<std::string>& material_model_names() {
#define SINEW_MODEL_NAME(M) M::name,
  static const std::vector<std::string> names = {SINEW_MATERIAL_MODELS(SINEW_MODEL_NAME)};
#undef SINEW_MODEL_NAME
  return names;
}
inline std::string to_string(MaterialModel m) { return material_model_names().at(static_cast<std::size_t>(m)); }

inline const Choices<Projection>& projection_choices() {
  static const Choices<Projection> c = {{"none", Projection::None}, {"clamp", Projection::Clamp}, {"abs", Projection::Abs}};
  return c;
}
inline std::string to_string(Projection p) {
  for (const auto& [name, value] : projection_choices())
    if (value == p) return name;
  return "?";
}

}  // namespace sinew
