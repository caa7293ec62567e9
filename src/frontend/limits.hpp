// The limits of the commands' options, one set for both callers: the command line
// (src/cli/main.cpp builds its option validators from these constants, so its messages are
// CLI11's, and each cmd_*.cpp runs the checks below again) and the Python module
// (python/src/bindings.cpp, where nothing else checks a keyword argument). Each check appends
// "OPTION VALUE: what was expected" with the option named as the caller's users write it
// (--max-points or max_points), or throws InputError with every problem of a command at once.
#pragma once

#include <climits>
#include <optional>
#include <string>
#include <vector>

#include "vibro/studies.hpp"
#include "vibro/system.hpp"

namespace vibro::frontend {

// How options are named in messages: "--sticking-fraction" (command line) or "sticking_fraction"
// (Python keyword arguments).
enum class Naming { kCli, kPython };
std::string OptionName(Naming naming, const std::string& cli_option);

// An integer option's range, both ends included.
struct IntLimit {
  long long lo, hi;
};
inline constexpr IntLimit kPeriodLimit{0, 4096};                // --period Q (orbit, continue, partition)
inline constexpr IntLimit kImpactsLimit{0, 1 << 20};            // orbit --impacts
inline constexpr IntLimit kTransientLimit{0, INT_MAX};          // orbit, continue --transient
inline constexpr IntLimit kMaxPointsLimit{1, 1 << 24};          // continue --max-points
inline constexpr IntLimit kThreadsLimit{0, 4096};               // --threads (0: all cores)
inline constexpr IntLimit kSamplesLimit{1, 1LL << 24};          // attractors --samples
inline constexpr IntLimit kGridLimit{1, 1 << 16};               // basin --grid NX,NY (each)
inline constexpr long long kMaxStudyCells = 1LL << 24;          // basin: NX·NY
inline constexpr IntLimit kSteps1Limit{1, 1 << 16};             // partition --steps1
inline constexpr IntLimit kSweepStepsLimit{1, 1 << 22};         // sweep --steps
inline constexpr IntLimit kRecordLimit{1, 1 << 16};             // sweep --record

// "OPTION VALUE: expected an integer in [LO, HI]" when value is outside `limit`.
void CheckInteger(Naming naming, const char* cli_option, long long value, IntLimit limit,
                  std::vector<std::string>& problems);
// "OPTION VALUE: expected a finite number" for nan and ±inf.
void CheckFinite(Naming naming, const char* cli_option, double value, std::vector<std::string>& problems);
// A file name with a NUL character is refused: the system would open the file named by the part
// before it, another file than the one given (only Python strings can hold one).
void CheckPath(Naming naming, const char* cli_option, const std::string& path, std::vector<std::string>& problems);
// Throws InputError(problems) when there are any.
void ThrowIfAny(const std::vector<std::string>& problems);

// ---- the checks of each command's options (InputError with every problem) ----

// orbit: --period, --impacts, --transient, --guess PHASE[,VELOCITY].
void CheckOrbitOptions(Naming naming, long long period, long long impacts, long long transient,
                       std::optional<double> guess_phase, std::optional<double> guess_velocity);

// continue: --to, --step, --max-points, --period, --transient.
void CheckContinuationOptions(Naming naming, double to, double step, long long max_points, long long period,
                              long long transient);

// sweep: --from, --to, --steps, --record.
void CheckSweepOptions(Naming naming, double from, double to, long long steps, long long record);

// attractors and basin: the two coordinates and their ranges (defaults when a range is empty),
// --grid (basin) or --samples (attractors), and --threads.
struct StudySpec {
  std::string x = "x_B", y = "v_B";
  std::vector<double> x_range, y_range;
  std::vector<long long> grid{64, 64};
  long long samples = 200;
  long long threads = 0;
};
struct StudyAxes {
  Coordinate x, y;
};
StudyAxes CheckStudyOptions(const System& system, const StudySpec& spec, bool basin, Naming naming);

}  // namespace vibro::frontend
