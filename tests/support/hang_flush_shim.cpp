// LD_PRELOAD shim for the test hardening.grace (tests/regression/grace_test.py): a library call
// that never returns. With VIBRO_TEST_HANG_FLUSH=N the N-th call of H5Fflush blocks for ever
// (after creating the file VIBRO_TEST_HANG_MARKER, so that the test knows the call has begun);
// every other call goes to HDF5's. This is what the fuzzing campaign saw HDF5's filter pipeline do
// on a damaged chunk (docs/reliability.md), and what vibro's stop grace period is for.
#include <dlfcn.h>
#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <cstdint>
#include <cstdlib>

// herr_t H5Fflush(hid_t, H5F_scope_t) with HDF5 1.10's types (hid_t is int64_t), declared here so
// that the shim needs no HDF5 headers.
extern "C" int H5Fflush(std::int64_t object_id, int scope) {
  static std::atomic<int> calls{0};
  const char* n = std::getenv("VIBRO_TEST_HANG_FLUSH");
  if (n != nullptr && ++calls == std::atoi(n)) {
    if (const char* marker = std::getenv("VIBRO_TEST_HANG_MARKER"))
      close(open(marker, O_CREAT | O_WRONLY, 0644));
    for (;;) pause();  // signal handlers run; the call never returns
  }
  using Fn = int (*)(std::int64_t, int);
  static const Fn real = reinterpret_cast<Fn>(dlsym(RTLD_NEXT, "H5Fflush"));
  return real(object_id, scope);
}
