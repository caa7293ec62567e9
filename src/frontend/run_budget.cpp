// A simulation's limits against its event rate (run_budget.hpp).
#include "frontend/run_budget.hpp"

#include <sys/stat.h>
#include <sys/statvfs.h>

#include <cmath>
#include <filesystem>
#include <limits>

#include <fmt/format.h>

namespace vibro::frontend {
namespace {

// 1.0·10⁹ (two significant digits, the exponent in superscript).
std::string Magnitude(double x) {
  if (!(x > 0) || !std::isfinite(x)) return fmt::format("{:g}", x);
  int e = static_cast<int>(std::floor(std::log10(x)));
  double m = x / std::pow(10.0, e);
  if (m >= 9.95) m /= 10, ++e;
  if (e < 4 && e > -3) return fmt::format("{:.3g}", x);
  static const char* digits[] = {"⁰", "¹", "²", "³", "⁴", "⁵", "⁶", "⁷", "⁸", "⁹"};
  std::string sup = e < 0 ? "⁻" : "";
  for (char c : std::to_string(std::abs(e))) sup += digits[c - '0'];
  return fmt::format("{:.1f}·10{}", m, sup);
}

std::string Duration(double s) {
  if (s < 120) return fmt::format("{:.0f} s", s);
  if (s < 7200) return fmt::format("{:.0f} min", s / 60);
  if (s < 172800) return fmt::format("{:.1f} h", s / 3600);
  return fmt::format("{:.1f} days", s / 86400);
}

std::string Bytes(double b) {
  const char* units[] = {"B", "kB", "MB", "GB", "TB", "PB", "EB"};
  int u = 0;
  while (b >= 1000 && u < 6) b /= 1000, ++u;
  return fmt::format("{:.3g} {}", b, units[u]);
}

// Bytes the file occupies on its disk (-1 when it cannot be seen).
long long DiskBytes(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return -1;
  return static_cast<long long>(st.st_blocks) * 512;
}

// Bytes free for this user on the disk holding `path` (-1 when unknown).
long long FreeBytes(const std::string& path) {
  std::error_code ec;
  auto dir = std::filesystem::absolute(path, ec).parent_path();
  struct statvfs v {};
  if (ec || ::statvfs(dir.c_str(), &v) != 0) return -1;
  return static_cast<long long>(v.f_bavail) * static_cast<long long>(v.f_frsize);
}

// The rate is judged after this much wall time (a short run never is) and then at most this often.
constexpr double kWarmup = 1.0;
constexpr long long kEventsBetweenChecks = 4096;

}  // namespace

RunBudget::RunBudget(const System& system, const Scene& scene, double time_limit, std::string out,
                     std::string option)
    : period_(system.period()),
      periods_(scene.run.periods),
      time_limit_(time_limit),
      out_(std::move(out)),
      option_(std::move(option)) {}

void RunBudget::OnEvent(const Event& e) {
  ++events_;
  if (e.kind == EventKind::kImpact) ++impacts_;
  if (!seen_ || events_ % kEventsBetweenChecks == 0) Check(e.clock);
}

void RunBudget::OnSection(const Sample& s) { Check(s.clock); }

void RunBudget::Check(const Clock& now) {
  const auto wall = WallClock::now();
  if (!seen_) {
    seen_ = true;
    first_ = now;
    first_seen_ = wall;
    events_ = 0, impacts_ = 0;
    if (!out_.empty()) file_bytes_ = DiskBytes(out_);
    return;
  }
  const double spent = std::chrono::duration<double>(wall - created_).count();
  const double left = time_limit_ > 0 ? time_limit_ - spent : std::numeric_limits<double>::infinity();
  if (left <= 0)
    Refuse(now, fmt::format("the time limit of {:g} s ({}) was reached", time_limit_, option_));
  const double measured = std::chrono::duration<double>(wall - first_seen_).count();
  if (measured < kWarmup) return;
  // Simulated time since the first look, and what remains of the run.
  const double done = static_cast<double>(now.period - first_.period) * period_ + (now.offset - first_.offset);
  const double remaining = static_cast<double>(periods_ - now.period) * period_ - now.offset;
  if (!(done > 0) || !(remaining > 0)) return;
  const double wall_left = measured * remaining / done;
  if (wall_left > left)
    Refuse(now,
           fmt::format("the rest of the run would take about {} at this pace, past the time limit of {:g} s ({}, "
                       "0 for none)",
                       Duration(wall_left), time_limit_, option_));
  if (!out_.empty() && file_bytes_ >= 0 && events_ > 0) {
    const long long bytes = DiskBytes(out_);
    const long long grown = bytes - file_bytes_;
    if (grown >= (1LL << 20)) {  // enough written to measure the bytes per event
      const double needed = static_cast<double>(grown) / static_cast<double>(events_) *
                            (static_cast<double>(events_) * remaining / done);
      const long long free = FreeBytes(out_);
      if (free >= 0 && needed > static_cast<double>(free))
        Refuse(now,
               fmt::format("{} would need about {} more at this pace, and its disk has {} free", out_,
                           Bytes(needed), Bytes(static_cast<double>(free))));
    }
  }
}

void RunBudget::Refuse(const Clock& now, const std::string& what) const {
  const double done = static_cast<double>(now.period - first_.period) * period_ + (now.offset - first_.offset);
  const bool impacts = impacts_ * 10 >= events_ * 9;
  const std::string rate =
      done > 0 ? fmt::format("{} {} per time unit", Magnitude(static_cast<double>(events_) / done),
                             impacts ? "impacts" : "events")
               : std::string("no time simulated");
  throw LimitError(fmt::format("{}: {}; stopped in period {} of {}{}", rate, what, now.period, periods_,
                               out_.empty() ? std::string()
                                            : fmt::format(", {} keeps what was written up to its last flush", out_)));
}

}  // namespace vibro::frontend
