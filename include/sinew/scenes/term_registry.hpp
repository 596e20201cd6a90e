// The energy terms a scene file adds through their own sections, in the order the System sums them
// after its own two (the elastic energy and the external forces; a dynamic run's integrator adds
// inertia last). A new term: its header (see term_kind.hpp and terms/pressure.hpp) and its name in
// the list.
#pragma once

#include <sinew/scenes/contact.hpp>
#include <sinew/scenes/term_kind.hpp>
#include <sinew/scenes/terms/attachment.hpp>
#include <sinew/scenes/terms/muscle.hpp>
#include <sinew/scenes/terms/pressure.hpp>

namespace sinew {

using SceneTerms = TermKinds<Contact, PressureLoads, Muscles, Attachments>;

}  // namespace sinew
