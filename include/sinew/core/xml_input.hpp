// Reading Teuchos XML parameter lists strictly. Teuchos alone reads "1.0e5x" as 1e5, an array entry
// "nan" as 0, and keeps the last of two entries with the same name; a scene must mean exactly what its
// file says, so every number (array entries included) must be a plain finite decimal, and no list may
// name an entry twice.
#pragma once

#include <Teuchos_RCP.hpp>

#include <string>
#include <vector>

namespace Teuchos {
class ParameterList;
}

namespace sinew {

// Throws InputError (kind File or MalformedXml) naming the file, the list and the entry at fault.
Teuchos::RCP<Teuchos::ParameterList> read_parameter_file(const std::string& path);

// The same checks on XML text already in memory (`name` stands for the file in messages).
Teuchos::RCP<Teuchos::ParameterList> read_parameter_text(const std::string& text, const std::string& name);

// A plain decimal number as a person writes it: optional sign, digits, optional fraction and exponent;
// no "nan", "inf", hexadecimal or trailing characters. For doubles the value must also be finite.
bool strict_number(const std::string& text, bool integer);

// The items of a comma-separated string entry ('Joint map', 'Skip joints'), each trimmed of blanks
// and newlines; empty items are dropped.
std::vector<std::string> comma_list(const std::string& text);

}  // namespace sinew
