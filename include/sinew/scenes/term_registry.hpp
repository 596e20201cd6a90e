// The energy terms a scene file may add through their own section, in the order the System sums them
// after the elastic, external-force and contact terms. A new term: its header (see term_kind.hpp and
// terms/pressure.hpp) and one line here.
#pragma once

#include <sinew/scenes/term_kind.hpp>
#include <sinew/scenes/terms/pressure.hpp>

namespace sinew {

using SceneTerms = TermKinds<PressureLoads>;

}  // namespace sinew
