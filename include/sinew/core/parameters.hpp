// Parameter sections declared once, in the manner of deal.II step-44's Parameters structs: a section is
// a plain struct whose `visit` member names every entry with its default, range and documentation,
//
//   struct LoadingParameters {
//     int steps;
//     template <class V> void visit(V& v) {
//       v.entry("Steps", steps, 1, "number of quasi-static load steps", Range::closed(1, 1e6));
//     }
//     void check(const SectionContext& c) const;   // optional: rules that tie entries together
//   };
//
// and the same `visit` serves every purpose: `declare_section<S>()` builds the list of valid entries
// (for `sinew --parameters`), `parse_section<S>(list, where)` reads a user's list into the struct with
// strict type, finiteness and range checks (naming the culprit), and `default_section<S>()` fills in the
// defaults. Nothing else may hold a default.
//
// Visitor vocabulary (all names are const char*):
//   entry(name, field, default, doc [, range])       bool, int, double, string, std::array<int|double, N>
//   optional(name, std::optional<T>& field, doc [, range])   no default: absent stays empty
//   choice(name, field, default, Choices<E>, doc)    a string picked from a list, stored as E
//   section(name, S& sub, doc)                       a nested sublist of a fixed shape
//   sections(name, NamedSections<S>& subs, doc)      a sublist whose sublists are user-named S's
//   inline_section(S& sub)                           S's entries at this level
//   other_sublists(NamedSections<S>& subs, doc)      every undeclared sublist at this level is an S
//   raw(name, Teuchos::ParameterList& out, doc)      passed through unchecked (NOX, Stratimikos)
#pragma once

#include <sinew/core/errors.hpp>
#include <sinew/core/range.hpp>
#include <sinew/core/section.hpp>
#include <sinew/core/validation.hpp>

#include <Teuchos_Array.hpp>
#include <Teuchos_ParameterList.hpp>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <optional>
#include <ostream>
#include <sstream>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace sinew {

// A number as people write it: integers plainly, large round numbers as 1e6, others with 6 digits.
std::string format_number(double x);

// "a, b or c"
std::string or_list(const std::vector<std::string>& names);

// What a section's check() sees: where it is (for messages) and which entries the user gave.
class SectionContext {
 public:
  SectionContext(const Teuchos::ParameterList& in, std::string where) : in_(in), where_(std::move(where)) {}
  bool given(const std::string& name) const { return in_.isParameter(name); }
  const std::string& where() const { return where_; }
  [[noreturn]] void fail(const std::string& message, InputErrorKind kind = InputErrorKind::InvalidValue) const {
    throw InputError(where_ + ": " + message, kind);
  }

 private:
  const Teuchos::ParameterList& in_;
  std::string where_;
};

namespace param_detail {

// Field type <-> the Teuchos type an XML file gives it.
template <class T>
struct Conv {
  using teuchos = T;
  static teuchos to(const T& v) { return v; }
  static T from(const teuchos& v, const std::string&, const std::string&) { return v; }
  template <class F>
  static void each_number(const T& v, F&& f) {
    if constexpr (std::is_arithmetic_v<T> && !std::is_same_v<T, bool>) f(static_cast<double>(v), -1);
  }
};
template <class N, std::size_t K>
struct Conv<std::array<N, K>> {
  using teuchos = Teuchos::Array<N>;
  static teuchos to(const std::array<N, K>& v) { return teuchos(v.begin(), v.end()); }
  static std::array<N, K> from(const teuchos& v, const std::string& where, const char* name) {
    if (v.size() != K)
      throw InputError(where + ": '" + name + "' needs " + std::to_string(K) + " entries, got " + std::to_string(v.size()));
    std::array<N, K> out{};
    for (std::size_t k = 0; k < K; ++k) out[k] = v[k];
    return out;
  }
  template <class F>
  static void each_number(const std::array<N, K>& v, F&& f) {
    for (std::size_t k = 0; k < K; ++k) f(static_cast<double>(v[k]), static_cast<int>(k));
  }
};
template <class N>
struct Conv<std::vector<N>> {
  using teuchos = Teuchos::Array<N>;
  static teuchos to(const std::vector<N>& v) { return teuchos(v.begin(), v.end()); }
  static std::vector<N> from(const teuchos& v, const std::string&, const std::string&) { return std::vector<N>(v.begin(), v.end()); }
  template <class F>
  static void each_number(const std::vector<N>& v, F&& f) {
    for (std::size_t k = 0; k < v.size(); ++k) f(static_cast<double>(v[k]), static_cast<int>(k));
  }
};

inline std::string with_range(const std::string& doc, const Range& r) {
  const std::string d = r.describe();
  return d.empty() ? std::string(doc) : std::string(doc) + " [" + d + "]";
}

template <class E>
std::vector<std::string> names_of(const Choices<E>& options) {
  std::vector<std::string> n;
  for (const auto& o : options) n.push_back(o.first);
  return n;
}
template <class E>
std::string name_of(const Choices<E>& options, const E& value) {
  for (const auto& o : options)
    if (o.second == value) return o.first;
  return "?";
}

// "'Poisson ratio' must lie in (-1, 0.5), got 0.5" and its siblings.
std::string range_message(const char* name, const Range& r, double value, int component);

}  // namespace param_detail

