// The list of material models: adding a model means writing its header (see material.hpp for what a
// model provides) and adding its line below. Everything else (the XML "Model" names, parameters and
// their validation, `sinew --parameters`, the kernels instantiated per model, the material tests and
// benchmarks) is generated from this list.
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

// X(struct name): one line per model, in the order `sinew --parameters` lists them. Every line ends
// with a backslash so that a new model is one added line; the comment below closes the list.
#define SINEW_MATERIAL_MODELS(X) \
  X(StableNeoHookean)            \
  X(StableNeoHookeanNoBarrier)   \
  X(NeoHookean)                  \
  X(FilteredNeoHookean)          \
  X(Corotational)                \
  X(FixedCorotational)           \
  X(StVK)                        \
  X(StVKKikuuwe)                 \
  X(Fung)                        \
  X(ArrudaBoyce)                 \
  // (end of the list)
