// The quad instantiation of the exact engine (run.precision = "quad"): ExactEngineT<Quad> with its
// damped sticking closed form, instantiated once in simulate_quad.cpp. Include this header, not
// exact_engine.hpp alone, wherever ExactEngineT<Quad> is used.
#pragma once

#include "dynamics/damped_sticking_quad.hpp"
#include "dynamics/exact_engine.hpp"
#include "dynamics/quad.hpp"

namespace vibro::detail {

extern template class ExactEngineT<Quad>;

}  // namespace vibro::detail
