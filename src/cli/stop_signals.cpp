#include "cli/stop_signals.hpp"

#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <cstdlib>
#include <cstring>

#include "vibro/stop_request.hpp"

namespace vibro::cli {
namespace {

std::atomic<bool> g_stop{false};
std::atomic<int> g_signals{0};
std::atomic<int> g_writing{0};
std::atomic<bool> g_discard{false};
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
  _exit(130);
}

extern "C" void OnStopSignal(int) {
  g_stop.store(true);
  const int count = g_signals.fetch_add(1) + 1;
  if (count == 1) alarm(kGraceSeconds);
  if (g_discard.load()) {
    if (g_discard_path[0] != '\0') unlink(g_discard_path);
    Say("\nvibro: interrupted; nothing to keep\n");
    _exit(130);
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

}  // namespace vibro::cli