// Builds the list of valid entries with defaults and documentation.
class Declarer {
 public:
  explicit Declarer(Teuchos::ParameterList& list) : list_(list) {}
  template <class T>
  void entry(const char* name, T&, const section_detail::identity_t<T>& def, const std::string& doc, Range r = Range::any()) {
    list_.set(name, param_detail::Conv<T>::to(def), param_detail::with_range(doc, r));
  }
  template <class T>
  void optional(const char* name, std::optional<T>&, const std::string& doc, Range r = Range::any()) {
    list_.set(name, param_detail::Conv<T>::to(T{}), param_detail::with_range(doc, r) + " (optional, no default)");
  }
  template <class E>
  void choice(const char* name, E&, const section_detail::identity_t<E>& def, const Choices<E>& options, const std::string& doc) {
    list_.set(name, param_detail::name_of(options, def), std::string(doc) + ": " + or_list(param_detail::names_of(options)));
  }
  template <class S>
  void section(const char* name, S& sub, const std::string& doc) {
    Declarer d(list_.sublist(name, false, doc));
    sub.visit(d);
  }
  template <class S>
  void sections(const char* name, NamedSections<S>&, const std::string& doc) {
    list_.sublist(name, false, doc);
  }
  template <class S>
  void inline_section(S& sub) {
    sub.visit(*this);
  }
  template <class S>
  void other_sublists(NamedSections<S>&, const std::string&) {}
  void raw(const char* name, Teuchos::ParameterList&, const std::string& doc) { list_.sublist(name, false, doc); }

 private:
  Teuchos::ParameterList& list_;
};

template <class S>
Teuchos::ParameterList declare_section(const std::string& name) {
  Teuchos::ParameterList valid(name);
  S s = default_section<S>();
  Declarer d(valid);
  s.visit(d);
  return valid;
}

template <class S>
S parse_section(const Teuchos::ParameterList& in, const std::string& where);

// Reads a user's list: strict types, finite numbers in range, no unknown entries (with a suggestion),
// then the section's own check(). Throws InputError naming `where` and the entry.
class Parser {
 public:
  Parser(const Teuchos::ParameterList& in, std::string where) : in_(in), where_(std::move(where)) {}

