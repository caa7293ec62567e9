// The bounds of one proof (budget.hpp).
#include "proof/budget.hpp"

#include <condition_variable>
#include <mutex>
#include <thread>

#include "vibro/stop_request.hpp"

namespace vibro::proof {

Budget::Budget(double seconds, const std::atomic<bool>* stop)
    : seconds_(seconds),
      end_(std::chrono::steady_clock::now() +
           std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(seconds))),
      stop_(stop),
      process_stop_(ProcessStopFlag()) {}

bool Budget::interrupted() const {
  return (stop_ && stop_->load(std::memory_order_relaxed)) ||
         (process_stop_ && process_stop_->load(std::memory_order_relaxed));
}

bool Budget::passed() const {
  if (interrupted()) return true;
  if (std::chrono::steady_clock::now() <= end_) return false;
  expired_.store(true);
  return true;
}

void Budget::Watch(const std::function<void()>& search) const {
  std::atomic<bool> stop{passed()};
  std::mutex mutex;
  std::condition_variable wake;
  bool done = false;
  std::thread watchdog([&] {
    std::unique_lock<std::mutex> lock(mutex);
    while (!done && !stop.load()) {
      wake.wait_for(lock, std::chrono::milliseconds(10));
      if (passed()) stop.store(true);
    }
  });
  struct Join {  // also when `search` throws
    std::mutex& mutex;
    std::condition_variable& wake;
    bool& done;
    std::thread& watchdog;
    ~Join() {
      {
        const std::lock_guard<std::mutex> lock(mutex);
        done = true;
      }
      wake.notify_all();
      watchdog.join();
    }
  } join{mutex, wake, done, watchdog};
  const ThreadStopFlag scope(&stop);
  search();
}

}  // namespace vibro::proof
