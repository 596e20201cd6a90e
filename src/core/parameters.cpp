// The non-template half of the parameter machinery: messages, the unknown-entry check, type checks and
// the reference printer.
#include <sinew/core/parameters.hpp>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <iomanip>
#include <map>
#include <stdexcept>

namespace sinew {

namespace {

// 1e+06 -> 1e6, 2.5e-07 -> 2.5e-7: the way people write exponents.
std::string plain_exponent(std::string s) {
  const auto e = s.find('e');
  if (e != std::string::npos) {
    std::string mant = s.substr(0, e), exp = s.substr(e + 1);
    const bool neg = exp[0] == '-';
    if (exp[0] == '+' || exp[0] == '-') exp = exp.substr(1);
    while (exp.size() > 1 && exp[0] == '0') exp = exp.substr(1);
    s = mant + "e" + (neg ? "-" : "") + exp;
  }
  return s;
}

}  // namespace

std::string format_number(double x) {
  if (!std::isfinite(x)) return std::isnan(x) ? "nan" : (x > 0 ? "inf" : "-inf");
  char buf[64];
  if (x == std::floor(x) && std::fabs(x) < 1e5) {
    std::snprintf(buf, sizeof buf, "%.0f", x);
    return buf;
  }
  std::snprintf(buf, sizeof buf, "%g", x);
  return plain_exponent(buf);
}

std::string round_trip_number(double x) {
  if (!std::isfinite(x)) return format_number(x);
  char buf[64];
  if (x == std::floor(x) && std::fabs(x) < 1e15) {
    std::snprintf(buf, sizeof buf, "%.0f", x);
    return buf;
  }
  for (int digits = 1; digits <= 17; ++digits) {
    std::snprintf(buf, sizeof buf, "%.*g", digits, x);
    if (std::strtod(buf, nullptr) == x) break;
  }
  return plain_exponent(buf);
}

namespace {

void escape_into(std::string& out, const std::string& s) {
  for (const char c : s) {
    if (c == '\\' || c == '=')
      (out += '\\') += c;
    else if (c == '\n')
      out += "\\n";
    else
      out += c;
  }
}

}  // namespace

std::string encode_entries(const std::vector<SectionEntry>& entries) {
  std::string out;
  for (const auto& e : entries) {
    escape_into(out, e.path);
    out += '=';
    escape_into(out, e.value);
    out += '\n';
  }
  return out;
}

std::vector<SectionEntry> decode_entries(const std::string& text) {
  std::vector<SectionEntry> out;
  SectionEntry e;
  std::string* field = &e.path;
  bool have_value = false;
  for (std::size_t k = 0; k < text.size(); ++k) {
    const char c = text[k];
    if (c == '\\') {
      if (++k == text.size()) throw std::invalid_argument("an entry list ends inside an escape");
      const char n = text[k];
      if (n == 'n')
        *field += '\n';
      else if (n == '\\' || n == '=')
        *field += n;
      else
        throw std::invalid_argument(std::string("an entry list has the unknown escape \\") + n);
    } else if (c == '=' && !have_value) {
      have_value = true;
      field = &e.value;
    } else if (c == '\n') {
      if (!have_value || e.path.empty()) throw std::invalid_argument("an entry list has a line without 'path=value'");
      out.push_back(e);
      e = SectionEntry();
      field = &e.path;
      have_value = false;
    } else {
      *field += c;
    }
  }
  if (!e.path.empty() || have_value) throw std::invalid_argument("an entry list does not end with a newline");
  return out;
}

EntryDifference compare_entries(const std::vector<SectionEntry>& stored, const std::vector<SectionEntry>& now,
                                const std::string& prefix) {
  EntryDifference d;
  auto named = [&](const SectionEntry& e) { return "'" + prefix + e.path + "'"; };
  std::map<std::string, const SectionEntry*> before;
  for (const auto& e : stored) before[e.path] = &e;
  for (const auto& e : now) {
    const auto it = before.find(e.path);
    if (it == before.end()) {
      if (e.at_default)
        d.new_at_default.push_back(named(e) + " (" + e.value + ")");
      else
        d.differ.push_back(named(e) + " " + e.value + " here, which that run did not have");
      continue;
    }
    if (it->second->value != e.value)
      d.differ.push_back(named(e) + " " + it->second->value + " there, " + e.value + " here");
    before.erase(it);
  }
  // What is left the earlier run had and this one does not, in the order it recorded them.
  for (const auto& e : stored)
    if (before.count(e.path)) d.differ.push_back(named(e) + " " + e.value + " there, which this run does not have");
  return d;
}

std::string or_list(const std::vector<std::string>& names) {
  std::string s;
  for (std::size_t k = 0; k < names.size(); ++k) {
    if (k > 0) s += (k + 1 == names.size()) ? " or " : ", ";
    s += names[k];
  }
  return s;
}

namespace param_detail {

std::string range_message(const char* name, const Range& r, double value, int component) {
  const std::string who = "'" + std::string(name) + "'" + (component >= 0 ? " entries" : "");
  const std::string got = ", got " + format_number(value);
  const bool has_lo = std::isfinite(r.lo), has_hi = std::isfinite(r.hi);
  if (!has_lo && !has_hi) return who + " must be finite" + got;
  if (has_lo && has_hi)
    return who + " must lie in " + (r.lo_open ? "(" : "[") + format_number(r.lo) + ", " + format_number(r.hi) +
           (r.hi_open ? ")" : "]") + got;
  if (has_lo) {
    if (r.lo == 0.0) return who + (r.lo_open ? " must be positive and finite" : " must be >= 0") + got;
    return who + (r.lo_open ? " must be greater than " : " must be at least ") + format_number(r.lo) + got;
  }
  return who + (r.hi_open ? " must be less than " : " must be at most ") + format_number(r.hi) + got;
}

}  // namespace param_detail

void Parser::require_sublist(const char* name) const {
  if (!in_.isSublist(name))
    throw InputError("'" + std::string(name) + "' in " + where_ + " must be a sublist", InputErrorKind::WrongType);
}

void Parser::require_type(const char* name, const Teuchos::any& want) const {
  const auto& have = in_.getEntry(name);
  if (have.isList())
    throw InputError("'" + std::string(name) + "' in " + where_ + " must be a parameter, not a sublist",
                     InputErrorKind::WrongType);
  if (have.getAny(false).type() != want.type())
    throw InputError("'" + std::string(name) + "' in " + where_ + " has type " + have.getAny(false).typeName() +
                         ", expected " + want.typeName(),
                     InputErrorKind::WrongType);
}

void Parser::finish() {
  for (auto it = in_.begin(); it != in_.end(); ++it) {
    const std::string& key = in_.name(it);
    if (std::find(known_.begin(), known_.end(), key) != known_.end()) continue;
    if (other_sublists_ && in_.entry(it).isList()) {
      pending_other_(key);
      continue;
    }
    std::string msg = "unknown entry '" + key + "' in " + where_;
    const std::string near = closest_name(key, known_);
    if (!near.empty()) msg += " (did you mean '" + near + "'?)";
    throw InputError(msg, InputErrorKind::UnknownEntry);
  }
}

void Printer::line(const char* name, const std::string& type, const std::string& def, const std::string& doc) {
  os_ << std::string(2 * indent_ + 2, ' ') << name << " (" << type << ", default " << def << ")\n"
      << std::string(2 * indent_ + 6, ' ') << doc << "\n";
}

void Printer::open(const char* name, const std::string& doc, int extra) {
  os_ << std::string(2 * (indent_ + extra) + 2, ' ') << name << "/  (sublist)\n"
      << std::string(2 * (indent_ + extra) + 6, ' ') << doc << "\n";
}

}  // namespace sinew
