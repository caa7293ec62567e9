// The engine a scene asks for (run.engine), in double precision.
#pragma once

#include <memory>

#include "dynamics/model_t.hpp"
#include "dynamics/propagator.hpp"
#include "vibro/scene.hpp"
#include "vibro/system.hpp"

namespace vibro::detail {

std::unique_ptr<Propagator> MakeEngine(const System& system, const ModelT<double>& model,
                                       const RunSpec& run);

}  // namespace vibro::detail
