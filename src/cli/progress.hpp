// Progress of long commands on stderr: shown only when stderr is a terminal and the command
// prints text (not --json); never moves backwards; redrawn at most every 0.2 s; thread-safe.
#pragma once

#include <chrono>
#include <mutex>
#include <string>

#include "vibro/observer.hpp"

namespace vibro::cli {

class Progress {
 public:
  Progress(std::string label, bool json);
  ~Progress();  // ends the line if anything was drawn
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  bool active() const { return active_; }
  // done of total units; calls with a smaller `done` than already shown are ignored.
  void Update(long long done, long long total, const std::string& note = "");

 private:
  std::string label_;
  bool active_;
  std::mutex mutex_;
  long long shown_ = -1;
  bool drawn_ = false;
  std::chrono::steady_clock::time_point last_{};
};

// Period-by-period progress of a simulation (the stroboscopic section is reached once a period).
class PeriodProgress final : public Observer {
 public:
  // first: the period the run starts at (a resumed run starts at its checkpoint).
  PeriodProgress(Progress& progress, long long periods, long long first = 0)
      : progress_(progress), periods_(periods), seen_(first - 1) {}
  void OnSection(const Sample& /*sample*/) override { progress_.Update(++seen_, periods_); }

 private:
  Progress& progress_;
  long long periods_;
  long long seen_;  // sections seen so far; the first is the starting state
};

}  // namespace vibro::cli
