// Strict reading of XML parameter lists: file checks, a nesting pre-scan (the XML parser recurses),
// then every Parameter's number checked and every list's names checked for duplicates before Teuchos
// converts the tree.
#include <sinew/core/errors.hpp>
#include <sinew/core/xml_input.hpp>

#include <Teuchos_ParameterList.hpp>
#include <Teuchos_StringInputSource.hpp>
#include <Teuchos_XMLParameterListReader.hpp>

#include <cctype>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

namespace sinew {

namespace {

constexpr std::uintmax_t kMaxFileBytes = 64u << 20;  // a scene file is a few kB; refuse absurd ones
constexpr int kMaxDepth = 64;

std::string trim(const std::string& s) {
  std::size_t b = 0, e = s.size();
  while (b < e && std::isspace(static_cast<unsigned char>(s[b]))) ++b;
  while (e > b && std::isspace(static_cast<unsigned char>(s[e - 1]))) --e;
  return s.substr(b, e - b);
}

bool strict_bool(const std::string& text) {
  std::string t = trim(text);
  for (char& c : t) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return t == "true" || t == "false" || t == "1" || t == "0";
}

// Depth of element nesting, without parsing: refuses files that would make the parser recurse deeply.
int max_depth(const std::string& text) {
  int depth = 0, worst = 0;
  for (std::size_t i = 0; i + 1 < text.size(); ++i) {
    if (text[i] != '<') continue;
    const char n = text[i + 1];
    if (n == '?' || n == '!') continue;
    const std::size_t close = text.find('>', i);
    if (close == std::string::npos) break;
    if (n == '/')
      --depth;
    else if (text[close - 1] != '/')
      worst = std::max(worst, ++depth);
    i = close;
  }
  return worst;
}

void check_tree(const Teuchos::XMLObject& node, const std::string& file, const std::string& where) {
  const std::string name = node.hasAttribute("name") ? node.getAttribute("name") : "?";
  if (node.getTag() == "Parameter" && node.hasAttribute("type") && node.hasAttribute("value")) {
    const std::string type = node.getAttribute("type"), value = node.getAttribute("value");
    auto bad = [&](const std::string& item, const char* why) {
      throw InputError(file + ": malformed XML parameter list: '" + name + "' in " + where + " is declared " + type +
                           " but its value '" + item + "' is " + why,
                       InputErrorKind::MalformedXml);
    };
    const bool integer = type == "int" || type == "Array(int)";
    if (type == "double" || type == "int") {
      if (!strict_number(value, integer)) bad(value, integer ? "not one (or out of range)" : "not one (or not finite)");
    } else if (type == "bool") {
      if (!strict_bool(value)) bad(value, "not true or false");
    } else if (type == "Array(double)" || type == "Array(int)") {
      const std::string v = trim(value);
      if (v.size() < 2 || v.front() != '{' || v.back() != '}') bad(value, "not an array {a, b, ...}");
      const std::string inner = trim(v.substr(1, v.size() - 2));
      if (!inner.empty()) {
        std::stringstream ss(inner);
        for (std::string item; std::getline(ss, item, ',');)
          if (!strict_number(item, integer)) bad(trim(item), integer ? "not an integer" : "not a finite number");
        if (inner.back() == ',') bad("", "empty");
      }
    }
  }
  const bool is_list = node.getTag() == "ParameterList";
  const std::string here = is_list && node.hasAttribute("name") ? node.getAttribute("name") : where;
  std::set<std::string> seen;
  for (int i = 0; i < node.numChildren(); ++i) {
    const Teuchos::XMLObject& c = node.getChild(i);
    if (is_list && (c.getTag() == "Parameter" || c.getTag() == "ParameterList") && c.hasAttribute("name")) {
      const std::string key = c.getAttribute("name");
      if (!seen.insert(key).second)
        throw InputError(file + ": malformed XML parameter list: entry '" + key + "' appears twice in " + here +
                             " (a second value would silently replace the first)",
                         InputErrorKind::MalformedXml);
    }
    check_tree(c, file, here);
  }
}

Teuchos::RCP<Teuchos::ParameterList> convert(const std::string& text, const std::string& name) {
  if (max_depth(text) > kMaxDepth)
    throw InputError(name + ": malformed XML parameter list: lists nested more than " + std::to_string(kMaxDepth) +
                         " deep",
                     InputErrorKind::MalformedXml);
  Teuchos::XMLObject tree;
  try {
    tree = Teuchos::StringInputSource(text).getObject();
  } catch (const std::exception& e) {
    std::string what = e.what();
    // Teuchos' messages carry a source-location banner; keep the informative last line.
    auto nl = what.find_last_of('\n', what.size() > 1 ? what.size() - 2 : 0);
    if (nl != std::string::npos && nl + 1 < what.size()) what = what.substr(nl + 1);
    throw InputError(name + ": malformed XML parameter list: " + trim(what), InputErrorKind::MalformedXml);
  }
  if (tree.getTag() != "ParameterList")
    throw InputError(name + ": malformed XML parameter list: the top element is <" + tree.getTag() +
                         ">, expected <ParameterList>",
                     InputErrorKind::MalformedXml);
  check_tree(tree, name, "the top-level list");
  try {
    return Teuchos::rcp(new Teuchos::ParameterList(Teuchos::XMLParameterListReader().toParameterList(tree)));
  } catch (const std::exception& e) {
    std::string what = e.what();
    auto nl = what.find_last_of('\n', what.size() > 1 ? what.size() - 2 : 0);
    if (nl != std::string::npos && nl + 1 < what.size()) what = what.substr(nl + 1);
    throw InputError(name + ": malformed XML parameter list: " + trim(what), InputErrorKind::MalformedXml);
  }
}

}  // namespace

bool strict_number(const std::string& text, bool integer) {
  const std::string t = trim(text);
  std::size_t i = 0;
  if (i < t.size() && (t[i] == '+' || t[i] == '-')) ++i;
  const std::size_t digits0 = i;
  while (i < t.size() && std::isdigit(static_cast<unsigned char>(t[i]))) ++i;
  std::size_t ndigits = i - digits0;
  if (!integer) {
    if (i < t.size() && t[i] == '.') {
      ++i;
      const std::size_t f0 = i;
      while (i < t.size() && std::isdigit(static_cast<unsigned char>(t[i]))) ++i;
      ndigits += i - f0;
    }
    if (ndigits == 0) return false;
    if (i < t.size() && (t[i] == 'e' || t[i] == 'E')) {
      ++i;
      if (i < t.size() && (t[i] == '+' || t[i] == '-')) ++i;
      const std::size_t e0 = i;
      while (i < t.size() && std::isdigit(static_cast<unsigned char>(t[i]))) ++i;
      if (i == e0) return false;
    }
  }
  if (ndigits == 0 || i != t.size()) return false;
  errno = 0;
  if (integer) {
    const long long v = std::strtoll(t.c_str(), nullptr, 10);
    return errno == 0 && v >= INT_MIN && v <= INT_MAX;
  }
  const double v = std::strtod(t.c_str(), nullptr);
  return std::isfinite(v);
}

Teuchos::RCP<Teuchos::ParameterList> read_parameter_file(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const auto status = fs::status(path, ec);
  if (ec || !fs::exists(status)) throw InputError(path + ": cannot open scene file (no such file)", InputErrorKind::File);
  if (fs::is_directory(status))
    throw InputError(path + ": is a directory, not a scene file", InputErrorKind::File);
  if (!fs::is_regular_file(status)) throw InputError(path + ": is not a regular file", InputErrorKind::File);
  const auto size = fs::file_size(path, ec);
  if (!ec && size > kMaxFileBytes)
    throw InputError(path + ": " + std::to_string(size) + " bytes is too large for a scene file (limit " +
                         std::to_string(kMaxFileBytes >> 20) + " MB)",
                     InputErrorKind::File);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open scene file", InputErrorKind::File);
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw InputError(path + ": cannot read scene file", InputErrorKind::File);
  return convert(text.str(), path);
}

Teuchos::RCP<Teuchos::ParameterList> read_parameter_text(const std::string& text, const std::string& name) {
  return convert(text, name);
}

std::vector<std::string> comma_list(const std::string& text) {
  std::vector<std::string> items;
  std::stringstream list(text);
  for (std::string item; std::getline(list, item, ',');) {
    item.erase(0, item.find_first_not_of(" \t\n"));
    item.erase(item.find_last_not_of(" \t\n") + 1);
    if (!item.empty()) items.push_back(std::move(item));
  }
  return items;
}

}  // namespace sinew
