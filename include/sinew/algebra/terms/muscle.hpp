// Muscles as a term of the energy: the fibre energy of materials/fiber.hpp integrated over each
// muscle's elements, E = sum over its elements and quadrature points of w Psi_f(F; a_e, alpha(t)), with
// a_e the element's unit fibre direction at rest and alpha(t) the muscle's activation at the load
// fraction t. It adds to the elastic term's isotropic energy of the same elements (the muscle's
// matrix), on the same element graph, so the Hessian needs no new couplings. The element loop is the
// elastic one's (discretization/element_kernel.hpp: gather, per-point F, scatter) with the fibre as
// its "model"; in coloured chunks on the host, as the elastic term runs (sums independent of the thread
// count), one element per work item with atomic adds on a device; default execution space or Serial.
//
// Where a muscle's fibres point and how its activation follows the load is the scene's business
// (scenes/terms/muscle.hpp): this term takes them as arrays and a function.
#pragma once

#include <sinew/algebra/energy_term.hpp>
#include <sinew/discretization/elements.hpp>
#include <sinew/materials/fiber.hpp>

#include <Teuchos_Comm.hpp>

#include <array>
#include <functional>
#include <string>
#include <vector>

namespace sinew {

// One muscle: its law, its local elements (owned and ghost) with their unit fibre directions, and its
// activation in [0, 1] as a function of the load fraction (the same on every rank).
struct MuscleBlock {
  std::string name;
  FiberLaw law;
  std::vector<int> elements;
  std::vector<std::array<double, 3>> fibers;  // per entry of `elements`
  std::function<double(double load)> activation;
};

class MuscleTerm final : public EnergyTerm {
 public:
  // Holds references to mesh and element data, which must outlive it. Throws std::invalid_argument
  // for a fibre that is not a unit vector or a law that is not valid (the scene checks both first).
  MuscleTerm(Teuchos::RCP<const Teuchos::Comm<int>> comm, const Mesh& mesh, const ElementData& elements,
             std::vector<MuscleBlock> muscles);

  const char* name() const override { return "muscle"; }
  void add(const TermInput& in, TermOutput& out) const override;
  void set_load(double t) override;

  // Per muscle: its activation, its owned elements' smallest and largest fibre stretch (at the
  // quadrature points of the last evaluation with forces, reduced over ranks), as log columns and a
  // summary line.
  std::vector<std::string> log_columns() const override;
  std::vector<double> log_values(const EvaluationTotals& totals) const override;
  std::vector<std::string> summary(const EvaluationTotals& totals) const override;
  // Per owned element: "fiber" (the unit direction at rest; 0 outside every muscle) and "activation".
  void element_fields(std::vector<TermState::Nodal>& fields) const override;

  double activation(std::size_t m) const { return blocks_[m].activation_now; }
  // The smallest and largest fibre stretch of muscle m at the last evaluation (all ranks; collective).
  std::array<double, 2> stretch_range(std::size_t m) const;

 private:
  struct Block {
    MuscleBlock spec;
    Kokkos::View<int*> elements;       // in coloured chunks, as the elastic term's blocks
    Kokkos::View<double* [3]> fibers;  // per entry of `elements`
    Kokkos::View<int*> chunks;         // chunk c is elements [chunks(c), chunks(c + 1)); empty: atomic adds
    std::vector<int> colour_begin;
    double activation_now = 0.0;
    mutable double min_stretch = 1.0, max_stretch = 1.0;  // this rank's owned points, last evaluation
  };
  Teuchos::RCP<const Teuchos::Comm<int>> comm_;
  const Mesh& mesh_;
  const ElementData& elements_;
  std::vector<Block> blocks_;
};

}  // namespace sinew
