// LD_PRELOAD shim for the test files.integrity (tests/regression/files_test.py): a disk that
// fills up during a run, wherever the test runs (no tmpfs mount needed).
//   VIBRO_TEST_DISK_BYTES=N  files whose name ends in ".h5" may take N bytes of writes in all;
//                            past that a write stores what still fits and then fails with
//                            ENOSPC, as on a full file system; statvfs() of such a file reports
//                            the bytes left as its free space.
// Every other call goes to the C library's.
#include <dlfcn.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <string>

namespace {

std::atomic<long long> g_used{0};

long long Budget() {
  static const long long budget = [] {
    const char* n = std::getenv("VIBRO_TEST_DISK_BYTES");
    return n != nullptr ? std::atoll(n) : -1LL;
  }();
  return budget;
}

bool EndsInH5(const std::string& s) { return s.size() >= 3 && s.compare(s.size() - 3, 3, ".h5") == 0; }

bool IsH5(int fd) {
  char link[64], target[4096];
  std::snprintf(link, sizeof link, "/proc/self/fd/%d", fd);
  const ssize_t n = readlink(link, target, sizeof target - 1);
  if (n <= 0) return false;
  target[n] = '\0';
  return EndsInH5(target);
}

// How many of `count` bytes may be written to fd; -1 with errno = ENOSPC when none.
ssize_t Allowed(int fd, size_t count) {
  if (Budget() < 0 || count == 0 || !IsH5(fd)) return static_cast<ssize_t>(count);
  const long long left = Budget() - g_used.load();
  if (left <= 0) {
    errno = ENOSPC;
    return -1;
  }
  const auto n = static_cast<ssize_t>(std::min<long long>(left, static_cast<long long>(count)));
  g_used += n;
  return n;
}

template <class Fn>
Fn Real(const char* name) {
  return reinterpret_cast<Fn>(dlsym(RTLD_NEXT, name));
}

}  // namespace

extern "C" ssize_t write(int fd, const void* buf, size_t count) {
  static const auto real = Real<ssize_t (*)(int, const void*, size_t)>("write");
  const ssize_t n = Allowed(fd, count);
  return n < 0 ? -1 : real(fd, buf, static_cast<size_t>(n));
}

extern "C" ssize_t pwrite(int fd, const void* buf, size_t count, off_t offset) {
  static const auto real = Real<ssize_t (*)(int, const void*, size_t, off_t)>("pwrite");
  const ssize_t n = Allowed(fd, count);
  return n < 0 ? -1 : real(fd, buf, static_cast<size_t>(n), offset);
}

extern "C" ssize_t pwrite64(int fd, const void* buf, size_t count, off64_t offset) {
  static const auto real = Real<ssize_t (*)(int, const void*, size_t, off64_t)>("pwrite64");
  const ssize_t n = Allowed(fd, count);
  return n < 0 ? -1 : real(fd, buf, static_cast<size_t>(n), offset);
}

extern "C" int statvfs(const char* path, struct statvfs* buf) {
  static const auto real = Real<int (*)(const char*, struct statvfs*)>("statvfs");
  const int r = real(path, buf);
  if (r == 0 && Budget() >= 0 && EndsInH5(path) && buf->f_frsize > 0) {
    const long long left = std::max(0LL, Budget() - g_used.load());
    buf->f_bavail = std::min<fsblkcnt_t>(buf->f_bavail, static_cast<fsblkcnt_t>(left) / buf->f_frsize);
    buf->f_bfree = std::min(buf->f_bfree, buf->f_bavail);
  }
  return r;
}
