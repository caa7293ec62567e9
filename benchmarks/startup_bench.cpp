// Start-up of a whole `vibro` process against a bare one (/bin/true), as a user running vibro
// once per case pays it: the CPU time (user + system, from wait4's rusage) of
//   - `vibro --version`,
//   - `vibro simulate data/scenes/fig08_preload.toml --set run.periods=20` (under 1 ms of work),
// each iteration running /bin/true and then vibro, so that both see the same machine. The
// reported time is vibro's CPU per process (manual time); `over_bare_ms` is the mean of vibro's
// CPU minus /bin/true's, pair by pair. Target (issue "start-up"): within 5 ms of /bin/true for
// every command that needs no MPI. What is loaded and why: docs/performance.md, "Start-up".
// VIBRO_STARTUP_CLI=/path/to/vibro measures another build (an older one, for a before/after).
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>

#include <fcntl.h>
#include <unistd.h>

#include <cstdlib>
#include <stdexcept>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

extern char** environ;

namespace {

// Runs argv with stdout and stderr on /dev/null; returns its CPU seconds (user + system).
double ChildCpuSeconds(const std::vector<std::string>& args) {
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 2, "/dev/null", O_WRONLY, 0);
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) throw std::runtime_error("cannot start " + args[0]);
  int status = 0;
  rusage usage{};
  if (wait4(pid, &status, 0, &usage) != pid || !WIFEXITED(status) || WEXITSTATUS(status) != 0)
    throw std::runtime_error(args[0] + " failed");
  const auto seconds = [](const timeval& t) { return static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_usec); };
  return seconds(usage.ru_utime) + seconds(usage.ru_stime);
}

void Startup(benchmark::State& state, const std::vector<std::string>& command) {
  const std::vector<std::string> bare{"/bin/true"};
  double over = 0, bare_total = 0;
  for (auto _ : state) {
    const double b = ChildCpuSeconds(bare);
    const double v = ChildCpuSeconds(command);
    state.SetIterationTime(v);
    over += v - b;
    bare_total += b;
  }
  const auto n = static_cast<double>(state.iterations());
  state.counters["over_bare_ms"] = 1e3 * over / n;
  state.counters["bare_ms"] = 1e3 * bare_total / n;
}

std::string Cli() {
  const char* other = std::getenv("VIBRO_STARTUP_CLI");
  return other != nullptr && *other != '\0' ? other : VIBRO_CLI;
}

void BM_BareProcess(benchmark::State& state) {
  for (auto _ : state) state.SetIterationTime(ChildCpuSeconds({"/bin/true"}));
}
BENCHMARK(BM_BareProcess)->UseManualTime()->Unit(benchmark::kMillisecond)->MinTime(2.0);

void BM_VibroVersion(benchmark::State& state) { Startup(state, {Cli(), "--version"}); }
BENCHMARK(BM_VibroVersion)->UseManualTime()->Unit(benchmark::kMillisecond)->MinTime(2.0);

void BM_VibroSimulate20Periods(benchmark::State& state) {
  Startup(state, {Cli(), "simulate", std::string(VIBRO_SCENES_DIR) + "/fig08_preload.toml",
                  "--set", "run.periods=20"});
}
BENCHMARK(BM_VibroSimulate20Periods)->UseManualTime()->Unit(benchmark::kMillisecond)->MinTime(2.0);

}  // namespace

BENCHMARK_MAIN();
