#include "dynamics/engine_factory.hpp"

#include <stdexcept>

#include "dynamics/cvode_engine.hpp"
#include "dynamics/exact_engine.hpp"

namespace vibro::detail {

std::unique_ptr<Propagator> MakeEngine(const System& system, const RunSpec& run,
                                       const std::atomic<bool>* stop) {
  std::unique_ptr<Propagator> engine;
  switch (run.engine) {
    case Engine::kExact:
      engine = std::make_unique<ExactEngine>(system);
      break;
    case Engine::kCvode:
      engine = std::make_unique<CvodeEngine>(system, run);
      break;
  }
  if (!engine) throw std::invalid_argument("unknown engine");
  engine->set_stop_flag(stop);
  return engine;
}

}  // namespace vibro::detail
