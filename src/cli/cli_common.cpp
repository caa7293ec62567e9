// What the command files of src/cli share (cli_common.hpp).
#include "cli/cli_common.hpp"

#include <fmt/format.h>

#include "cli/text_format.hpp"
#include "vibro/scene_file.hpp"

void PrintAttractor(const vibro::Attractor& a, double restitution) {
  fmt::print("{}", vibro::cli::AttractorText(a, restitution));
}

void PrintLyapunov(const vibro::LyapunovSpectrum& s) {
  if (!s.undefined.empty()) {
    fmt::print("lyapunov     none: {}\n", s.undefined);
    return;
  }
  std::string list;
  for (size_t i = 0; i < s.exponents.size(); ++i) {
    const double e = s.exponents[i];
    list += list.empty() ? "" : ", ";
    if (!std::isfinite(e))
      list += "-inf";
    else if (i < s.ci.size())
      list += fmt::format("{:.4g} ± {:.2g}", e, 0.5 * (s.ci[i].second - s.ci[i].first));
    else
      list += fmt::format("{:.4g}", e);
  }
  fmt::print("lyapunov     {} per unit time ({} periods{}){}\n", list, s.periods,
             s.singular_periods ? fmt::format(", {} left out for a grazing", s.singular_periods) : "",
             s.chaotic() ? ": chaotic" : "");
}

int ExitCode(vibro::RunStatus s) {
  switch (s) {
    case vibro::RunStatus::kOk: return 0;
    case vibro::RunStatus::kNumericalFailure: return kExitNumerical;
    case vibro::RunStatus::kInterrupted: return kExitInterrupted;
    case vibro::RunStatus::kUndetermined: return kExitNumerical;
  }
  return kExitInternal;
}
