// Progress of long commands on stderr, only when the command prints text (not --json); never
// moves backwards; thread-safe.
//   - stderr a terminal: a bar redrawn in place (\r) at most every 0.2 s, with the rate and the
//     time left, ended by a newline;
//   - stderr a file or pipe (a log): whole lines, at most one every kLineSeconds, the first one
//     after kLineSeconds (a short command writes none); when one was written, a last line with
//     the state reached and the time taken.
#pragma once

#include <chrono>
#include <mutex>
#include <string>

#include "vibro/observer.hpp"

namespace vibro::cli {

class Progress {
 public:
  static constexpr double kLineSeconds = 5.0;

  Progress(std::string label, bool json);
  ~Progress();  // ends the bar's line, or writes the last line of a log
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  bool active() const { return style_ != Style::kOff; }
  // done of total units; calls with a smaller `done` than already seen are ignored.
  void Update(long long done, long long total, const std::string& note = "");

 private:
  enum class Style { kOff, kBar, kLines };
  using Clock = std::chrono::steady_clock;
  // "42% (420 / 1000), 35.2/s, 16 s left" from the state seen (mutex held).
  std::string State(Clock::time_point now, bool final) const;

  std::string label_;
  Style style_;
  std::mutex mutex_;
  long long done_ = -1, total_ = 0;  // the latest state seen
  std::string note_;
  long long first_done_ = -1;  // the first state seen, and when: the rate counts from there
  Clock::time_point first_{}, last_{};
  bool drawn_ = false;  // anything written
};

// Period-by-period progress of a simulation (the stroboscopic section is reached once a period):
// the section's period of the run's `periods` (a resumed run starts at its checkpoint's, whose
// section is not reported again).
class PeriodProgress final : public Observer {
 public:
  PeriodProgress(Progress& progress, long long periods) : progress_(progress), periods_(periods) {}
  void OnSection(const Sample& sample) override { progress_.Update(sample.clock.period, periods_); }

 private:
  Progress& progress_;
  long long periods_;
};

}  // namespace vibro::cli
