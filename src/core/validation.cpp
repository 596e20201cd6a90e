// Name matching for messages: edit distance with swaps, the closest valid name, the unknown-entry check
// for lists that are not declared as sections.
#include <sinew/core/errors.hpp>
#include <sinew/core/validation.hpp>

#include <Teuchos_ParameterList.hpp>

#include <algorithm>
#include <cctype>

namespace sinew {

std::size_t edit_distance(const std::string& a, const std::string& b) {
  // Optimal string alignment: insertions, deletions, substitutions and swaps of adjacent letters
  // (the commonest typo) each cost one.
  auto lower = [](char c) { return std::tolower(static_cast<unsigned char>(c)); };
  const std::size_t n = a.size(), m = b.size();
  std::vector<std::size_t> d((n + 1) * (m + 1));
  auto at = [&](std::size_t i, std::size_t j) -> std::size_t& { return d[i * (m + 1) + j]; };
  for (std::size_t i = 0; i <= n; ++i) at(i, 0) = i;
  for (std::size_t j = 0; j <= m; ++j) at(0, j) = j;
  for (std::size_t i = 1; i <= n; ++i) {
    for (std::size_t j = 1; j <= m; ++j) {
      const std::size_t cost = lower(a[i - 1]) == lower(b[j - 1]) ? 0 : 1;
      at(i, j) = std::min({at(i - 1, j) + 1, at(i, j - 1) + 1, at(i - 1, j - 1) + cost});
      if (i > 1 && j > 1 && lower(a[i - 1]) == lower(b[j - 2]) && lower(a[i - 2]) == lower(b[j - 1]))
        at(i, j) = std::min(at(i, j), at(i - 2, j - 2) + 1);
    }
  }
  return at(n, m);
}

std::string closest_name(const std::string& name, const std::vector<std::string>& candidates) {
  std::string best;
  std::size_t best_d = std::string::npos;
  for (const auto& c : candidates) {
    const std::size_t d = edit_distance(name, c);
    if (d < best_d) {
      best_d = d;
      best = c;
    }
  }
  // Accept up to a third of the longer name's length in edits: catches typos, not unrelated words.
  if (best.empty() || best_d * 3 > std::max(name.size(), best.size())) return "";
  return best;
}

void require_known_entries(const Teuchos::ParameterList& list, const Teuchos::ParameterList& valid,
                           const std::string& where) {
  std::vector<std::string> names;
  for (auto it = valid.begin(); it != valid.end(); ++it) names.push_back(valid.name(it));
  for (auto it = list.begin(); it != list.end(); ++it) {
    const std::string& key = list.name(it);
    if (!valid.isParameter(key)) {
      std::string msg = "unknown entry '" + key + "' in " + where;
      const std::string near = closest_name(key, names);
      if (!near.empty()) msg += " (did you mean '" + near + "'?)";
      throw InputError(msg, InputErrorKind::UnknownEntry);
    }
    const auto& have = list.entry(it);
    const auto& want = valid.getEntry(key);
    if (have.isList() != want.isList())
      throw InputError("entry '" + key + "' in " + where + " must be " + (want.isList() ? "a sublist" : "a parameter"),
                       InputErrorKind::WrongType);
    if (!have.isList() && have.getAny(false).type() != want.getAny(false).type())
      throw InputError("entry '" + key + "' in " + where + " has type " + have.getAny(false).typeName() +
                       ", expected " + want.getAny(false).typeName(),
                       InputErrorKind::WrongType);
  }
}

}  // namespace sinew
