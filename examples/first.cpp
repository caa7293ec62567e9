// Simulate a scene, count its releases, then solve its periodic orbit.
#include <cstdio>

#include "vibro/attractor.hpp"
#include "vibro/poincare.hpp"
#include "vibro/scene_file.hpp"
#include "vibro/simulator.hpp"
#include "vibro/system.hpp"

// An observer sees every event, sample and section point of a run, in time order.
class ReleaseCounter final : public vibro::Observer {
 public:
  void OnEvent(const vibro::Event& e) override {
    if (e.kind == vibro::EventKind::kRelease) ++releases;
  }
  long long releases = 0;
};

int main(int argc, char** argv) {
  try {
    const auto loaded = vibro::LoadScene(argc > 1 ? argv[1] : "data/scenes/default.toml",
                                         {"excitation.amplitude=1.25"});
    const vibro::System system(loaded.scene);  // immutable; share it by const& across threads

    vibro::AttractorRecorder recorder(system, loaded.scene);
    ReleaseCounter counter;
    vibro::SimulationOptions options;
    options.observers = {&recorder, &counter};
    const vibro::RunResult run = vibro::Simulate(system, loaded.scene, options);
    if (run.status != vibro::RunStatus::kOk) {
      std::fprintf(stderr, "%s\n", run.message.c_str());
      return 3;
    }
    const vibro::Attractor a = recorder.Classify();
    std::printf("t_end %.10g, %lld releases, %s, sticking fraction %.6f\n", run.t_end,
                counter.releases, a.kind.c_str(), a.sticking_fraction.value_or(0.0));

    const vibro::OrbitResult orbit = vibro::FindOrbit(system, loaded.scene, vibro::OrbitRequest{});
    std::printf("orbit %s, period %d, %zu multipliers, %s\n", orbit.status.c_str(), orbit.period,
                orbit.multipliers.size(), orbit.stable ? "stable" : "unstable");
  } catch (const vibro::InputError& e) {  // bad input: every problem, located
    for (const auto& m : e.messages()) std::fprintf(stderr, "%s\n", m.c_str());
    return 2;
  }
}
