// An allocation counter preloaded into vibro (measurement only, not part of vibro; docs/output.md,
// "Crash safety"): logs every refused allocation and whether libhdf5 was on the stack, and the peak
// of live heap bytes inside each stretch of HDF5 calls, which vibro's memory reserve delimits
// (munmap, then mmap again, of exactly MemoryReserve::kBytes = 16 MiB PROT_NONE).
// Build: gcc -O2 -shared -fPIC -o allocwatch.so scripts/allocwatch.c -ldl
// Run:   ALLOCWATCH_LOG=aw.log LD_PRELOAD=./allocwatch.so build/vibro simulate ... --out F.h5
#define _GNU_SOURCE
#include <dlfcn.h>
#include <execinfo.h>
#include <fcntl.h>
#include <malloc.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/syscall.h>
#include <unistd.h>

extern void* __libc_malloc(size_t);
extern void* __libc_calloc(size_t, size_t);
extern void* __libc_realloc(void*, size_t);
extern void __libc_free(void*);
extern void* __libc_memalign(size_t, size_t);

static _Atomic long live = 0, base = 0, peak = 0, maxstretch = 0, fails = 0, hdf5fails = 0, stretches = 0;
static _Atomic int in_stretch = 0;
static int logfd = -1;
static __thread int busy = 0;
#define RES (16UL << 20)

static void note(long d) {
  long v = atomic_fetch_add(&live, d) + d;
  if (atomic_load(&in_stretch)) {
    long p = atomic_load(&peak);
    while (v > p && !atomic_compare_exchange_weak(&peak, &p, v)) {}
  }
}
static void failed(size_t n) {
  atomic_fetch_add(&fails, 1);
  if (busy) return;
  busy = 1;
  void* f[64];
  int k = backtrace(f, 64), h = 0;
  for (int i = 0; i < k; ++i) {
    Dl_info d;
    if (dladdr(f[i], &d) && d.dli_fname && strstr(d.dli_fname, "libhdf5")) { h = 1; break; }
  }
  if (h) atomic_fetch_add(&hdf5fails, 1);
  if (logfd >= 0) {
    char b[160];
    int m = snprintf(b, sizeof b, "FAIL %zu bytes hdf5_on_stack=%d stretch=%d\n", n, h, atomic_load(&in_stretch));
    write(logfd, b, m);
  }
  busy = 0;
}
void* malloc(size_t n) { void* p = __libc_malloc(n); if (p) note(malloc_usable_size(p)); else failed(n); return p; }
void* calloc(size_t a, size_t b) { void* p = __libc_calloc(a, b); if (p) note(malloc_usable_size(p)); else failed(a * b); return p; }
void* realloc(void* q, size_t n) {
  long old = q ? (long)malloc_usable_size(q) : 0;
  void* p = __libc_realloc(q, n);
  if (p) note((long)malloc_usable_size(p) - old); else if (n) failed(n); else note(-old);
  return p;
}
void free(void* p) { if (p) note(-(long)malloc_usable_size(p)); __libc_free(p); }
int posix_memalign(void** r, size_t a, size_t n) { void* p = __libc_memalign(a, n); if (!p) { failed(n); return 12; } note(malloc_usable_size(p)); *r = p; return 0; }
void* aligned_alloc(size_t a, size_t n) { void* p = __libc_memalign(a, n); if (p) note(malloc_usable_size(p)); else failed(n); return p; }

int munmap(void* a, size_t len) {
  int r = syscall(SYS_munmap, a, len);
  if (len == RES) { atomic_store(&base, atomic_load(&live)); atomic_store(&peak, atomic_load(&live)); atomic_store(&in_stretch, 1); atomic_fetch_add(&stretches, 1); }
  return r;
}
void* mmap(void* a, size_t len, int prot, int fl, int fd, off_t off) {
  if (len == RES && prot == PROT_NONE && atomic_load(&in_stretch)) {
    atomic_store(&in_stretch, 0);
    long d = atomic_load(&peak) - atomic_load(&base);
    if (logfd >= 0) { char b[120]; int k = snprintf(b, sizeof b, "STRETCH %ld peak=%ld net=%ld\n", (long)stretches, d, atomic_load(&live) - atomic_load(&base)); write(logfd, b, k); }
    long m = atomic_load(&maxstretch);
    while (d > m && !atomic_compare_exchange_weak(&maxstretch, &m, d)) {}
  }
  long r = syscall(SYS_mmap, a, len, prot, fl, fd, off);
  if (r == -1) return MAP_FAILED;  // syscall() has set errno
  return (void*)r;
}
__attribute__((constructor)) static void init(void) {
  void* f[4]; backtrace(f, 4);
  const char* p = getenv("ALLOCWATCH_LOG");
  if (p) logfd = open(p, O_WRONLY | O_CREAT | O_APPEND, 0644);
}
__attribute__((destructor)) static void fini(void) {
  if (atomic_load(&in_stretch)) { long d = atomic_load(&peak) - atomic_load(&base); if (logfd >= 0) { char b[120]; int k = snprintf(b, sizeof b, "LAST STRETCH peak=%ld\n", d); write(logfd, b, k); } if (d > maxstretch) maxstretch = d; }
  if (logfd >= 0) {
    char b[200];
    int m = snprintf(b, sizeof b, "END fails=%ld hdf5_fails=%ld stretches=%ld max_stretch_peak=%ld\n", (long)fails, (long)hdf5fails, (long)stretches, (long)maxstretch);
    write(logfd, b, m);
  }
}
