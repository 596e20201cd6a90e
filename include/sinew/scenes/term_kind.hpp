// How a scene file adds an energy term: a term kind is a struct with
//   using Parameters = ...;               its section, declared once (visit, optional check)
//   static constexpr const char* section  the section's name in the scene file ("Pressure")
//   static constexpr const char* doc      one line for sinew --parameters
//   static bool active(const Parameters&) whether the scene asked for the term
//   static std::shared_ptr<EnergyTerm> make(const Parameters&, const TermContext&)
//   static void resolve_paths(Parameters&, const std::function<void(std::string&)>&)   (optional: file
//                                          names in the section, taken from the scene file's folder)
// and TermKinds<K...> (term_registry.hpp lists them) holds their sections in a scene's parameters,
// parses, checks, documents and fingerprints them with the rest (one visit), and adds the active terms
// to the scene's system in the listed order. A new term is its own header and one line in the list.
#pragma once

#include <sinew/algebra/system.hpp>

#include <Teuchos_Comm.hpp>

#include <functional>
#include <memory>
#include <string>
#include <tuple>
#include <utility>

namespace sinew {

// What a term's make() may use: the system (its mesh and maps), the communicator, the skeleton, and
// whether the run is dynamic (loads in full from the start rather than ramped). make() throws InputError naming the
// section's entry at fault; the scene adds the file's name.
class Skeleton;
struct TermContext {
  System& system;
  const Teuchos::Comm<int>& comm;
  const Skeleton& skeleton;  // bones a term may follow (colliders carried by a bone)
  bool dynamic = false;
};

template <class... Kinds>
struct TermKinds {
  std::tuple<typename Kinds::Parameters...> parameters;

  template <class V>
  void visit(V& v) {
    visit_each(v, std::index_sequence_for<Kinds...>{});
  }
  // Adds each active term to the context's system (collective).
  void add_terms(const TermContext& c) const { add_each(c, std::index_sequence_for<Kinds...>{}); }
  // The section of kind K.
  template <class K>
  typename K::Parameters& of() {
    return std::get<typename K::Parameters>(parameters);
  }
  template <class K>
  const typename K::Parameters& of() const {
    return std::get<typename K::Parameters>(parameters);
  }
  // Relative file names in the sections, resolved by `resolve` (kinds that have any say so).
  void resolve_paths(const std::function<void(std::string&)>& resolve) {
    resolve_each(resolve, std::index_sequence_for<Kinds...>{});
  }
  // The section names, in order (the checkpoint's physics list).
  static std::vector<std::string> sections() { return {Kinds::section...}; }
  // Each section's parameters with f(name, parameters).
  template <class F>
  void for_each(F&& f) const {
    for_each_impl(f, std::index_sequence_for<Kinds...>{});
  }

 private:
  template <class K>
  static auto resolve_one(typename K::Parameters& p, const std::function<void(std::string&)>& r, int)
      -> decltype(K::resolve_paths(p, r), void()) {
    K::resolve_paths(p, r);
  }
  template <class K>
  static void resolve_one(typename K::Parameters&, const std::function<void(std::string&)>&, long) {}
  template <std::size_t... I>
  void resolve_each(const std::function<void(std::string&)>& r, std::index_sequence<I...>) {
    (resolve_one<Kinds>(std::get<I>(parameters), r, 0), ...);
  }
  template <class V, std::size_t... I>
  void visit_each(V& v, std::index_sequence<I...>) {
    (v.section(Kinds::section, std::get<I>(parameters), Kinds::doc), ...);
  }
  template <std::size_t... I>
  void add_each(const TermContext& c, std::index_sequence<I...>) const {
    (add_one<Kinds>(c, std::get<I>(parameters)), ...);
  }
  template <class K>
  static void add_one(const TermContext& c, const typename K::Parameters& p) {
    if (K::active(p)) c.system.add_term(K::make(p, c));
  }
  template <class F, std::size_t... I>
  void for_each_impl(F& f, std::index_sequence<I...>) const {
    (f(Kinds::section, std::get<I>(parameters)), ...);
  }
};

}  // namespace sinew
