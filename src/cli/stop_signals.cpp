#include "cli/stop_signals.hpp"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <thread>

#include <fmt/format.h>

#include "vibro/stop_request.hpp"

namespace vibro::cli {
namespace {

std::atomic<bool> g_stop{false};
std::atomic<int> g_signals{0};
std::atomic<int> g_writing{0};
std::atomic<bool> g_discard{false};
// The exit code of a stop that cannot wait for the command (discard mode, grace over): 130 for a
// signal, 3 once the --time-limit was reached first.
std::atomic<int> g_stop_exit{130};
std::atomic<bool> g_time_up{false};
// "vibro: the time limit of S s (--time-limit, ...) was reached" (written before the watchdog
// starts, read by the handlers and the watchdog only).
char g_time_message[512] = {0};
// The file to remove on a stop in discard mode; written before g_discard is set, read by the
// handler only (unlink and _exit are async-signal-safe).
char g_discard_path[4096] = {0};

void Say(const char* text) {
  const ssize_t n = write(STDERR_FILENO, text, std::strlen(text));
  (void)n;
}

// After a stop request every loop ends within a second; a library call that never returns (the
// HDF5 filter pipeline on a damaged chunk of a resumed file was seen to) cannot poll. The first
// request therefore arms a grace period: past it, the process leaves (files keep what was last
// flushed, as after SIGKILL). A final write in progress gets up to 30 s.
constexpr unsigned kGraceSeconds = 4;
std::atomic<int> g_grace_extensions{0};

extern "C" void OnGraceOver(int) {
  if (g_writing.load() > 0 && g_grace_extensions.fetch_add(1) < 6) {
    alarm(kGraceSeconds);
    return;
  }
  Say("\nvibro: the stop request could not be honoured in time (a library call does not return); "
      "leaving now: files keep what was last flushed\n");
  if (g_time_up.load()) Say(g_time_message);
  _exit(g_stop_exit.load());
}

extern "C" void OnStopSignal(int) {
  g_stop.store(true);
  const int count = g_signals.fetch_add(1) + 1;
  if (count == 1) alarm(kGraceSeconds);
  if (g_discard.load()) {
    if (g_discard_path[0] != '\0') unlink(g_discard_path);
    if (g_time_up.load()) Say(g_time_message);
    Say(g_time_up.load() ? "vibro: nothing to keep\n" : "\nvibro: interrupted; nothing to keep\n");
    _exit(g_stop_exit.load());
  }
  if (count >= 3 && g_writing.load() == 0) {
    Say("\nvibro: third stop request: leaving now (files keep what was flushed)\n");
    _exit(130);
  }
}

}  // namespace

const std::atomic<bool>& StopFlag() { return g_stop; }
bool StopRequested() { return g_stop.load(); }

void InstallStopHandlers() {
  struct sigaction sa {};
  sa.sa_handler = OnStopSignal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESTART;
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  struct sigaction grace {};
  grace.sa_handler = OnGraceOver;
  sigemptyset(&grace.sa_mask);
  grace.sa_flags = SA_RESTART;
  sigaction(SIGALRM, &grace, nullptr);
  // A file-size limit (ulimit -f) is a write that fails with EFBIG, reported as a full disk is
  // (exit 3, the file keeping its last flush), not a death by SIGXFSZ (as Python ignores it too).
  signal(SIGXFSZ, SIG_IGN);
  // Every run polls the flag, also those started deep inside another computation (an orbit
  // solve inside a continuation, the orbits of a study's classes).
  SetProcessStopFlag(&g_stop);
  // For scripts and tests that send stop requests: a signal sent before this point ends the
  // process by the default action (no exit 130, nothing kept), so they wait for this line
  // (printed once, at the first installation).
  static std::atomic<bool> announced{false};
  if (const char* ready = std::getenv("VIBRO_SIGNAL_READY");
      ready != nullptr && *ready != '\0' && !announced.exchange(true))
    Say("vibro: ready for stop requests\n");
}

namespace {
// Installed before main() runs (static initialization of the program), so that a stop request
// that comes while the command line is being set up is honoured too; main() installs them again.
[[maybe_unused]] const bool g_installed_early = (InstallStopHandlers(), true);
}  // namespace

FinalWrite::FinalWrite() { g_writing.fetch_add(1); }
FinalWrite::~FinalWrite() { g_writing.fetch_sub(1); }

void DiscardOnStop(const std::string& path) {
  g_discard.store(false);
  const size_t n = std::min(path.size(), sizeof g_discard_path - 1);
  std::memcpy(g_discard_path, path.data(), n);
  g_discard_path[n] = '\0';
  g_discard.store(true);
  if (g_stop.load()) OnStopSignal(SIGTERM);  // a signal that came before: leave now
}

void KeepOnStop() { g_discard.store(false); }

void ArmTimeLimit(double seconds, const std::string& option) {
  if (!(seconds > 0)) return;
  const std::string text = fmt::format("vibro: the time limit of {:g} s ({}, for the whole command) was reached\n",
                                       seconds, option);
  const size_t n = std::min(text.size(), sizeof g_time_message - 1);
  std::memcpy(g_time_message, text.data(), n);
  g_time_message[n] = '\0';
  const auto end = std::chrono::steady_clock::now() +
                   std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(seconds));
  // Detached: it sleeps until the limit or the process's end, and touches only atomics.
  std::thread([end] {
    // Signals are for the command's own threads, never this one.
    sigset_t all;
    sigfillset(&all);
    pthread_sigmask(SIG_BLOCK, &all, nullptr);
    std::this_thread::sleep_until(end);
    if (g_stop.load()) return;  // a stop request came first: an interruption
    g_stop_exit.store(3);
    g_time_up.store(true);
    OnStopSignal(0);  // a stop request like a signal's: every loop ends, what was computed is kept
  }).detach();
}

bool TimeLimitReached() { return g_time_up.load(); }
const char* TimeLimitMessage() { return g_time_message; }

}  // namespace vibro::cli
