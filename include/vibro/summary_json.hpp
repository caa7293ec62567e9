// JSON summaries printed by `--json` (CONTRACT §2). nlohmann/json stays inside src/io.
#pragma once

#include <string>

#include "vibro/system.hpp"

namespace vibro {

// `vibro model --json`: frequencies, forcing, contact, constrained_frequencies, static_reaction,
// modes_kept (+ mode_shapes, modal_masses and contact_modes for the physical form).
std::string ModelJson(const System& system);

}  // namespace vibro
