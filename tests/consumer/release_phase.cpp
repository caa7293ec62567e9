// A user's program against the installed library: simulates the shipped Fig. 8 scene with a
// plastic stop (r = 0) and checks every release against the closed form of MODEL §6.1 (the
// paper's eq. (32)): the body leaves the preloaded stop when f sin ωt = 1, i.e. at the phase
// φ1 = arcsin(1/f) with cos φ1 > 0. Usage: release_phase SCENE (fig08_preload.toml).
#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include <vibro/observer.hpp>
#include <vibro/scene_file.hpp>
#include <vibro/simulator.hpp>
#include <vibro/system.hpp>

namespace {
struct Releases : vibro::Observer {
  std::vector<double> times;
  void OnEvent(const vibro::Event& e) override {
    if (e.kind == vibro::EventKind::kRelease) times.push_back(e.t);
  }
};
}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: release_phase SCENE.toml\n");
    return 2;
  }
  const auto loaded = vibro::LoadScene(argv[1], {"stop.restitution=0", "run.periods=20"});
  const vibro::System system(loaded.scene);
  Releases releases;
  vibro::SimulationOptions options;
  options.observers.push_back(&releases);
  const auto result = vibro::Simulate(system, loaded.scene, options);
  if (result.status != vibro::RunStatus::kOk || releases.times.size() < 10) {
    std::fprintf(stderr, "run failed or too few releases (%zu): %s\n", releases.times.size(),
                 result.message.c_str());
    return 1;
  }
  const double f = loaded.scene.amplitude, omega = loaded.scene.frequency;
  const double phi1 = std::asin(1.0 / f);  // eq. (32), the branch with cos φ1 > 0
  double worst = 0;
  for (double t : releases.times) {
    const double phase = std::remainder(omega * t - phi1, 2 * std::numbers::pi);
    worst = std::max(worst, std::abs(phase));
  }
  std::printf("%zu releases, largest |ωt − arcsin(1/f)| mod 2π = %.3e (f = %g)\n", releases.times.size(),
              worst, f);
  return worst < 1e-9 ? 0 : 1;
}
