// The process's stop request (docs/reliability.md): one flag that every run polls, besides its
// own SimulationOptions::stop_requested.
#pragma once

#include <atomic>

namespace vibro {

// Set by a program that turns SIGINT/SIGTERM into a stop request (the `vibro` command does so
// before any command runs). From then on every run started by Simulate() polls `flag` between
// events and inside its engine's stepping and root loops, wherever the run is started from: the
// transients and Newton iterations of an orbit solve inside a continuation or a partition, the
// orbits of a study's classes. A run that sees it ends with status interrupted; the command
// that owns the computation reports it as interrupted. nullptr (the default): none.
void SetProcessStopFlag(const std::atomic<bool>* flag);
// The flag the runs started on the calling thread poll: the thread's own (ThreadStopFlag) while
// one is set, else the process's.
const std::atomic<bool>* ProcessStopFlag();

// While alive, runs started on the calling thread poll `flag` instead of the process's stop flag:
// a computation's own limit over the runs it starts (the prover's time limit over its orbit
// search, docs/prove.md). Whoever sets `flag` sets it on the process's stop request too.
class ThreadStopFlag {
 public:
  explicit ThreadStopFlag(const std::atomic<bool>* flag);
  ~ThreadStopFlag();
  ThreadStopFlag(const ThreadStopFlag&) = delete;
  ThreadStopFlag& operator=(const ThreadStopFlag&) = delete;

 private:
  const std::atomic<bool>* previous_;
};

}  // namespace vibro
