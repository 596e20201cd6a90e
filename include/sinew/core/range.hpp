// The allowed range of a numeric parameter, declared next to the parameter itself (also inside the
// material headers, which must stay free of Trilinos types so that they compile for a device).
#pragma once

#include <cmath>
#include <limits>
#include <sstream>
#include <string>

namespace sinew {

struct Range {
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  bool lo_open = true, hi_open = true;

  static Range any() { return {}; }
  static Range positive() { return {0.0, std::numeric_limits<double>::infinity(), true, true}; }
  static Range non_negative() { return {0.0, std::numeric_limits<double>::infinity(), false, true}; }
  static Range at_least(double a) { return {a, std::numeric_limits<double>::infinity(), false, true}; }
  static Range closed(double a, double b) { return {a, b, false, false}; }
  static Range open(double a, double b) { return {a, b, true, true}; }
  static Range closed_open(double a, double b) { return {a, b, false, true}; }
  static Range open_closed(double a, double b) { return {a, b, true, false}; }

  bool contains(double x) const {
    if (std::isnan(x)) return false;
    const bool above = lo_open ? x > lo : x >= lo;
    const bool below = hi_open ? x < hi : x <= hi;
    return above && below;
  }

  // "> 0", ">= 1", "in [0, 1)"; empty for any finite number.
  std::string describe() const {
    const bool has_lo = std::isfinite(lo), has_hi = std::isfinite(hi);
    std::ostringstream os;
    os.precision(6);
    if (has_lo && has_hi)
      os << "in " << (lo_open ? "(" : "[") << lo << ", " << hi << (hi_open ? ")" : "]");
    else if (has_lo)
      os << (lo_open ? "> " : ">= ") << lo;
    else if (has_hi)
      os << (hi_open ? "< " : "<= ") << hi;
    return os.str();
  }
};

}  // namespace sinew
