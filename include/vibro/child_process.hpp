// Waiting for a child process while honouring the process's stop request (docs/reliability.md,
// "Stop requests"): the contained test read of a file (io/hdf5_probe.cpp) and the plotting
// process of `vibro plot` run in children, and a stop request must end the wait within a second.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

namespace vibro {

// A wait for a child process cut short by the process's stop request (ProcessStopFlag()); the
// child was killed. Nothing was computed or written.
class Interrupted : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Waits for child `pid` (from fork) and returns its waitpid status. The process's stop flag is
// polled every few milliseconds: once it is set the child is killed (SIGKILL) and reaped, and
// Interrupted is thrown with `what` in its message. A child that ends with a failure while the
// flag is set (a Ctrl-C reaches the whole process group) is interrupted too.
int WaitForChild(int pid, const std::string& what);

// Starts argv[0] (looked up on PATH when it has no slash) with the arguments argv[1…] and waits for
// it as WaitForChild does. Returns the waitpid status; 127 << 8 (exit 127) when it cannot start.
int RunChild(const std::vector<std::string>& argv, const std::string& what);

}  // namespace vibro
