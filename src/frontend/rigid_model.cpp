// The entry check of the analyses built on the rigid model (frontend/rigid_model.hpp).
#include "frontend/rigid_model.hpp"

#include <algorithm>
#include <array>

#include <fmt/format.h>

#include "vibro/scene.hpp"

namespace vibro::frontend {

bool TakesCompliantStops(const std::string& command) {
  // check: the exact engine against CVODE (the quad engine, `check --precision quad`, does not
  // take a contact phase yet); orbit: the Poincaré solver with the compliant saltations
  // (docs/compliant.md, "Periodic orbits"); continue: the same map along a branch ("Along a continued branch").
  static constexpr std::array<const char*, 5> kTakes = {"model", "simulate", "check", "orbit", "continue"};
  return std::any_of(kTakes.begin(), kTakes.end(), [&](const char* c) { return command == c; });
}

void CheckSceneModel(const std::string& command, const LoadedScene& loaded, const std::string& scene, Naming naming) {
  if (TakesCompliantStops(command) || !HasCompliantContact(loaded.scene)) return;
  const bool cli = naming == Naming::kCli;
  throw InputError({fmt::format("{}: a compliant stop (a stiffness on [stop] or a [[contact]]) runs in {}; {} does "
                                "not handle it yet (docs/compliant.md)",
                                scene,
                                cli ? "`vibro simulate` (with --rigid-beside), `vibro model`, `vibro check`, `vibro orbit` and `vibro continue`"
                                    : "vibro.simulate (rigid_beside), vibro.model, vibro.check, vibro.orbit and vibro.continue_",
                                command.find(' ') != std::string::npos ? fmt::format("`vibro {}`", command)
                                : cli                                  ? "this command"
                                                                       : "this function")});
}

}  // namespace vibro::frontend
