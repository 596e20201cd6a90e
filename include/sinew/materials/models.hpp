// All material models and the run-time selection of one. The choice is made once, outside any kernel:
// `with_material(spec, fn)` calls fn with the concrete model struct, so each kernel is instantiated once
// per model and no virtual call or switch runs per quadrature point.
#pragma once

#include <sinew/materials/arruda_boyce.hpp>
#include <sinew/materials/corotational.hpp>
#include <sinew/materials/filtered_neohookean.hpp>
#include <sinew/materials/fixed_corotational.hpp>
#include <sinew/materials/fung.hpp>
#include <sinew/materials/neohookean.hpp>
#include <sinew/materials/stable_neohookean.hpp>
#include <sinew/materials/stable_neohookean_nobarrier.hpp>
#include <sinew/materials/stvk.hpp>

#include <string>
#include <vector>

namespace sinew {

enum class MaterialModel {
  StableNeoHookean,
  StableNeoHookeanNoBarrier,
  NeoHookean,
  FilteredNeoHookean,
  Corotational,
  FixedCorotational,
  StVK,
  StVKKikuuwe,
  Fung,
  ArrudaBoyce
};

// A fully resolved material: model, Lame constants of the small-strain response, the model-specific
// parameters and the Hessian projection. Built from XML by material_from_parameters (host only).
struct MaterialSpec {
  MaterialModel model = MaterialModel::StableNeoHookean;
  double mu_L = 0.0, lambda_L = 0.0;     // Lame constants the model reproduces at small strain
  double fung_fraction = 0.5;            // share of the shear modulus in the exponential term
  double fung_exponent = 1.0;            // mu1 of Eq. 53
  double ab_beta1 = 0.05, ab_beta2 = 0.005;  // Eq. 58
  double kikuuwe_kappa = 0.0;            // Eq. 51
  double filter_threshold = 0.25;        // filtered Neo-Hookean singular-value threshold
  Projection projection = Projection::Clamp;
};

template <class Fn>
decltype(auto) with_material(const MaterialSpec& s, Fn&& fn) {
  switch (s.model) {
    case MaterialModel::StableNeoHookeanNoBarrier:
      return fn(StableNeoHookeanNoBarrier::from_lame(s.mu_L, s.lambda_L));
    case MaterialModel::NeoHookean: return fn(NeoHookean::from_lame(s.mu_L, s.lambda_L));
    case MaterialModel::FilteredNeoHookean:
      return fn(FilteredNeoHookean::from_lame(s.mu_L, s.lambda_L, s.filter_threshold));
    case MaterialModel::Corotational: return fn(Corotational::from_lame(s.mu_L, s.lambda_L));
    case MaterialModel::FixedCorotational: return fn(FixedCorotational::from_lame(s.mu_L, s.lambda_L));
    case MaterialModel::StVK: return fn(StVK::from_lame(s.mu_L, s.lambda_L, 0.0));
    case MaterialModel::StVKKikuuwe: return fn(StVK::from_lame(s.mu_L, s.lambda_L, s.kikuuwe_kappa));
    case MaterialModel::Fung: return fn(Fung::from_lame(s.mu_L, s.lambda_L, s.fung_fraction, s.fung_exponent));
    case MaterialModel::ArrudaBoyce: return fn(ArrudaBoyce::from_lame(s.mu_L, s.lambda_L, s.ab_beta1, s.ab_beta2));
    case MaterialModel::StableNeoHookean: break;
  }
  return fn(StableNeoHookean::from_lame(s.mu_L, s.lambda_L));
}

// Names used in XML ("Model" entry) and on the command line, in enum order.
const std::vector<std::string>& material_model_names();
std::string to_string(MaterialModel m);
std::string to_string(Projection p);

}  // namespace sinew