  template <class T>
  void entry(const char* name, T& field, const section_detail::identity_t<T>& def, const std::string&, Range r = Range::any()) {
    known_.emplace_back(name);
    if (!in_.isParameter(name)) {
      field = def;
      return;
    }
    field = read<T>(name, r);
  }
  template <class T>
  void optional(const char* name, std::optional<T>& field, const std::string&, Range r = Range::any()) {
    known_.emplace_back(name);
    if (in_.isParameter(name))
      field = read<T>(name, r);
    else
      field.reset();
  }
  template <class E>
  void choice(const char* name, E& field, const section_detail::identity_t<E>& def, const Choices<E>& options, const std::string&) {
    known_.emplace_back(name);
    if (!in_.isParameter(name)) {
      field = def;
      return;
    }
    const std::string v = read<std::string>(name, Range::any());
    for (const auto& o : options)
      if (o.first == v) {
        field = o.second;
        return;
      }
    const auto names = param_detail::names_of(options);
    std::string msg = "'" + std::string(name) + "' must be " + or_list(names) + ", got \"" + v + "\"";
    const std::string near = closest_name(v, names);
    if (!near.empty()) msg += " (did you mean \"" + near + "\"?)";
    throw InputError(where_ + ": " + msg);
  }
  template <class S>
  void section(const char* name, S& sub, const std::string&) {
    known_.emplace_back(name);
    if (!in_.isParameter(name)) {
      sub = default_section<S>();
      return;
    }
    require_sublist(name);
    sub = parse_section<S>(in_.sublist(name), child(name));
  }
  template <class S>
  void sections(const char* name, NamedSections<S>& subs, const std::string&) {
    known_.emplace_back(name);
    subs.clear();
    if (!in_.isParameter(name)) return;
    require_sublist(name);
    const auto& list = in_.sublist(name);
    for (auto it = list.begin(); it != list.end(); ++it) {
      const std::string& key = list.name(it);
      const std::string path = child(name) + "/" + key;
      if (!list.entry(it).isList()) throw InputError(path + " must be a sublist", InputErrorKind::WrongType);
      subs.emplace_back(key, parse_section<S>(list.sublist(key), path));
    }
  }
  template <class S>
  void inline_section(S& sub) {
    sub.visit(*this);
    check_of(sub);
  }
  template <class S>
  void other_sublists(NamedSections<S>& subs, const std::string&) {
    other_sublists_ = true;
    subs.clear();
    pending_other_ = [this, &subs](const std::string& key) {
      subs.emplace_back(key, parse_section<S>(in_.sublist(key), child(key.c_str())));
    };
  }
  void raw(const char* name, Teuchos::ParameterList& out, const std::string&) {
    known_.emplace_back(name);
    out = Teuchos::ParameterList(name);
    if (!in_.isParameter(name)) return;
    require_sublist(name);
    out = in_.sublist(name);
  }

  // Unknown entries, and the undeclared sublists when the section takes them.
  void finish();

  template <class S>
  void check_of(const S& s) {
    if constexpr (has_check<S>(0)) s.check(SectionContext(in_, where_));
  }

 private:
  template <class S>
  static constexpr auto has_check(int) -> decltype(std::declval<const S&>().check(std::declval<const SectionContext&>()), bool()) {
    return true;
  }
  template <class S>
  static constexpr bool has_check(...) {
    return false;
  }

  std::string child(const char* name) const { return where_ == "the top-level list" ? std::string(name) : where_ + "/" + name; }
  void require_sublist(const char* name) const;
  // Type of the entry against T's Teuchos type, conversion, finiteness and range of every number.
  template <class T>
  T read(const char* name, const Range& r) const {
    using C = param_detail::Conv<T>;
    require_type(name, Teuchos::any(typename C::teuchos()));
    const T v = C::from(in_.get<typename C::teuchos>(name), where_, name);
    C::each_number(v, [&](double x, int component) {
      if (!std::isfinite(x) || !r.contains(x))
        throw InputError(where_ + ": " + param_detail::range_message(name, r, x, component));
    });
    return v;
  }
  void require_type(const char* name, const Teuchos::any& want) const;

  const Teuchos::ParameterList& in_;
  std::string where_;
  std::vector<std::string> known_;
  bool other_sublists_ = false;
  std::function<void(const std::string&)> pending_other_;
};

template <class S>
S parse_section(const Teuchos::ParameterList& in, const std::string& where) {
  S s = default_section<S>();
  Parser p(in, where);
  s.visit(p);
  p.finish();
  p.check_of(s);
  return s;
}

