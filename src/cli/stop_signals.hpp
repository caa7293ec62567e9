// Stop requests of the `vibro` command (SIGINT, SIGTERM), honoured the same way by every command.
//
// The handlers are installed once, before any command runs, and stay installed until exit:
//   - the first signal sets the stop flag, which every long loop polls (engines, continuation,
//     partitions, studies, sweeps); the command then writes what it computed with status
//     "interrupted" and exits 130;
//   - further signals while a final write is in progress (a FinalWrite is alive) are ignored, so
//     that a second Ctrl-C never leaves a half-written file;
//   - a third signal outside a final write ends the process at once (exit 130): the way out of a
//     loop that does not poll;
//   - a command with nothing partial to keep (`orbit`, `check`) may register a file to remove and
//     leave on the first signal (DiscardOnStop).
#pragma once

#include <atomic>
#include <string>

namespace vibro::cli {

// The process-wide stop flag (set by the handlers).
const std::atomic<bool>& StopFlag();
bool StopRequested();

// Installs the SIGINT/SIGTERM handlers for the rest of the process; then, when the environment
// variable VIBRO_SIGNAL_READY is set (not empty), prints "vibro: ready for stop requests" on
// stderr (docs/reliability.md).
void InstallStopHandlers();

// While alive, signals only set the flag: the file being written is never cut short.
class FinalWrite {
 public:
  FinalWrite();
  ~FinalWrite();
  FinalWrite(const FinalWrite&) = delete;
  FinalWrite& operator=(const FinalWrite&) = delete;
};

// From now on the first signal removes `path` (when not empty: a file this command created and
// has not filled) and exits 130 at once. Cleared by KeepOnStop().
void DiscardOnStop(const std::string& path);
void KeepOnStop();

// --time-limit S of a command (docs/cli.md "Time limits"): S seconds after this call (S > 0), the
// stop flag is set as by a signal, so that every loop of the command ends the way a stop request
// ends it, keeping what was computed; the command then exits 3 instead of 130 (main.cpp), after
// the line TimeLimitMessage(). `option` names the limit in that line ("--time-limit").
void ArmTimeLimit(double seconds, const std::string& option);
bool TimeLimitReached();
const char* TimeLimitMessage();

}  // namespace vibro::cli
