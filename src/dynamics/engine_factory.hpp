// Chooses the propagator behind the automaton from the scene's run.engine.
#pragma once

#include <memory>

#include "dynamics/propagator.hpp"
#include "vibro/scene.hpp"
#include "vibro/system.hpp"

namespace vibro::detail {

std::unique_ptr<Propagator> MakeEngine(const System& system, const RunSpec& run);

}  // namespace vibro::detail
