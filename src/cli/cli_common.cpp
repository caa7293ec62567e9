// What the command files of src/cli share (cli_common.hpp).
#include "cli/cli_common.hpp"

#include <algorithm>

#include <fmt/format.h>

#include "cli/text_format.hpp"
#include "vibro/scene_file.hpp"

void PrintLoads(const vibro::LoadsSummary& s) {
  if (s.contacts.empty()) {
    if (!s.note.empty()) fmt::print("loads        {}\n", s.note);
    return;
  }
  if (s.blocks == 0)
    fmt::print("loads        exact, per period of the orbit{}\n", s.note.empty() ? "" : "; " + s.note);
  else
    fmt::print("loads        periods {}..{}{}\n", s.first_period, s.first_period + s.periods,
               s.block_periods > 0 ? fmt::format(", 95 % intervals from {} blocks of {} periods", s.blocks, s.block_periods)
                                   : "; " + s.note);
  if (!s.whole_run) fmt::print("loads        not the whole run: {}\n", s.coverage);
  const auto pm = [](double v, const vibro::ContactLoads::Interval& ci) {
    return ci ? fmt::format("{:.6g} ± {:.2g}", v, 0.5 * (ci->second - ci->first)) : fmt::format("{:.6g}", v);
  };
  for (const auto& c : s.contacts) {
    if (!c.compliant) {
      fmt::print("  contact {}  impacts/T {}, impulse/T {}, ∫R dt/T {}, mean force {}, dissipated power {}, "
                 "work rate {}, contact fraction {}\n",
                 c.contact, pm(c.impacts_per_period, c.impacts_per_period_ci),
                 pm(c.impulse_per_period, c.impulse_per_period_ci),
                 pm(c.reaction_integral_per_period, c.reaction_integral_per_period_ci),
                 pm(c.mean_force, c.mean_force_ci), pm(c.dissipated_power, c.dissipated_power_ci),
                 pm(c.work_rate, c.work_rate_ci), pm(c.contact_fraction, c.contact_fraction_ci));
      continue;
    }
    // A compliant stop (docs/loads.md, "Peak force and contact duration over a run"): no impacts,
    // so no impact impulse and no rigid-limit work rate; its contact phases instead.
    fmt::print("  contact {}  compliant: contact phases/T {}, ∫λ dt/T {}, mean force {}, dissipated power {}, "
               "contact fraction {}\n",
               c.contact, pm(c.phases_per_period, c.phases_per_period_ci),
               pm(c.reaction_integral_per_period, c.reaction_integral_per_period_ci),
               pm(c.mean_force, c.mean_force_ci), pm(c.dissipated_power, c.dissipated_power_ci),
               pm(c.contact_fraction, c.contact_fraction_ci));
    fmt::print("             per contact phase: peak force {}, duration {}; largest peak force {:.6g} (certified)\n",
               pm(c.peak_force_mean, c.peak_force_mean_ci), pm(c.contact_duration_mean, c.contact_duration_mean_ci),
               c.peak_force_max);
  }
  if (std::any_of(s.contacts.begin(), s.contacts.end(), [](const auto& c) { return c.compliant; }))
    fmt::print("  (a compliant stop has no impacts: impacts/T, impact impulse/T and the rigid-limit work rate do not "
               "apply to it, docs/loads.md)\n");
}

