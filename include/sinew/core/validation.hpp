// Name matching for messages that name the culprit: "unknown entry 'Poison ratio' in Material (did you
// mean 'Poisson ratio'?)".
#pragma once

#include <string>
#include <vector>

namespace Teuchos {
class ParameterList;
}

namespace sinew {

// Levenshtein distance with adjacent swaps, case-insensitive.
std::size_t edit_distance(const std::string& a, const std::string& b);

// The candidate closest to `name`, or "" when none is reasonably close.
std::string closest_name(const std::string& name, const std::vector<std::string>& candidates);

// Throws InputError for the first entry of `list` that `valid` does not have (suggesting the closest
// valid name), and for an entry whose type differs from the valid one. `where` names the sublist
// in messages, e.g. "Material". Sublists are not descended into.
void require_known_entries(const Teuchos::ParameterList& list, const Teuchos::ParameterList& valid,
                           const std::string& where);

}  // namespace sinew
