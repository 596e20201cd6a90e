// The non-template half of the parameter machinery: messages, the unknown-entry check, type checks and
// the reference printer.
#include <sinew/core/parameters.hpp>

#include <algorithm>
#include <cstdio>
#include <iomanip>

namespace sinew {

std::string format_number(double x) {
  if (!std::isfinite(x)) return std::isnan(x) ? "nan" : (x > 0 ? "inf" : "-inf");
  char buf[64];
  if (x == std::floor(x) && std::fabs(x) < 1e5) {
    std::snprintf(buf, sizeof buf, "%.0f", x);
    return buf;
  }
  std::snprintf(buf, sizeof buf, "%g", x);
  // 1e+06 -> 1e6, 2.5e-07 -> 2.5e-7: the way people write exponents.
  std::string s = buf;
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
