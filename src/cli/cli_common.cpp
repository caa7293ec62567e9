// What the command files of src/cli share (cli_common.hpp).
#include "cli/cli_common.hpp"

#include <fmt/format.h>

#include "cli/text_format.hpp"
#include "vibro/scene_file.hpp"

void PrintAttractor(const vibro::Attractor& a, double restitution) {
  fmt::print("{}", vibro::cli::AttractorText(a, restitution));
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
