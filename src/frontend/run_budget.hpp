// The limits of one simulation (`vibro simulate`, Python `simulate`), checked as it goes against
// its event rate: the wall time (--time-limit, for the whole run) and, with an output file, the
// free space of the disk that holds it. A run whose rate would take it past either ends at once
// with LimitError and one line saying why ("1.0·10⁹ impacts per time unit: …"), instead of running
// for days or filling the disk; its output file keeps what was written up to its last flush.
#pragma once

#include <chrono>
#include <stdexcept>
#include <string>

#include "vibro/observer.hpp"
#include "vibro/scene.hpp"
#include "vibro/system.hpp"

namespace vibro::frontend {

// A run ended by its limits (exit 3 on the command line).
class LimitError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class RunBudget final : public Observer {
 public:
  // The default --time-limit of a simulation: one day.
  static constexpr double kDefaultTimeLimit = 86400.0;
  // time_limit: seconds for the whole run, 0 for none; out: the output file ("" for none);
  // option: the limit as the caller's users write it (--time-limit or time_limit).
  RunBudget(const System& system, const Scene& scene, double time_limit, std::string out, std::string option);
  void OnEvent(const Event& e) override;
  void OnSection(const Sample& s) override;

 private:
  using WallClock = std::chrono::steady_clock;
  void Check(const Clock& now);
  [[noreturn]] void Refuse(const Clock& now, const std::string& what) const;

  double period_;
  long long periods_;
  double time_limit_;
  std::string out_, option_;
  WallClock::time_point created_ = WallClock::now(), first_seen_{};
  bool seen_ = false;
  Clock first_{};
  long long events_ = 0, impacts_ = 0;
  long long file_bytes_ = -1;  // the output's size on disk when first seen
};

}  // namespace vibro::frontend
