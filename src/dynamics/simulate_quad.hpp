// The hybrid automaton with the exact engine in 113-bit quad precision (run.precision = "quad"):
// the reference against which the double engines are checked. The only entry point into the
// quad instantiation, so that Boost.Multiprecision stays inside simulate_quad.cpp.
#pragma once

#include "vibro/simulator.hpp"

namespace vibro::detail {

RunResult SimulateQuad(const System& system, const Scene& scene, const SimulationOptions& options);

}  // namespace vibro::detail