// `sinew --parameters`: every entry of a section with type, default, range and documentation; named
// sublists are shown once with "<name>" for the user's names.
class Printer {
 public:
  Printer(std::ostream& os, std::string path, int indent = 0) : os_(os), path_(std::move(path)), indent_(indent) {}
  template <class T>
  void entry(const char* name, T&, const section_detail::identity_t<T>& def, const std::string& doc, Range r = Range::any()) {
    line(name, type_name(param_detail::Conv<T>::to(def)), value_text(param_detail::Conv<T>::to(def)), param_detail::with_range(doc, r));
  }
  template <class T>
  void optional(const char* name, std::optional<T>&, const std::string& doc, Range r = Range::any()) {
    line(name, type_name(param_detail::Conv<T>::to(T{})), "(none)", param_detail::with_range(doc, r));
  }
  template <class E>
  void choice(const char* name, E&, const section_detail::identity_t<E>& def, const Choices<E>& options, const std::string& doc) {
    line(name, "string", "\"" + param_detail::name_of(options, def) + "\"", std::string(doc) + ": " + or_list(param_detail::names_of(options)));
  }
  template <class S>
  void section(const char* name, S& sub, const std::string& doc) {
    open(name, doc);
    Printer p(os_, path_ + "/" + name, indent_ + 1);
    sub.visit(p);
  }
  template <class S>
  void sections(const char* name, NamedSections<S>&, const std::string& doc) {
    open(name, doc);
    open("<name>", "one sublist per item, named as you like", 1);
    S s = default_section<S>();
    Printer p(os_, path_ + "/" + name + "/<name>", indent_ + 2);
    s.visit(p);
  }
  template <class S>
  void inline_section(S& sub) {
    sub.visit(*this);
  }
  template <class S>
  void other_sublists(NamedSections<S>&, const std::string& doc) {
    open("<name>", doc);
    S s = default_section<S>();
    Printer p(os_, path_ + "/<name>", indent_ + 1);
    s.visit(p);
  }
  void raw(const char* name, Teuchos::ParameterList&, const std::string& doc) { open(name, doc); }

 private:
  template <class V>
  static std::string type_name(const V& v) {
    return Teuchos::any(v).typeName();
  }
  template <class V>
  static std::string value_text(const V& v) {
    Teuchos::ParameterList l;
    l.set("x", v);
    std::ostringstream os;
    os << l.getEntry("x").getAny(false);
    return os.str();
  }
  void line(const char* name, const std::string& type, const std::string& def, const std::string& doc);
  void open(const char* name, const std::string& doc, int extra = 0);

  std::ostream& os_;
  std::string path_;
  int indent_;
};

template <class S>
void print_section(std::ostream& os, const std::string& title) {
  os << "== " << title << " ==\n";
  S s = default_section<S>();
  Printer p(os, title);
  s.visit(p);
  os << "\n";
}

// One entry of a section as a checkpoint records it: its path within the section ("Leaf/Gain"), its
// value as people read it (numbers to the digits that round-trip), and whether that is its default.
struct SectionEntry {
  std::string path, value;
  bool at_default = false;
};

// The shortest decimal text that reads back as x exactly.
std::string round_trip_number(double x);

// Entries as one text, "path=value" per line ('\\', '=' and newlines escaped), and back. Throws
// std::invalid_argument on a text that is not such a list.
std::string encode_entries(const std::vector<SectionEntry>& entries);
std::vector<SectionEntry> decode_entries(const std::string& text);

// How a section's entries recorded by an earlier run (`stored`) differ from this run's (`now`):
// `differ` names every entry whose value changed, that only one side has, or that is new here at a value
// other than its default; `new_at_default` the entries the earlier run did not have (a parameter added
// since) that this run leaves at their defaults, which a new parameter's default keeps the old
// behaviour for, so they do not count as a difference. Each is named by `prefix` + its path, quoted.
struct EntryDifference {
  std::vector<std::string> differ, new_at_default;
};
EntryDifference compare_entries(const std::vector<SectionEntry>& stored, const std::vector<SectionEntry>& now,
                                const std::string& prefix = "");

// Writes a parsed section's values as canonical text, one "path=value;" per entry, defaults included
// (so neither the order of a file's entries nor whether a default is spelled out changes it; numbers
// exactly, in hexadecimal floating point). A checkpoint keeps a digest of it per physics section, so
// that a restart can tell whether it continues the same physics, and the entries themselves (`entries`),
// so that it can say which differ.
class Fingerprinter {
 public:
  explicit Fingerprinter(std::ostream& os, std::string prefix = "", std::vector<SectionEntry>* entries = nullptr)
      : os_(os), prefix_(std::move(prefix)), entries_(entries) {}

