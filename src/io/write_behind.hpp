// The store's write-behind (docs/output.md, "Writing"): one writer thread that runs one job at a
// time (the encoding of the rows set aside for a flush), while the simulation goes on buffering
// the rows that follow. The job makes no HDF5 call: the store's thread writes what it encoded
// after Wait(), so that the library is only ever used by that thread, while the writer waits
// (memory_reserve.hpp). A job's exception is thrown again by the next Wait() in the store's thread.
#pragma once

#include <signal.h>

#include <condition_variable>
#include <exception>
#include <functional>
#include <mutex>
#include <stdexcept>
#include <string>
#include <system_error>
#include <thread>

namespace vibro::store {

class WriteBehind {
 public:
  WriteBehind() = default;
  WriteBehind(const WriteBehind&) = delete;
  WriteBehind& operator=(const WriteBehind&) = delete;
  ~WriteBehind() {
    {
      std::unique_lock<std::mutex> lock(mutex_);
      done_.wait(lock, [&] { return !job_; });
      stop_ = true;
    }
    ready_.notify_one();
    if (thread_.joinable()) thread_.join();
  }

  // Waits for the job under way, if any; rethrows its exception.
  void Wait() {
    std::unique_lock<std::mutex> lock(mutex_);
    done_.wait(lock, [&] { return !job_; });
    if (error_) {
      const std::exception_ptr e = error_;
      error_ = nullptr;
      std::rethrow_exception(e);
    }
  }

  // Whether a job is under way (no wait).
  bool Busy() {
    std::lock_guard<std::mutex> lock(mutex_);
    return static_cast<bool>(job_);
  }

  // Runs `job` on the writer thread (started on the first call); the caller has called Wait().
  void Start(std::function<void()> job) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      job_ = std::move(job);
    }
    if (!thread_.joinable()) {
      try {
        thread_ = std::thread([this] { Loop(); });
      } catch (const std::system_error& e) {
        // The system refused the thread (ulimit -v, a process limit): the job is dropped, so that
        // Wait() and the destructor do not wait for ever for a thread that does not exist, and
        // the refusal is reported as TBB reports its own (exit 3, MemoryError in Python).
        std::lock_guard<std::mutex> lock(mutex_);
        job_ = nullptr;
        throw std::runtime_error(std::string("pthread_create has failed: ") + e.what());
      }
    }
    ready_.notify_one();
  }

 private:
  void Loop() {
    // Stop requests (SIGINT, SIGTERM, ...) are for the simulation's thread, never this one (a
    // write interrupted by a handler here would fail for no reason).
    sigset_t all;
    sigfillset(&all);
    pthread_sigmask(SIG_BLOCK, &all, nullptr);
    std::unique_lock<std::mutex> lock(mutex_);
    for (;;) {
      ready_.wait(lock, [&] { return job_ || stop_; });
      if (!job_) return;
      lock.unlock();
      std::exception_ptr error;
      try {
        job_();
      } catch (...) {
        error = std::current_exception();
      }
      lock.lock();
      job_ = nullptr;
      error_ = error;
      done_.notify_all();
    }
  }

  std::mutex mutex_;
  std::condition_variable ready_, done_;
  std::function<void()> job_;
  std::exception_ptr error_;
  bool stop_ = false;
  std::thread thread_;
};

}  // namespace vibro::store
