// What the command files of src/cli share (cli_common.hpp).
#include "cli/cli_common.hpp"

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
  for (const auto& c : s.contacts)
    fmt::print("  contact {}  impacts/T {}, impulse/T {}, ∫R dt/T {}, mean force {}, dissipated power {}, "
               "work rate {}, contact fraction {}\n",
               c.contact, pm(c.impacts_per_period, c.impacts_per_period_ci),
               pm(c.impulse_per_period, c.impulse_per_period_ci),
               pm(c.reaction_integral_per_period, c.reaction_integral_per_period_ci),
               pm(c.mean_force, c.mean_force_ci), pm(c.dissipated_power, c.dissipated_power_ci),
               pm(c.work_rate, c.work_rate_ci), pm(c.contact_fraction, c.contact_fraction_ci));
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
