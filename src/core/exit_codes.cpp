// The mapping from exceptions to messages and exit codes.
#include <sinew/core/errors.hpp>
#include <sinew/core/exit_codes.hpp>

#include <cstdio>
#include <exception>

namespace sinew {

int run_guarded(const char* program, bool report, const std::function<int()>& fn) {
  try {
    return fn();
  } catch (const UsageError& e) {
    if (report) std::fprintf(stderr, "%s: %s (see --help)\n", program, e.what());
    return code(ExitCode::Usage);
  } catch (const InputError& e) {
    if (report) std::fprintf(stderr, "%s: input error [%s]: %s\n", program, to_string(e.kind), e.what());
    return code(ExitCode::InputError);
  } catch (const std::exception& e) {
    if (report) std::fprintf(stderr, "%s: error: %s\n", program, e.what());
    return code(ExitCode::Failure);
  }
}

}  // namespace sinew
