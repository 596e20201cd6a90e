// The "Material" section of a scene (host only): one material law, and optionally one sublist per mesh
// region (a volume group of a mesh file) with a law of its own, e.g.
//
//   <ParameterList name="Material">
//     <Parameter name="Model" type="string" value="stable-neohookean"/>   (elements in no listed region)
//     <Parameter name="Young modulus" type="double" value="2.0e4"/>
//     <ParameterList name="tendon">                                          (the volume group "tendon")
//       <Parameter name="Model" type="string" value="stable-neohookean"/>
//       <Parameter name="Young modulus" type="double" value="5.0e5"/>
//     </ParameterList>
//   </ParameterList>
//
// A region's sublist is a complete law of its own: what it does not give takes the declared default,
// not the value of the enclosing list.
#pragma once

#include <sinew/core/parameters.hpp>
#include <sinew/materials/models.hpp>

#include <sstream>

namespace sinew {

// The ranges of Young's modulus and Poisson's ratio (used by the section below and by the conversion).
inline Range young_range() { return Range::positive(); }
inline Range poisson_range() { return Range::open(-1.0, 0.5); }

// Lame constants from Young's modulus and Poisson's ratio; throws InputError naming the parameter when
// either is out of its range.
inline void lame_from_young_poisson(double E, double nu, double& mu_L, double& lambda_L) {
  if (!std::isfinite(E) || !young_range().contains(E))
    throw InputError("Material: " + param_detail::range_message("Young modulus", young_range(), E, -1));
  if (!poisson_range().contains(nu))
    throw InputError("Material: " + param_detail::range_message("Poisson ratio", poisson_range(), nu, -1));
  mu_L = E / (2.0 * (1.0 + nu));
  lambda_L = E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
}

inline double young_modulus(const MaterialSpec& s) { return s.mu_L * (3.0 * s.lambda_L + 2.0 * s.mu_L) / (s.lambda_L + s.mu_L); }
inline double poisson_ratio(const MaterialSpec& s) { return s.lambda_L / (2.0 * (s.lambda_L + s.mu_L)); }

namespace material_detail {

// Collects entry names, to tell which model an option belongs to.
struct NameCollector {
  std::vector<std::string> names;
  template <class T, class D>
  void entry(const char* n, T&, const D&, const std::string&, Range = Range::any()) {
    names.emplace_back(n);
  }
  template <class T>
  void optional(const char* n, T&, const std::string&, Range = Range::any()) {
    names.emplace_back(n);
  }
};

// ", Fung fraction 0.5, Fung exponent 1" for descriptions.
struct OptionWriter {
  std::ostringstream& os;
  template <class T, class D>
  void entry(const char* n, T& v, const D&, const std::string&, Range = Range::any()) {
    os << ", " << n << " " << v;
  }
  template <class T>
  void optional(const char* n, std::optional<T>& v, const std::string&, Range = Range::any()) {
    if (v) os << ", " << n << " " << *v;
  }
};

}  // namespace material_detail

// One material law as a scene gives it.
struct MaterialLaw {
  std::string model;
  double young = 0.0, poisson = 0.0, density = 0.0;
  std::optional<double> lame_mu, lame_lambda;
  std::string projection, volumetric;
  double mean_share = 0.0;
  MaterialOptions options;

  template <class V>
  void visit(V& v) {
    v.entry("Model", model, std::string(StableNeoHookean::name), "hyperelastic model (required): " + models_doc());
    v.entry("Young modulus", young, 1.0e5, "Young's modulus E in stress units (or give 'Lame mu' and 'Lame lambda')",
            young_range());
    v.entry("Poisson ratio", poisson, 0.45, "Poisson's ratio nu", poisson_range());
    v.optional("Lame mu", lame_mu, "Lame shear modulus mu_L, instead of E and nu", Range::positive());
    v.optional("Lame lambda", lame_lambda, "Lame first parameter lambda_L, instead of E and nu (lambda_L > -2/3 mu_L)");
    v.entry("Density", density, 1000.0,
            "mass per reference volume (gravity, inertia); the default is soft tissue's, about water's in kg/m^3",
            Range::positive());
    v.entry("Projection", projection, std::string("clamp"),
            "Hessian PSD projection: none, clamp (Smith et al. 2018, Sec. 4) or abs (Chen et al. 2024)");
    v.entry("Volumetric", volumetric, std::string("points"),
            "where the law's volume term lambda/2 (J - alpha)^2 is evaluated: at every quadrature point (the paper's "
            "element), or on each element's mean dilatation (current over reference volume; one volume constraint per "
            "hex8 instead of eight, against locking when nearly incompressible): points or mean dilatation "
            "(stable-neohookean and stable-neohookean-nobarrier only; a tet4 has one point, where both agree)");
    v.entry("Mean dilatation share", mean_share, 0.8,
            "with 'Volumetric' mean dilatation: the share of the volume term on each hex8's mean dilatation; the rest "
            "stays at the points, where it keeps the hex8's modes that change J at its points but not its mean from "
            "going unstable under large strain (1: the pure mean dilatation, on which the paper's pi twist at nu = 0.49 "
            "does not converge; 0.8 converges it at 15^3 and 30^3)",
            Range::open_closed(0.0, 1.0));
#define SINEW_MODEL_VISIT(M) std::get<static_cast<std::size_t>(model_of<M>()) + 1>(options).visit(v);
    SINEW_MATERIAL_MODELS(SINEW_MODEL_VISIT)
#undef SINEW_MODEL_VISIT
  }

