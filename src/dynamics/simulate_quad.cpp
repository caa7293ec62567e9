#include "dynamics/simulate_quad.hpp"

#include "dynamics/automaton.hpp"
#include "dynamics/exact_engine_quad.hpp"

namespace vibro::detail {

template class ExactEngineT<Quad>;

RunResult SimulateQuad(const System& system, const Scene& scene, const SimulationOptions& options) {
  const ModelT<Quad> model(system);
  Automaton<Quad> a(system, model, scene, options,
                    std::make_unique<ExactEngineT<Quad>>(system, model));
  return a.Run();
}

}  // namespace vibro::detail
