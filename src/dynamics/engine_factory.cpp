#include "dynamics/engine_factory.hpp"

#include <stdexcept>

#include "dynamics/exact_engine.hpp"

namespace vibro::detail {

std::unique_ptr<Propagator> MakeEngine(const System& system, const RunSpec& run) {
  switch (run.engine) {
    case Engine::kExact:
      return std::make_unique<ExactEngine>(system);
    case Engine::kCvode:
      break;
  }
  throw std::invalid_argument("run.engine = \"cvode\": the CVODE engine is not part of this build yet");
}

}  // namespace vibro::detail
