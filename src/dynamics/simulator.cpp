// Simulate(): the hybrid automaton (dynamics/automaton.hpp) in double precision with the scene's
// engine, or in quad precision with the exact engine (dynamics/simulate_quad.cpp).
#include "vibro/simulator.hpp"

#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "dynamics/automaton.hpp"
#include "dynamics/engine_factory.hpp"
#include "dynamics/simulate_quad.hpp"
#include "vibro/stop_request.hpp"

namespace vibro {
namespace {
std::atomic<const std::atomic<bool>*> g_process_stop{nullptr};
thread_local const std::atomic<bool>* t_thread_stop = nullptr;
}  // namespace

void SetProcessStopFlag(const std::atomic<bool>* flag) { g_process_stop.store(flag); }
const std::atomic<bool>* ProcessStopFlag() { return t_thread_stop ? t_thread_stop : g_process_stop.load(); }

ThreadStopFlag::ThreadStopFlag(const std::atomic<bool>* flag) : previous_(t_thread_stop) { t_thread_stop = flag; }
ThreadStopFlag::~ThreadStopFlag() { t_thread_stop = previous_; }

const char* ToString(RunStatus s) {
  switch (s) {
    case RunStatus::kOk: return "ok";
    case RunStatus::kNumericalFailure: return "numerical-failure";
    case RunStatus::kInterrupted: return "interrupted";
    case RunStatus::kUndetermined: return "undetermined";
  }
  return "?";
}

const char* ToString(EventKind k) {
  switch (k) {
    case EventKind::kImpact: return "impact";
    case EventKind::kAccumulation: return "accumulation";
    case EventKind::kStick: return "stick";
    case EventKind::kRelease: return "release";
    case EventKind::kGrazing: return "grazing";
  }
  return "?";
}

RunResult Simulate(const System& system, const Scene& scene, const SimulationOptions& options) {
  // The clock counts periods of 2π/ω: with ω ≤ 0 (or NaN) a period boundary is never reached,
  // and the run would not end.
  if (!(std::isfinite(system.frequency()) && system.frequency() > 0)) {
    RunResult r;
    r.status = RunStatus::kNumericalFailure;
    r.message = fmt::format("excitation.frequency = {:.17g}: the forcing frequency must be finite and > 0",
                            system.frequency());
    r.X = Eigen::VectorXd::Constant(system.dof(), std::numeric_limits<double>::quiet_NaN());
    r.V = r.X;
    return r;
  }
  if (scene.run.precision == Precision::kQuad) return detail::SimulateQuad(system, scene, options);
  const detail::ModelT<double> model(system);
  detail::Automaton<double> a(system, model, scene, options,
                              detail::MakeEngine(system, model, scene.run));
  return a.Run();
}

}  // namespace vibro