  template <class T>
  void entry(const char* name, T& field, const section_detail::identity_t<T>& def, const std::string&, Range = Range::any()) {
    put(name, field, field == def);
  }
  template <class T>
  void optional(const char* name, std::optional<T>& field, const std::string&, Range = Range::any()) {
    if (field) {
      put(name, *field, false);
    } else {
      os_ << prefix_ << name << "=(none);";
      record(name, "(none)", true);
    }
  }
  template <class E>
  void choice(const char* name, E& field, const section_detail::identity_t<E>& def, const Choices<E>& options, const std::string&) {
    const std::string v = param_detail::name_of(options, field);
    os_ << prefix_ << name << "=" << v << ";";
    record(name, v, field == def);
  }
  template <class S>
  void section(const char* name, S& sub, const std::string&) {
    Fingerprinter f(os_, prefix_ + name + "/", entries_);
    sub.visit(f);
  }
  template <class S>
  void sections(const char* name, NamedSections<S>& subs, const std::string&) {
    for (auto& [key, sub] : subs) {
      Fingerprinter f(os_, prefix_ + name + "/" + key + "/", entries_);
      sub.visit(f);
    }
  }
  template <class S>
  void inline_section(S& sub) {
    sub.visit(*this);
  }
  template <class S>
  void other_sublists(NamedSections<S>& subs, const std::string&) {
    for (auto& [key, sub] : subs) {
      Fingerprinter f(os_, prefix_ + key + "/", entries_);
      sub.visit(f);
    }
  }
  void raw(const char* name, Teuchos::ParameterList& list, const std::string&) {
    std::ostringstream text;
    text << list;
    os_ << prefix_ << name << "=" << text.str() << ";";
    record(name, text.str(), list.numParams() == 0);
  }

 private:
  template <class T>
  void put(const char* name, const T& v, bool at_default) {
    os_ << prefix_ << name << "=";
    value(v);
    os_ << ";";
    if (entries_) {
      std::ostringstream text;
      readable(text, v);
      record(name, text.str(), at_default);
    }
  }
  void record(const char* name, const std::string& v, bool at_default) {
    if (entries_) entries_->push_back({prefix_ + name, v, at_default});
  }
  template <class T>
  void value(const T& v) {
    if constexpr (std::is_same_v<T, std::string>) {
      os_ << '"' << v << '"';
    } else if constexpr (std::is_same_v<T, bool>) {
      os_ << (v ? "true" : "false");
    } else if constexpr (std::is_arithmetic_v<T>) {
      os_ << std::hexfloat << static_cast<double>(v) << std::defaultfloat;
    } else {  // std::array and std::vector of numbers
      os_ << "{";
      for (const auto& x : v) {
        value(x);
        os_ << ",";
      }
      os_ << "}";
    }
  }
  template <class T>
  static void readable(std::ostream& os, const T& v) {
    if constexpr (std::is_same_v<T, std::string>) {
      os << '"' << v << '"';
    } else if constexpr (std::is_same_v<T, bool>) {
      os << (v ? "true" : "false");
    } else if constexpr (std::is_arithmetic_v<T>) {
      os << round_trip_number(static_cast<double>(v));
    } else {
      os << "{";
      bool first = true;
      for (const auto& x : v) {
        if (!first) os << ", ";
        first = false;
        readable(os, x);
      }
      os << "}";
    }
  }

  std::ostream& os_;
  std::string prefix_;
  std::vector<SectionEntry>* entries_;
};

// A section's digest (16 hex digits, FNV-1a 64 of its canonical text) and its entries.
struct SectionFingerprint {
  std::string digest;
  std::vector<SectionEntry> entries;
};

template <class S>
SectionFingerprint section_fingerprint(const S& section) {
  S copy = section;  // visit() is not const
  std::ostringstream os;
  SectionFingerprint out;
  Fingerprinter f(os, "", &out.entries);
  copy.visit(f);
  std::uint64_t h = 1469598103934665603ull;
  for (const unsigned char c : os.str()) h = (h ^ c) * 1099511628211ull;
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(h));
  out.digest = hex;
  return out;
}

}  // namespace sinew