void PrintRigidComparison(const vibro::RigidComparison& c) {
  fmt::print("rigid model  the same scene with rigid stops ({} / {}): distance between the trajectories {:.4g} "
             "(largest, at t = {:.10g}), {:.4g} at the end\n",
             vibro::ToString(c.compliant_result.status), vibro::ToString(c.rigid_result.status), c.distance,
             c.distance_time, c.end_distance);
  const auto find = [](const vibro::LoadsSummary& s, size_t j) -> const vibro::ContactLoads* {
    for (const auto& l : s.contacts)
      if (l.contact == static_cast<int>(j)) return &l;
    return nullptr;
  };
  for (size_t j = 0; j < c.rigid.zeta.size(); ++j) {
    const auto* a = find(c.compliant_loads, j);
    const auto* b = find(c.rigid_loads, j);
    if (std::isfinite(c.rigid.zeta[j]))
      fmt::print("  contact {}  ζ {:.6g} → r {:.6g}; {} contact phases: peak force {:.6g} (largest), {:.6g} (mean), "
                 "duration {:.6g} (mean)\n",
                 j, c.rigid.zeta[j], c.rigid.restitution[j], c.phases[j], c.peak_force_max[j], c.peak_force_mean[j],
                 c.duration_mean[j]);
    else
      fmt::print("  contact {}  rigid in both (r {:.6g})\n", j, c.rigid.restitution[j]);
    if (a && b)
      fmt::print("    compliant / rigid: impulse/T {:.6g} / {:.6g}, mean force {:.6g} / {:.6g}, dissipated power "
                 "{:.6g} / {:.6g}\n",
                 a->impulse_per_period + a->reaction_integral_per_period,
                 b->impulse_per_period + b->reaction_integral_per_period, a->mean_force, b->mean_force,
                 a->dissipated_power, b->dissipated_power);
  }
}

void PrintRigidOrbitComparison(const vibro::RigidOrbitComparison& c) {
  if (c.orbit.status != "converged") {
    fmt::print("rigid model  the same scene with rigid stops: no orbit ({}{})\n", c.orbit.status,
               c.orbit.message.empty() ? "" : ": " + c.orbit.message);
    return;
  }
  fmt::print("rigid model  the same scene with rigid stops: its orbit from the same section, distance between the "
             "orbits {:.4g} (largest, at t = {:.10g}), {:.4g} at the section\n",
             c.distance, c.distance_time, c.section_distance);
  fmt::print("  rigid orbit {}, multipliers {}, stable {}\n", c.orbit.summary.kind,
             c.orbit.no_jacobian.empty() ? vibro::cli::FormatMultipliers(c.orbit.multipliers) : "none: " + c.orbit.no_jacobian,
             c.orbit.no_jacobian.empty() ? (c.orbit.stable ? "yes" : "no") : "-");
  for (size_t k = 0; k < c.compliant_loads.contacts.size() && k < c.rigid_loads.contacts.size(); ++k) {
    const auto& a = c.compliant_loads.contacts[k];
    const auto& b = c.rigid_loads.contacts[k];
    const size_t j = static_cast<size_t>(a.contact);
    fmt::print("  contact {}  ζ {:.6g} → r {:.6g}; compliant / rigid: impulse/T {:.6g} / {:.6g}, mean force {:.6g} / "
               "{:.6g}, dissipated power {:.6g} / {:.6g}\n",
               a.contact, j < c.rigid.zeta.size() ? c.rigid.zeta[j] : std::nan(""),
               j < c.rigid.restitution.size() ? c.rigid.restitution[j] : std::nan(""),
               a.impulse_per_period + a.reaction_integral_per_period,
               b.impulse_per_period + b.reaction_integral_per_period, a.mean_force, b.mean_force,
               a.dissipated_power, b.dissipated_power);
  }
}

void PrintAttractor(const vibro::Attractor& a, double restitution, bool named) {
  fmt::print("{}", vibro::cli::AttractorText(a, restitution, "", named));
}

void PrintLyapunov(const vibro::LyapunovSpectrum& s) { fmt::print("{}", vibro::cli::LyapunovText(s)); }

int ExitCode(vibro::RunStatus s) {
  switch (s) {
    case vibro::RunStatus::kOk: return 0;
    case vibro::RunStatus::kNumericalFailure: return kExitNumerical;
    case vibro::RunStatus::kInterrupted: return kExitInterrupted;
    case vibro::RunStatus::kUndetermined: return kExitNumerical;
  }
  return kExitInternal;
}
