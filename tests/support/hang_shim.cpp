// LD_PRELOAD shim for the test hardening.grace (tests/regression/grace_test.py): a library call
// that never returns, as the fuzzing campaign saw HDF5's filter pipeline do on a damaged chunk
// (docs/reliability.md).
//   VIBRO_TEST_HANG_FLUSH=N  the N-th call of H5Fflush blocks for ever;
//   VIBRO_TEST_HANG_READ=N   the N-th call of H5Dread blocks for ever (in whichever process
//                            makes it: the contained test read of a file runs in a child).
// A call that blocks first writes its process id to the file VIBRO_TEST_HANG_MARKER, so that the
// test knows the call has begun and which process is stuck. Every other call goes to HDF5's.
#include <dlfcn.h>
#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <cstdint>
#include <cstdlib>
#include <string>

namespace {

bool IsTheOne(const char* env, std::atomic<int>& calls) {
  const char* n = std::getenv(env);
  return n != nullptr && ++calls == std::atoi(n);
}

[[noreturn]] void BlockForEver() {
  if (const char* marker = std::getenv("VIBRO_TEST_HANG_MARKER")) {
    const int fd = open(marker, O_CREAT | O_WRONLY | O_TRUNC, 0644);
    const std::string pid = std::to_string(getpid()) + "\n";
    if (fd >= 0) {
      const ssize_t n = write(fd, pid.data(), pid.size());
      (void)n;
      close(fd);
    }
  }
  for (;;) pause();  // signal handlers run; the call never returns
}

}  // namespace

// HDF5 1.10's signatures with its types (hid_t is int64_t, herr_t int), declared here so that the
// shim needs no HDF5 headers.
extern "C" int H5Fflush(std::int64_t object_id, int scope) {
  static std::atomic<int> calls{0};
  if (IsTheOne("VIBRO_TEST_HANG_FLUSH", calls)) BlockForEver();
  using Fn = int (*)(std::int64_t, int);
  static const Fn real = reinterpret_cast<Fn>(dlsym(RTLD_NEXT, "H5Fflush"));
  return real(object_id, scope);
}

extern "C" int H5Dread(std::int64_t dset, std::int64_t mem_type, std::int64_t mem_space,
                       std::int64_t file_space, std::int64_t plist, void* buf) {
  static std::atomic<int> calls{0};
  if (IsTheOne("VIBRO_TEST_HANG_READ", calls)) BlockForEver();
  using Fn = int (*)(std::int64_t, std::int64_t, std::int64_t, std::int64_t, std::int64_t, void*);
  static const Fn real = reinterpret_cast<Fn>(dlsym(RTLD_NEXT, "H5Dread"));
  return real(dset, mem_type, mem_space, file_space, plist, buf);
}
