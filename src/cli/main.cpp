// The `vibro` command (CONTRACT §2, §4). The only file that includes CLI11.
//
// Exit codes: 0 success · 1 internal error · 2 bad input · 3 numerical failure · 130 interrupted.
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "vibro/attractor.hpp"
#include "vibro/scene_file.hpp"
#include "vibro/simulator.hpp"
#include "vibro/summary_json.hpp"
#include "vibro/system.hpp"

namespace {

constexpr int kExitInternal = 1;
constexpr int kExitBadInput = 2;
constexpr int kExitNumerical = 3;
constexpr int kExitInterrupted = 130;

std::string Vec(const Eigen::VectorXd& v) {
  std::string s = "[";
  for (Eigen::Index i = 0; i < v.size(); ++i) s += fmt::format("{}{:.10g}", i ? ", " : "", v[i]);
  return s + "]";
}

int RunModel(const std::string& path, const std::vector<std::string>& sets, bool json) {
  const auto loaded = vibro::LoadScene(path, sets);
  const vibro::System sys(loaded.scene);
  if (json) {
    fmt::print("{}\n", vibro::ModelJson(sys));
    return 0;
  }
  fmt::print("scene               {}{}\n", path,
             loaded.scene.title.empty() ? "" : "  (" + loaded.scene.title + ")");
  fmt::print("form                {}, {} mode(s) kept\n", sys.physical() ? "physical" : "modal",
             sys.dof());
  fmt::print("frequencies ω_i     {}\n", Vec(sys.omega()));
  fmt::print("forcing T_A         {}\n", Vec(sys.forcing()));
  fmt::print("contact T_B         {}\n", Vec(sys.contact()));
  if (sys.damped()) fmt::print("damping ratios ζ_i  {}\n", Vec(sys.damping()));
  fmt::print("s_A, s_B            {:.10g}, {:.10g}\n", sys.s_A(), sys.s_B());
  fmt::print("constrained ω'_k    {}\n", Vec(sys.constrained().frequencies));
  fmt::print("static flexibility  {:.10g}\n", sys.flexibility());
  if (auto r = sys.static_reaction())
    fmt::print("static reaction     {:.10g}\n", *r);
  else
    fmt::print("static reaction     none (clearance)\n");
  fmt::print("stop x0, r          {:.10g}, {:.10g}\n", sys.stop(), sys.restitution());
  fmt::print("excitation f, ω, T  {:.10g}, {:.10g}, {:.10g}\n", sys.amplitude(), sys.frequency(),
             sys.period());
  if (sys.physical()) {
    for (int i = 0; i < sys.dof(); ++i)
      fmt::print("mode shape ψ_{}{}     {}\n", i + 1,
                 sys.contact_shape()[i] > 0 ? "" : " (node at B)",
                 Vec(sys.mode_shapes().col(i)));
  }
  return 0;
}

std::string Phases(const std::vector<std::pair<double, double>>& phases) {
  std::string s;
  for (const auto& [a, b] : phases) s += fmt::format("{}[{:.6f}, {:.6f}]", s.empty() ? "" : " ", a, b);
  return s.empty() ? "none" : s;
}

int RunSimulate(const std::string& path, const std::vector<std::string>& sets, bool json) {
  const auto loaded = vibro::LoadScene(path, sets);
  const vibro::System sys(loaded.scene);
  vibro::AttractorRecorder recorder(sys, loaded.scene);
  vibro::SimulationOptions options;
  options.observers.push_back(&recorder);
  const auto result = vibro::Simulate(sys, loaded.scene, options);
  const auto attractor = recorder.Classify();
  if (json) {
    fmt::print("{}\n", vibro::SimulationJson(loaded.scene, result, attractor));
  } else {
    fmt::print("scene        {}{}\n", path,
               loaded.scene.title.empty() ? "" : "  (" + loaded.scene.title + ")");
    fmt::print("engine       {}, chatter {}\n", vibro::ToString(loaded.scene.run.engine),
               vibro::ToString(loaded.scene.run.chatter));
    fmt::print("status       {}{}\n", vibro::ToString(result.status),
               result.message.empty() ? "" : ": " + result.message);
    fmt::print("t_end        {:.10g} ({} periods)\n", result.t_end, result.end.period);
    fmt::print("events       {} impacts, {} accumulations, {} sticks, {} releases, {} grazings\n",
               result.counts.impacts, result.counts.accumulations, result.counts.sticks,
               result.counts.releases, result.counts.grazings);
    fmt::print("attractor    {}", attractor.kind);
    if (attractor.period) fmt::print(", period {}", *attractor.period);
    if (attractor.impacts_per_period) fmt::print(", {} impacts/period", *attractor.impacts_per_period);
    if (attractor.sticking_fraction) fmt::print(", sticking fraction {:.6f}", *attractor.sticking_fraction);
    fmt::print("\nstick phases {}\n", Phases(attractor.stick_phases));
  }
  switch (result.status) {
    case vibro::RunStatus::kOk: return 0;
    case vibro::RunStatus::kNumericalFailure: return kExitNumerical;
    case vibro::RunStatus::kInterrupted: return kExitInterrupted;
  }
  return kExitInternal;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"vibro: harmonically forced impact oscillators with sticking and chattering"};
  app.require_subcommand(1);
  app.set_version_flag("--version", VIBRO_VERSION);

  std::string scene_path;
  std::vector<std::string> sets;
  bool json = false;
  const auto add_scene_options = [&](CLI::App* cmd) {
    cmd->add_option("SCENE", scene_path, "scene file (TOML)")->required();
    cmd->add_option("--set", sets, "override a scene key, KEY=VALUE in TOML syntax (repeatable)")
        ->take_all()
        ->allow_extra_args(false);
    cmd->add_flag("--json", json, "print one JSON object on stdout");
  };

  CLI::App* model = app.add_subcommand("model", "print the structural model derived from a scene");
  add_scene_options(model);
  CLI::App* simulate = app.add_subcommand("simulate", "simulate a scene and summarise its attractor");
  add_scene_options(simulate);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : kExitBadInput;
  }

  try {
    if (*model) return RunModel(scene_path, sets, json);
    if (*simulate) return RunSimulate(scene_path, sets, json);
  } catch (const vibro::InputError& e) {
    for (const auto& m : e.messages()) fmt::print(stderr, "{}\n", m);
    fmt::print(stderr, "vibro: {} problem(s) in the input; nothing was computed or written\n",
               e.messages().size());
    return kExitBadInput;
  } catch (const std::exception& e) {
    fmt::print(stderr, "vibro: internal error: {}\n", e.what());
    return kExitInternal;
  }
  return kExitInternal;
}
