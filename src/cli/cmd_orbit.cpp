// `vibro orbit SCENE`: a periodic orbit and its Floquet multipliers (docs/orbits.md).
#include <cmath>
#include <optional>

#include <fmt/format.h>

#include "cli/cli_common.hpp"
#include "cli/stop_signals.hpp"
#include "cli/text_format.hpp"
#include "vibro/hdf5_store.hpp"
#include "vibro/loads.hpp"
#include "vibro/poincare.hpp"
#include "vibro/rigid_model.hpp"
#include "vibro/scene_file.hpp"
#include "vibro/summary_json.hpp"
#include "vibro/system.hpp"

int RunOrbit(const std::string& path, const std::vector<std::string>& sets, bool json,
             const vibro::OrbitRequest& req, const std::string& out) {
  vibro::frontend::CheckOrbitOptions(vibro::frontend::Naming::kCli, req.period, req.impacts, req.transient_periods,
                                     req.guess_phase, req.guess_velocity);
  const auto loaded = vibro::LoadScene(path, sets);
  const vibro::System sys(loaded.scene);
  if (!out.empty()) vibro::Hdf5Store::Create(out, vibro::frontend::HeaderOf(loaded, sys)).reset();  // fail early
  // An orbit is found whole or not at all: a stop request removes the unfilled file and leaves.
  vibro::cli::DiscardOnStop(out);
  auto orbit = vibro::SolveOrbit(sys, loaded.scene, req);
  // Reported from the start of its contact sequence's canonical rotation (docs/orbits.md).
  vibro::StartAtCanonicalRotation(sys, loaded.scene, req, orbit);
  vibro::cli::KeepOnStop();
  const bool converged = orbit.status == "converged";
  // The orbit's exact per-period contact loads (docs/loads.md): one period simulated from it.
  const vibro::LoadsSummary loads = converged ? vibro::OrbitLoads(sys, loaded.scene, orbit) : vibro::LoadsSummary{};
  // A compliant stop (docs/compliant.md, "Periodic orbits"): the rigid model's orbit beside it.
  std::optional<vibro::RigidOrbitComparison> rigid;
  if (converged && vibro::HasCompliantContact(loaded.scene)) rigid = vibro::CompareOrbitWithRigid(loaded.scene, sys, orbit, req);
  if (!out.empty() && converged) {
    const vibro::cli::FinalWrite writing;
    vibro::frontend::WriteOrbit(out, loaded, sys, orbit);
  } else if (!out.empty()) {
    const vibro::cli::FinalWrite writing;
    vibro::frontend::WriteOrbitFailure(out, loaded, sys, orbit);
  }
  if (json) {
    std::string text = vibro::OrbitJson(orbit, req.kind, converged ? &loads : nullptr);
    if (rigid) text = text.substr(0, text.rfind('}')) + ",\"rigid_model\":" + vibro::RigidOrbitJson(*rigid) + "}";
    fmt::print("{}\n", text);
  } else {
    fmt::print("status       {}{}\n", orbit.status, orbit.message.empty() ? "" : ": " + orbit.message);
    fmt::print("period       {} (Newton: {} iterations, residual {:.2e})\n", orbit.period,
               orbit.newton_iterations, orbit.residual);
    // --period Q of an orbit whose least period p divides Q: it is the period-p orbit.
    if (converged && orbit.summary.period && *orbit.summary.period < orbit.period)
      fmt::print("least period {}: the orbit repeats every {} period(s); found as a period-{} orbit (multipliers over "
                 "{} periods)\n", *orbit.summary.period, *orbit.summary.period, orbit.period, orbit.period);
    if (orbit.distance_from_start)
      fmt::print("from start   distance {:.3g} ({})\n", *orbit.distance_from_start,
                 req.transient_periods > 0 ? fmt::format("after a transient of {} periods", req.transient_periods)
                 : req.guess_phase         ? "Newton started at the guess"
                                           : "Newton started at the start state");
    // Several contacts: each impact has its contact's restitution (the sequence names the contacts).
    PrintAttractor(orbit.summary, loaded.scene.contacts.size() > 1 ? std::nan("") : loaded.scene.restitution,
                   !loaded.scene.contacts.empty());
    if (!orbit.sequence.empty()) fmt::print("sequence     {}\n", orbit.sequence);
    const std::string mu = vibro::cli::FormatMultipliers(orbit.multipliers);
    fmt::print("multipliers  {}\n", !orbit.no_jacobian.empty() ? "none: " + orbit.no_jacobian
                                     : !mu.empty()                ? mu
                                     : converged && loaded.scene.contacts.size() > 1
                                         ? "none (superstable: its sticking phases hold every direction)"
                                     : converged ? "none (superstable: one-DOF sticking)"
                                                                  : "-");
    fmt::print("stable       {}\n", !converged || !orbit.no_jacobian.empty() ? "-" : orbit.stable ? "yes" : "no");
    // A compliant stop (docs/compliant.md, "Periodic orbits"): each contact phase's exact loads.
    if (converged && !orbit.contact_phases.empty()) {
      fmt::print("contact phases over the orbit's {} period(s) (times from the section, t0 = {:.10g}):\n", orbit.period,
                 orbit.section_time);
      fmt::print("  {:>7} {:>14} {:>14} {:>14} {:>14} {:>14} {:>14} {:>14}\n", "contact", "entry", "duration",
                 "peak force", "peak at", "penetration", "impulse", "dissipated");
      for (const auto& p : orbit.contact_phases)
        fmt::print("  {:>7} {:>14.9g} {:>14.9g} {:>14.9g} {:>14.9g} {:>14.9g} {:>14.9g} {:>14.9g}\n", p.contact,
                   p.entry - orbit.section_time, p.duration, p.peak_force, p.peak_time - orbit.section_time,
                   p.penetration, p.impulse, p.dissipated);
    }
    if (converged) PrintLoads(loads);
    if (rigid) PrintRigidOrbitComparison(*rigid);
    if (orbit.quad_evaluations > 0)
      fmt::print("quad         {} map evaluations in quad precision (chattering sequences that double "
                 "leaves undetermined)\n", orbit.quad_evaluations);
  }
  if (!converged) {
    const bool sticking = req.kind == vibro::OrbitKind::kSticking, impact = req.kind == vibro::OrbitKind::kImpact;
    std::string hint = "vibro: try ";
    if (sticking && orbit.reached == "impact-periodic") hint += "--kind impact (the attractor has impacts and no sticking), ";
    if (impact && vibro::HoldsContact(orbit.reached)) hint += "--kind sticking (the attractor sticks), ";
    // What applies to this attempt, the cheapest first: from a transient, Newton from a state on
    // the orbit (--transient 0) or from a guess; from a guess or a start state, another one or a
    // transient after it.
    if (req.transient_periods > 0)
      hint += "--transient 0 from a state on the orbit ([initial], or --set initial.time=T --set "
              "initial.displacement=[...] --set initial.velocity=[...]), --guess PHASE[,VELOCITY] "
              "(Newton starts there), or --period Q";
    else if (req.guess_phase)
      hint += "--period Q, another --guess PHASE,VELOCITY, or --transient N to start Newton after N "
              "periods from the guess";
    else
      hint += "--period Q, another start state, --guess PHASE[,VELOCITY], or --transient N to start "
              "Newton after N periods";
    fmt::print(stderr, "{}\n", hint);
  }
  return converged ? 0 : kExitNumerical;
}
