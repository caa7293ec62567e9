// The limits of the commands' options and their checks (limits.hpp).
#include "frontend/limits.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "frontend/frontend.hpp"
#include "vibro/scene_file.hpp"

namespace vibro::frontend {

std::string OptionName(Naming naming, const std::string& cli_option) {
  if (naming == Naming::kCli) return cli_option;
  std::string name = cli_option.substr(cli_option.find_first_not_of('-'));
  std::replace(name.begin(), name.end(), '-', '_');
  return name;
}

void CheckInteger(Naming naming, const char* cli_option, long long value, IntLimit limit,
                  std::vector<std::string>& problems) {
  if (value >= limit.lo && value <= limit.hi) return;
  problems.push_back(limit.hi == INT_MAX
                         ? fmt::format("{} {}: expected an integer ≥ {}", OptionName(naming, cli_option), value, limit.lo)
                         : fmt::format("{} {}: expected an integer in [{}, {}]", OptionName(naming, cli_option), value,
                                       limit.lo, limit.hi));
}

void CheckFinite(Naming naming, const char* cli_option, double value, std::vector<std::string>& problems) {
  if (std::isfinite(value)) return;
  problems.push_back(fmt::format("{} {}: expected a finite number", OptionName(naming, cli_option), value));
}

void CheckPath(Naming naming, const char* cli_option, const std::string& path, std::vector<std::string>& problems) {
  const auto nul = path.find('\0');
  if (nul == std::string::npos) return;
  std::string shown;  // the NUL as \0, so that the message is one printable line
  for (char c : path) shown += c == '\0' ? std::string("\\0") : std::string(1, c);
  problems.push_back(fmt::format("{} '{}': a file name cannot contain a NUL character (the system would open "
                                 "'{}')",
                                 OptionName(naming, cli_option), shown, path.substr(0, nul)));
}

void ThrowIfAny(const std::vector<std::string>& problems) {
  if (!problems.empty()) throw InputError(problems);
}

void CheckOrbitOptions(Naming naming, long long period, long long impacts, long long transient,
                       std::optional<double> guess_phase, std::optional<double> guess_velocity) {
  std::vector<std::string> problems;
  CheckInteger(naming, "--period", period, kPeriodLimit, problems);
  CheckInteger(naming, "--impacts", impacts, kImpactsLimit, problems);
  CheckInteger(naming, "--transient", transient, kTransientLimit, problems);
  if ((guess_phase && !std::isfinite(*guess_phase)) || (guess_velocity && !std::isfinite(*guess_velocity)))
    problems.push_back(fmt::format("{} {}{}: expected finite numbers (no nan or inf)", OptionName(naming, "--guess"),
                                   guess_phase.value_or(0.0),
                                   guess_velocity ? fmt::format(",{}", *guess_velocity) : std::string()));
  ThrowIfAny(problems);
}

void CheckContinuationOptions(Naming naming, double to, double step, long long max_points, long long period,
                              long long transient) {
  std::vector<std::string> problems;
  CheckFinite(naming, "--to", to, problems);
  CheckFinite(naming, "--step", step, problems);
  CheckInteger(naming, "--max-points", max_points, kMaxPointsLimit, problems);
  CheckInteger(naming, "--period", period, kPeriodLimit, problems);
  CheckInteger(naming, "--transient", transient, kTransientLimit, problems);
  ThrowIfAny(problems);
}

void CheckSweepOptions(Naming naming, double from, double to, long long steps, long long record) {
  std::vector<std::string> problems;
  CheckFinite(naming, naming == Naming::kPython ? "from_" : "--from", from, problems);  // `from` is a keyword
  CheckFinite(naming, "--to", to, problems);
  CheckInteger(naming, "--steps", steps, kSweepStepsLimit, problems);
  CheckInteger(naming, "--record", record, kRecordLimit, problems);
  ThrowIfAny(problems);
}

StudyAxes CheckStudyOptions(const System& sys, const StudySpec& a, bool basin, Naming naming) {
  const auto opt = [&](const char* o) { return OptionName(naming, o); };
  const bool cli = naming == Naming::kCli;
  std::vector<std::string> problems;
  for (const auto& [o, name] : {std::pair{"--x", a.x}, std::pair{"--y", a.y}})
    if (auto p = CheckCoordinate(sys, name); !p.empty()) problems.push_back(fmt::format("{} {}: {}", opt(o), name, p));
  StudyAxes axes{StudyCoordinate(sys, a.x, a.x_range, opt("--x-range").c_str(), problems),
                 StudyCoordinate(sys, a.y, a.y_range, opt("--y-range").c_str(), problems)};
  if (basin) {
    const auto shown = [&] {
      return cli ? fmt::format("{}", fmt::join(a.grid, ",")) : fmt::format("({})", fmt::join(a.grid, ", "));
    };
    if (a.grid.size() != 2 || a.grid[0] < 1 || a.grid[1] < 1)
      problems.push_back(cli ? "--grid: expected NX,NY with NX, NY ≥ 1" : "grid: expected (NX, NY) with NX, NY ≥ 1");
    else if (a.grid[0] > kGridLimit.hi || a.grid[1] > kGridLimit.hi)
      problems.push_back(fmt::format("{} {}: expected NX, NY ≤ {}", opt("--grid"), shown(), kGridLimit.hi));
    else if (a.grid[0] * a.grid[1] > kMaxStudyCells)
      problems.push_back(fmt::format("{} {}: at most {} cells (2^24) in one study", opt("--grid"), shown(),
                                     kMaxStudyCells));
  } else if (a.samples < 1) {
    problems.push_back(opt("--samples") + ": expected N ≥ 1");
  } else {
    CheckInteger(naming, "--samples", a.samples, kSamplesLimit, problems);
  }
  CheckInteger(naming, "--threads", a.threads, kThreadsLimit, problems);
  ThrowIfAny(problems);
  return axes;
}

}  // namespace vibro::frontend
