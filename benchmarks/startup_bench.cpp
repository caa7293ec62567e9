// Start-up of a whole `vibro` process against a bare one (/bin/true), as a user running vibro
// once per case pays it: the CPU time (user + system, from wait4's rusage) of
//   - `vibro --version`,
//   - `vibro simulate data/scenes/fig08_preload.toml --set run.periods=20` (under 1 ms of work),
// each iteration running /bin/true and then vibro, so that both see the same machine. The
// reported time is vibro's CPU per process (manual time); `over_bare_ms` is the mean of vibro's
// CPU minus /bin/true's, pair by pair. Target (issue "start-up"): within 5 ms of /bin/true for
// every command that needs no MPI. What is loaded and why: docs/performance.md, "Start-up".
// VIBRO_STARTUP_CLI=/path/to/vibro measures another build. VIBRO_STARTUP_BEFORE=DIR (a folder made
// by scripts/snapshot_build.sh: a vibro with its libvibro) pairs a build against it in one run:
// each iteration runs /bin/true, then both builds, in alternating order, and the counters give
// both excesses over /bin/true and `after_over_before_ms`, the mean difference pair by pair.
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

// Runs argv with stdout and stderr on /dev/null, in `env` (default: this process's environment);
// returns its CPU seconds (user + system).
double ChildCpuSeconds(const std::vector<std::string>& args, char** env = environ) {
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 2, "/dev/null", O_WRONLY, 0);
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), env);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) throw std::runtime_error("cannot start " + args[0]);
  int status = 0;
  rusage usage{};
  if (wait4(pid, &status, 0, &usage) != pid || !WIFEXITED(status) || WEXITSTATUS(status) != 0)
    throw std::runtime_error(args[0] + " failed");
  const auto seconds = [](const timeval& t) { return static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_usec); };
  return seconds(usage.ru_utime) + seconds(usage.ru_stime);
}

// The snapshot folder of VIBRO_STARTUP_BEFORE, or empty.
std::string BeforeDir() {
  const char* dir = std::getenv("VIBRO_STARTUP_BEFORE");
  return dir != nullptr ? dir : "";
}

// This environment with LD_LIBRARY_PATH=dir first (a snapshot's vibro runs its own libvibro).
struct EnvironmentWith {
  std::vector<std::string> strings;
  std::vector<char*> pointers;
  explicit EnvironmentWith(const std::string& dir) {
    strings.push_back("LD_LIBRARY_PATH=" + dir);
    for (char** e = environ; *e != nullptr; ++e)
      if (std::string(*e).rfind("LD_LIBRARY_PATH=", 0) != 0) strings.emplace_back(*e);
    for (auto& s : strings) pointers.push_back(s.data());
    pointers.push_back(nullptr);
  }
};

// `args` are the arguments after the program.
void Startup(benchmark::State& state, const std::string& cli, const std::vector<std::string>& args) {
  const std::vector<std::string> bare{"/bin/true"};
  std::vector<std::string> command{cli};
  command.insert(command.end(), args.begin(), args.end());
  const std::string before_dir = BeforeDir();
  std::vector<std::string> before{before_dir + "/vibro"};
  before.insert(before.end(), args.begin(), args.end());
  EnvironmentWith before_env(before_dir);
  double over = 0, bare_total = 0, before_over = 0, after_minus_before = 0;
  bool after_first = true;
  for (auto _ : state) {
    const double b = ChildCpuSeconds(bare);
    double v = 0, w = 0;
    if (before_dir.empty()) {
      v = ChildCpuSeconds(command);
    } else if (after_first) {
      v = ChildCpuSeconds(command);
      w = ChildCpuSeconds(before, before_env.pointers.data());
    } else {
      w = ChildCpuSeconds(before, before_env.pointers.data());
      v = ChildCpuSeconds(command);
    }
    after_first = !after_first;
    state.SetIterationTime(v);
    over += v - b;
    bare_total += b;
    before_over += w - b;
    after_minus_before += v - w;
  }
  const auto n = static_cast<double>(state.iterations());
  state.counters["over_bare_ms"] = 1e3 * over / n;
  state.counters["bare_ms"] = 1e3 * bare_total / n;
  if (!before_dir.empty()) {
    state.counters["before_over_bare_ms"] = 1e3 * before_over / n;
    state.counters["after_over_before_ms"] = 1e3 * after_minus_before / n;
  }
}

std::string Cli() {
  const char* other = std::getenv("VIBRO_STARTUP_CLI");
  return other != nullptr && *other != '\0' ? other : VIBRO_CLI;
}

void BM_BareProcess(benchmark::State& state) {
  for (auto _ : state) state.SetIterationTime(ChildCpuSeconds({"/bin/true"}));
}
BENCHMARK(BM_BareProcess)->UseManualTime()->Unit(benchmark::kMillisecond)->MinTime(2.0);

void BM_VibroVersion(benchmark::State& state) { Startup(state, Cli(), {"--version"}); }
BENCHMARK(BM_VibroVersion)->UseManualTime()->Unit(benchmark::kMillisecond)->MinTime(2.0);

void BM_VibroSimulate20Periods(benchmark::State& state) {
  Startup(state, Cli(), {"simulate", std::string(VIBRO_SCENES_DIR) + "/fig08_preload.toml", "--set", "run.periods=20"});
}
BENCHMARK(BM_VibroSimulate20Periods)->UseManualTime()->Unit(benchmark::kMillisecond)->MinTime(2.0);

}  // namespace

BENCHMARK_MAIN();
