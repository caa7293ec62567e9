// WaitForChild and RunChild (vibro/child_process.hpp): a child's wait that polls the stop flag.
#include "vibro/child_process.hpp"

#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <ctime>

#include "vibro/stop_request.hpp"

namespace vibro {

int WaitForChild(int pid, const std::string& what) {
  const std::atomic<bool>* stop = ProcessStopFlag();
  int st = 0;
  for (;;) {
    const pid_t r = waitpid(pid, &st, WNOHANG);
    if (r == pid) {
      // A child that failed while a stop request came (Ctrl-C reaches the whole process group)
      // was stopped by it; one that succeeded finished first.
      const bool failed = WIFSIGNALED(st) || (WIFEXITED(st) && WEXITSTATUS(st) != 0);
      if (failed && stop != nullptr && stop->load()) throw Interrupted(what + ": interrupted by a stop request");
      return st;
    }
    if (r < 0 && errno != EINTR) return st;  // not our child (cannot happen): nothing to wait for
    if (stop != nullptr && stop->load()) {
      kill(pid, SIGKILL);
      while (waitpid(pid, &st, 0) < 0 && errno == EINTR) {
      }
      throw Interrupted(what + ": interrupted by a stop request");
    }
    const timespec nap{0, 2'000'000};  // 2 ms; a signal ends it early
    nanosleep(&nap, nullptr);
  }
}

int RunChild(const std::vector<std::string>& argv, const std::string& what) {
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  const pid_t pid = fork();
  if (pid < 0) return 127 << 8;
  if (pid == 0) {
    // Default dispositions in the child: vibro's stop and grace handlers are not for it.
    signal(SIGINT, SIG_DFL);
    signal(SIGTERM, SIG_DFL);
    signal(SIGALRM, SIG_DFL);
    execvp(args[0], args.data());
    _exit(127);
  }
  return WaitForChild(pid, what);
}

}  // namespace vibro
