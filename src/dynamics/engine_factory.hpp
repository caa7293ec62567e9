// Chooses the propagator behind the automaton from the scene's run.engine.
#pragma once

#include <memory>

#include "dynamics/propagator.hpp"
#include "vibro/scene.hpp"
#include "vibro/system.hpp"

namespace vibro::detail {

// `stop`: a stop request polled inside the engine's stepping loops (may be null).
std::unique_ptr<Propagator> MakeEngine(const System& system, const RunSpec& run,
                                       const std::atomic<bool>* stop = nullptr);

}  // namespace vibro::detail
