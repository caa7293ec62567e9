#include "dynamics/engine_factory.hpp"

#include <stdexcept>

#include "dynamics/cvode_api.hpp"
#include "dynamics/exact_engine.hpp"

namespace vibro::detail {

std::unique_ptr<Propagator> MakeEngine(const System& system, const ModelT<double>& model,
                                       const RunSpec& run) {
  switch (run.engine) {
    case Engine::kExact:
      return std::make_unique<ExactEngine>(system, model);
    case Engine::kCvode:
      return MakeCvodeEngine(system, run);  // the plugin, loaded on first use
  }
  throw std::invalid_argument("unknown engine");
}

}  // namespace vibro::detail
