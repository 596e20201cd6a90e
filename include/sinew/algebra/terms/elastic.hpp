// The elastic energy of the mesh, E = sum over elements and quadrature points of w Psi(F) (Eq. 14 and
// the models it is compared with), its gradient and its per-point projected Hessian (Sec. 4): the
// element loop (discretization/element_kernel.hpp) run block by block, one block per material law, so
// each law's kernel is its own instantiation with no per-element switch.
#pragma once

#include <sinew/algebra/energy_term.hpp>
#include <sinew/algebra/node_relaxation.hpp>
#include <sinew/discretization/elements.hpp>
#include <sinew/materials/models.hpp>

#include <string>
#include <vector>

namespace sinew {

struct MaterialAssignment;

class ElasticTerm final : public EnergyTerm {
 public:
  // Throws InputError when a region of `materials` is not an element group of the mesh. Holds
  // references to mesh and elements, which must outlive it.
  ElasticTerm(const Mesh& mesh, const ElementData& elements, const MaterialAssignment& materials);

  const char* name() const override { return "elastic"; }
  void add(const TermInput& in, TermOutput& out) const override;
  // Node relaxation is this term's own local solve (relax below).
  bool allows_node_relaxation(std::vector<char>&) const override { return true; }

  // The law of elements in no region (blocks_[0], possibly with no elements).
  const MaterialSpec& default_law() const { return blocks_.front().law; }
  // Largest (mu_L + |lambda_L|) over the laws with elements.
  double stiffness_scale() const;
  // The density of each local element's law.
  std::vector<double> element_density() const;
  // Owned elements per region, in the order the regions were given (not the default law's block).
  std::vector<long long> owned_region_elements() const;
  // Moves each of `nodes` (local ids whose elements are all on this rank) in turn to lower the energy of
  // its elements plus the rest of the energy, linearised: `force` holds the total gradient at each node
  // (3 per node, in the order of `nodes`) at the start. u holds the displacements of the local nodes
  // (3 per node) and is updated. Host memory only (returns nothing done otherwise).
  NodeRelaxationTotals relax(std::vector<double>& u, const std::vector<int>& nodes, const std::vector<double>& force,
                             const NodeRelaxationSettings& settings) const;

 private:
  struct Block {
    MaterialSpec law;
    Kokkos::View<int*> elements;  // local element ids, in coloured chunks (discretization/colouring.hpp)
    Kokkos::View<int*> chunks;    // chunk c is elements [chunks(c), chunks(c + 1)); empty: atomic adds
    std::vector<int> colour_begin;
  };
  const Mesh& mesh_;
  const ElementData& elements_;
  std::vector<Block> blocks_;
};

}  // namespace sinew
