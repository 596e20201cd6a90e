// Error classes that reach the user. Each names its culprit; the driver turns them into one message
// "input error [kind]: ..." and a non-zero exit code.
#pragma once

#include <stdexcept>
#include <string>

namespace sinew {

enum class InputErrorKind {
  InvalidValue,          // out of range, impossible or inconsistent values
  MalformedXml,          // the file is not a Teuchos XML parameter list
  UnknownEntry,          // a key the list does not accept (typo)
  WrongType,             // an entry of the wrong type (int for double, parameter for sublist, ...)
  MissingEntry,          // a required entry is absent
  EmptyRegion,           // a boundary region selects no node
  ConflictingConditions, // a node under two boundary conditions
  BadMesh,               // degenerate or inverted rest elements, impossible partition
  File                   // a file that cannot be read or written
};

inline const char* to_string(InputErrorKind k) {
  switch (k) {
    case InputErrorKind::InvalidValue: return "invalid-value";
    case InputErrorKind::MalformedXml: return "malformed-xml";
    case InputErrorKind::UnknownEntry: return "unknown-entry";
    case InputErrorKind::WrongType: return "wrong-type";
    case InputErrorKind::MissingEntry: return "missing-entry";
    case InputErrorKind::EmptyRegion: return "empty-region";
    case InputErrorKind::ConflictingConditions: return "conflicting-conditions";
    case InputErrorKind::BadMesh: return "bad-mesh";
    case InputErrorKind::File: return "file";
  }
  return "input";
}

// Bad input: XML syntax, unknown key, wrong type, value out of range, inconsistent settings.
struct InputError : std::runtime_error {
  InputErrorKind kind;
  explicit InputError(const std::string& what, InputErrorKind k = InputErrorKind::InvalidValue)
      : std::runtime_error(what), kind(k) {}
  // The same error with more context (e.g. the file name) in front.
  InputError prefixed(const std::string& prefix) const { return InputError(prefix + what(), kind); }
};

// A bad command line (exit code 2).
struct UsageError : std::runtime_error {
  explicit UsageError(const std::string& what) : std::runtime_error(what) {}
};

}  // namespace sinew