  void check(const SectionContext& c) const {
    if (!c.given("Model")) c.fail("missing entry 'Model'", InputErrorKind::MissingEntry);
    const auto m = find_model();
    if (!m) {
      const auto& names = material_model_names();
      std::string msg = "unknown 'Model' \"" + model + "\"";
      const std::string near = closest_name(model, names);
      if (!near.empty()) msg += " (did you mean \"" + near + "\"?)";
      c.fail(msg + "; known models: " + or_list(names));
    }
    if (!find_projection()) c.fail("'Projection' must be one of none, clamp, abs; got \"" + projection + "\"");
    if (volumetric != "points" && volumetric != "mean dilatation")
      c.fail("'Volumetric' must be points or mean dilatation, got \"" + volumetric + "\"");
    if (volumetric == "mean dilatation" &&
        !with_material(spec(), [](const auto& law) { return has_volume_term<std::decay_t<decltype(law)>>::value; }))
      c.fail("'Volumetric' mean dilatation needs a law with a volume term lambda/2 (J - alpha)^2 (stable-neohookean, "
             "stable-neohookean-nobarrier), not " + model);
    if (c.given("Mean dilatation share") && volumetric != "mean dilatation")
      c.fail("'Mean dilatation share' applies only with 'Volumetric' mean dilatation (here \"" + volumetric + "\")");
    const bool has_en = c.given("Young modulus") || c.given("Poisson ratio");
    const bool has_lame = c.given("Lame mu") || c.given("Lame lambda");
    if (has_en && has_lame) c.fail("give either 'Young modulus'/'Poisson ratio' or 'Lame mu'/'Lame lambda', not both");
    if (has_lame && !(lame_mu && lame_lambda)) c.fail("'Lame mu' and 'Lame lambda' must be given together");
    if (has_lame && !(3.0 * *lame_lambda + 2.0 * *lame_mu > 0.0))
      c.fail("'Lame lambda' must give a positive bulk modulus (lambda > -2/3 mu), got " + format_number(*lame_lambda));
    // An option of another model is a mistake (a typo'd model, or a leftover): say so.
    for (std::size_t k = 0; k < kMaterialModelCount; ++k) {
      if (k == static_cast<std::size_t>(*m)) continue;
      for (const auto& name : option_names(static_cast<MaterialModel>(k)))
        if (c.given(name)) c.fail("'" + name + "' belongs to model " + material_model_names()[k] + ", not " + model);
    }
    const std::string why = with_material(spec(), [](const auto& law) { return law.invalid(); });
    if (!why.empty()) c.fail(why);
  }

  // The resolved spec of a checked law.
  MaterialSpec spec() const {
    MaterialSpec s = material_defaults(find_model().value_or(MaterialModel::StableNeoHookean), 0.0, 0.0);
    if (lame_mu && lame_lambda) {
      s.mu_L = *lame_mu;
      s.lambda_L = *lame_lambda;
    } else {
      lame_from_young_poisson(young, poisson, s.mu_L, s.lambda_L);
    }
    s.options = options;
    s.projection = find_projection().value_or(Projection::Clamp);
    s.mean_dilatation = volumetric == "mean dilatation" ? mean_share : 0.0;
    s.density = density;
    return s;
  }

 private:
  static std::string models_doc() {
    std::string d;
#define SINEW_MODEL_DOC(M) d += std::string(d.empty() ? "" : ", ") + M::name + " (" + M::equation + ")";
    SINEW_MATERIAL_MODELS(SINEW_MODEL_DOC)
#undef SINEW_MODEL_DOC
    return d;
  }

  static std::vector<std::string> option_names(MaterialModel m) {
    MaterialSpec s = material_defaults(m, 1.0, 1.0);
    material_detail::NameCollector names;
    switch (m) {
#define SINEW_MODEL_NAMES(M) \
  case MaterialModel::M: options_of<M>(s).visit(names); break;
      SINEW_MATERIAL_MODELS(SINEW_MODEL_NAMES)
#undef SINEW_MODEL_NAMES
    }
    return names.names;
  }

  std::optional<MaterialModel> find_model() const {
    const auto& names = material_model_names();
    for (std::size_t k = 0; k < names.size(); ++k)
      if (names[k] == model) return static_cast<MaterialModel>(k);
    return std::nullopt;
  }
  std::optional<Projection> find_projection() const {
    for (const auto& [name, value] : projection_choices())
      if (name == projection) return value;
    return std::nullopt;
  }
};

// The whole "Material" section: the law of elements in no listed region, and one law per region.
struct MaterialParameters {
  MaterialLaw law;
  NamedSections<MaterialLaw> regions;

  template <class V>
  void visit(V& v) {
    v.inline_section(law);
    v.other_sublists(regions, "a sublist named after a volume group of the mesh file: the law of its elements");
  }
};

// The spec of a "Material" list without regions (the material-point tool and tests use this).
inline MaterialSpec material_from_parameters(const Teuchos::ParameterList& list) {
  return parse_section<MaterialLaw>(list, "Material").spec();
}

// One line describing a material, e.g. for logs.
inline std::string describe(const MaterialSpec& s) {
  std::ostringstream os;
  os.precision(6);
  os << to_string(s.model) << " (E = " << young_modulus(s) << ", nu = " << poisson_ratio(s) << ", mu_L = " << s.mu_L
     << ", lambda_L = " << s.lambda_L << ", projection " << to_string(s.projection);
  if (s.mean_dilatation > 0.0) os << ", volume term " << 100.0 * s.mean_dilatation << "% on the mean dilatation";
  MaterialSpec copy = s;
  material_detail::OptionWriter w{os};
  switch (s.model) {
#define SINEW_MODEL_DESCRIBE(M) \
  case MaterialModel::M: options_of<M>(copy).visit(w); break;
    SINEW_MATERIAL_MODELS(SINEW_MODEL_DESCRIBE)
#undef SINEW_MODEL_DESCRIBE
  }
  os << ")";
  return os.str();
}

}  // namespace sinew
