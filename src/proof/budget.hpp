// The bounds of one proof (docs/prove.md "Bounds"): a wall-clock limit over the whole proof, the
// orbit search before it included; the stop requests (SIGINT and SIGTERM of the command, Ctrl-C
// in Python), which end it with no verdict; and the sizes a certificate may reach, so that every
// request is bounded in time and memory whatever its period.
#pragma once

#include <atomic>
#include <chrono>
#include <cstddef>
#include <functional>

namespace vibro::proof {

// Unknowns of an impacting orbit's multiple-shooting map, m(2n + 1) for m impacts and n modes:
// the Jacobian over the box has m²(2n + 1)² entries and the checker's time grows with them.
inline constexpr std::size_t kMaxUnknowns = 128;
// Subdivision pieces of the positivity tests of one proof (each is written to the certificate).
inline constexpr std::size_t kMaxPieces = 1'000'000;

class Budget {
 public:
  // `stop`: the caller's stop flag (or nullptr); the process's (vibro/stop_request.hpp), as it is
  // when the budget is made, is polled too.
  Budget(double seconds, const std::atomic<bool>* stop);
  Budget(const Budget&) = delete;
  Budget& operator=(const Budget&) = delete;

  // Out of time or stopped: every loop of a proof ends.
  bool passed() const;
  bool interrupted() const;  // a stop request came
  // passed() said so because the time was up: the proof ended for that reason.
  bool expired() const { return expired_.load(); }
  double seconds() const { return seconds_; }
  // Takes n pieces; false once the proof would hold more than kMaxPieces.
  bool TakePieces(std::size_t n) const { return pieces_.fetch_add(n) + n <= kMaxPieces; }

  // Runs `search` (the orbit search: transient, Newton, one period followed) with the budget over
  // the runs it starts on this thread: a watchdog sets the flag that they poll (ThreadStopFlag)
  // as soon as passed(). The caller checks passed() afterwards: what the search returned then is
  // no result.
  void Watch(const std::function<void()>& search) const;

 private:
  double seconds_;
  std::chrono::steady_clock::time_point end_;
  const std::atomic<bool>* stop_;
  const std::atomic<bool>* process_stop_;
  mutable std::atomic<std::size_t> pieces_{0};
  mutable std::atomic<bool> expired_{false};
};

}  // namespace vibro::proof
