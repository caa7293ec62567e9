// A contained first read (and first write) of a file given to vibro (docs/reliability.md).
// The HDF5 library trusts a file's metadata: a flipped byte in a global heap makes it copy out of
// bounds and crash. Before vibro reads a file it is read once in full by a child process (every
// attribute, every dataset up to kProbeBytes): if that child dies, the file is reported as
// corrupt (bad input) and vibro itself never touches it.
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>

#include <fmt/format.h>

#include "io/hdf5_store_impl.hpp"
#include "vibro/child_process.hpp"
#include "vibro/scene_file.hpp"

namespace vibro::store {
namespace {
constexpr double kProbeBytes = 64e6;
constexpr int kOutOfMemory = 5;  // the test read's exit status when an allocation failed

// A test read may ask for more memory than a vibro file can need (a flipped length of a
// variable-length attribute made HDF5 allocate 23 GB, the machine's memory): the child gets its
// address space now plus 2 GiB; past that its allocations fail, and it fails or dies, which
// reports the file as corrupt.
void LimitMemory() {
  long pages = 0;
  if (FILE* f = std::fopen("/proc/self/statm", "r")) {
    if (std::fscanf(f, "%ld", &pages) != 1) pages = 0;
    std::fclose(f);
  }
  if (pages <= 0) return;
  const rlim_t limit = static_cast<rlim_t>(pages) * static_cast<rlim_t>(sysconf(_SC_PAGESIZE)) + (rlim_t{2} << 30);
  const rlimit r{limit, limit};
  setrlimit(RLIMIT_AS, &r);
}
}  // namespace

InputError CannotOpen(const std::string& path) {
  const std::string name = path.empty() ? "''" : path;
  struct stat st {};
  if (path.empty() || stat(path.c_str(), &st) != 0)
    return InputError({fmt::format("{}: no such file", name)});
  if (S_ISDIR(st.st_mode)) return InputError({fmt::format("{}: is a directory, not a vibro file", name)});
  if (access(path.c_str(), R_OK) != 0) return InputError({fmt::format("{}: not readable", name)});
  return InputError({fmt::format("{}: not an HDF5 file (or one damaged beyond opening)", name)});
}

void ProbeInChild(const std::string& path, const std::vector<std::string>& only) {
  std::fflush(nullptr);
  const pid_t pid = fork();
  if (pid < 0) return;  // no child: vibro's own checked reads follow
  if (pid == 0) {
    signal(SIGALRM, SIG_DFL);  // the parent's stop-grace handler is not for this child
    alarm(120);  // a corrupt file that makes the library loop is reported too
    LimitMemory();
    // Not readable as HDF5 at all, or an object that fails cleanly: vibro's own reads report it.
    // A read that failed for want of memory (the limit above) would make vibro's own read ask for
    // the same: status kOutOfMemory.
    errno = 0;
    const bool read = h5::ReadEverything(path, kProbeBytes, only);
    _exit(!read && errno == ENOMEM ? kOutOfMemory : 0);
  }
  // A stop request ends the wait (the child is killed): nothing was read or written.
  const int st = WaitForChild(pid, "the test read of " + path);
  if (WIFEXITED(st) && WEXITSTATUS(st) == kOutOfMemory)
    throw InputError({fmt::format("{}: a corrupt HDF5 file: reading it makes the HDF5 library ask for "
                                  "more than 2 GiB of memory (a damaged length); the file was not changed",
                                  path)});
  // The child exits 0 whatever it read; a signal or another exit (a sanitizer's report) is a crash.
  if (WIFSIGNALED(st) || (WIFEXITED(st) && WEXITSTATUS(st) != 0))
    throw InputError({fmt::format("{}: a corrupt HDF5 file: reading it makes the HDF5 library fail "
                                  "(status {} of a test read); the file was not changed",
                                  path, WIFSIGNALED(st) ? WTERMSIG(st) : WEXITSTATUS(st))});
}

// A file whose metadata cannot take a resume's changes (a failed truncation would leave it half
// changed) is refused unchanged. A refusal for a reason of the input itself (InputError) is left
// to the real call, which throws it before changing anything.
void ProbeWrite(const std::string& path, const std::function<void(const std::string&)>& changes) {
  struct stat st_file {};
  if (stat(path.c_str(), &st_file) != 0 || st_file.st_size > (off_t{1} << 30)) return;  // no copy of GBs
  std::fflush(nullptr);
  const pid_t pid = fork();
  if (pid < 0) return;
  if (pid == 0) {
    signal(SIGALRM, SIG_DFL);  // the parent's stop-grace handler is not for this child
    // A file-size limit (ulimit -f) met by the copy is a write that fails (EFBIG: no room for the
    // trial, which says nothing about the file), not a death by SIGXFSZ read as the file's damage.
    signal(SIGXFSZ, SIG_IGN);
    alarm(120);
    LimitMemory();
    h5::Silence();
    char copy[] = "/tmp/vibro-resume-probe-XXXXXX";
    const int fd = mkstemp(copy);
    if (fd < 0) _exit(0);  // no room for a copy: go on without the trial
    bool ok = false;
    if (FILE* in = std::fopen(path.c_str(), "rb")) {
      char buf[1 << 16];
      size_t n;
      ok = true;
      while (ok && (n = std::fread(buf, 1, sizeof buf, in)) > 0) ok = write(fd, buf, n) == static_cast<ssize_t>(n);
      std::fclose(in);
    }
    close(fd);
    int code = 0;
    if (ok) {
      try {
        changes(copy);
      } catch (const WriteError& e) {
        // No room for the trial (a full /tmp) says nothing about the file; HDF5 failing to write
        // without a system error (a damaged chunk index met by a truncation) is the file's damage.
        code = e.from_system() ? 0 : 3;
      } catch (const InputError& e) {
        // "cannot resume: <HDF5 failure>" is the file's damage; other refusals are the input's.
        code = std::string(e.what()).find("HDF5") != std::string::npos ? 3 : 0;
      } catch (const std::exception&) {
        code = 3;
      }
    }
    unlink(copy);
    _exit(code);
  }
  const int st = WaitForChild(pid, "the test write to a copy of " + path);
  if (WIFSIGNALED(st) || (WIFEXITED(st) && WEXITSTATUS(st) != 0))
    throw InputError({fmt::format("{}: cannot resume: a corrupt HDF5 file (a test write to a copy of it "
                                  "failed); the file was not changed",
                                  path)});
}

}  // namespace vibro::store
