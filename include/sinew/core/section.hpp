// The Trilinos-free half of parameter sections (see core/parameters.hpp for the whole story): the
// containers sections use and the visitor that fills in defaults. Material headers include only this,
// so they still compile for a device.
#pragma once

#include <sinew/core/range.hpp>

#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace sinew {

// Sublists of one section type keyed by user-chosen names, in file order (boundary conditions, bones).
template <class S>
using NamedSections = std::vector<std::pair<std::string, S>>;

// The (name, value) pairs of a choice entry.
template <class E>
using Choices = std::vector<std::pair<std::string, E>>;

namespace section_detail {
template <class T>
struct identity {
  using type = T;
};
// Keeps a default argument from taking part in template deduction: the field's type decides.
template <class T>
using identity_t = typename identity<T>::type;
}  // namespace section_detail

// Sets every entry of a section to its declared default.
class Defaulter {
 public:
  template <class T>
  void entry(const char*, T& field, const section_detail::identity_t<T>& def, const std::string&, Range = Range::any()) {
    field = def;
  }
  template <class T>
  void optional(const char*, std::optional<T>& field, const std::string&, Range = Range::any()) {
    field.reset();
  }
  template <class E>
  void choice(const char*, E& field, const section_detail::identity_t<E>& def, const Choices<E>&, const std::string&) {
    field = def;
  }
  template <class S>
  void section(const char*, S& sub, const std::string&) {
    sub.visit(*this);
  }
  template <class S>
  void sections(const char*, NamedSections<S>& subs, const std::string&) {
    subs.clear();
  }
  template <class S>
  void inline_section(S& sub) {
    sub.visit(*this);
  }
  template <class S>
  void other_sublists(NamedSections<S>& subs, const std::string&) {
    subs.clear();
  }
  template <class List>
  void raw(const char*, List& out, const std::string&) {
    out = List();
  }
};

// A section with every entry at its default: the only way to get one, so no default lives elsewhere.
template <class S>
S default_section() {
  S s{};
  Defaulter d;
  s.visit(d);
  return s;
}

}  // namespace sinew
