// The mapping from exceptions to messages and exit codes.
#include <sinew/core/errors.hpp>
#include <sinew/driver/exit_codes.hpp>

#include <cstdio>
#include <exception>

namespace sinew {

int run_guarded(bool report, const std::function<int()>& fn) {
  try {
    return fn();
  } catch (const InputError& e) {
    if (report) std::fprintf(stderr, "sinew: input error [%s]: %s\n", to_string(e.kind), e.what());
    return code(ExitCode::InputError);
  } catch (const std::exception& e) {
    if (report) std::fprintf(stderr, "sinew: error: %s\n", e.what());
    return code(ExitCode::Failure);
  }
}

}  // namespace sinew
