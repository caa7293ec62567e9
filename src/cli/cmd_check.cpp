// `vibro check SCENE`: the exact engine, CVODE and the Poincaré solver (and quad) compared
// (docs/verification.md).
#include <optional>

#include <fmt/format.h>

#include "cli/cli_common.hpp"
#include "cli/stop_signals.hpp"
#include "vibro/check.hpp"
#include "vibro/scene_file.hpp"
#include "vibro/summary_json.hpp"
#include "vibro/system.hpp"

int RunCheck(const std::string& path, const std::vector<std::string>& sets, bool json,
             bool with_quad) {
  const auto loaded = vibro::LoadScene(path, sets);
  const vibro::System sys(loaded.scene);
  vibro::cli::DiscardOnStop("");  // nothing partial to keep
  const auto report = vibro::CrossCheck(sys, loaded.scene, with_quad);
  vibro::cli::KeepOnStop();
  if (json) {
    fmt::print("{}\n", vibro::CheckJson(report));
  } else {
    const auto cell = [](const std::optional<double>& v) {
      return v ? fmt::format("{:>18.12g}", *v) : fmt::format("{:>18}", "-");
    };
    fmt::print("{:<40} {:>18} {:>18} {:>18}{} {:>10} {:>10}  {}\n", "quantity", "exact", "cvode",
               "poincare", with_quad ? fmt::format(" {:>18}", "quad") : "", "max diff",
               "tolerance", "");
    for (const auto& r : report.rows) {
      fmt::print("{:<40} {} {} {}{} {:>10.2e} {:>10.2e}  {}{}\n", r.quantity, cell(r.exact),
                 cell(r.cvode), cell(r.orbit), with_quad ? fmt::format(" {}", cell(r.quad)) : "",
                 r.difference, r.tolerance, r.ok ? "ok" : "FAIL",
                 r.note.empty() ? "" : fmt::format("  {}", r.note));
    }
    fmt::print("{}\n", report.ok ? "agreement: ok" : "agreement: FAILED (beyond tolerance)");
  }
  return report.ok ? 0 : kExitDisagree;
}
