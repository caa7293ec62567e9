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
const std::atomic<bool>* ProcessStopFlag();

}  // namespace vibro
