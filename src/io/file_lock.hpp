// One writer per output file (docs/reliability.md, "One writer per file"): an advisory lock on
// the whole file, held for as long as a run writes it.
//
// The lock is an open-file-description lock (fcntl F_OFD_SETLK) on the file itself:
//   - it dies with the process (also after SIGKILL): no stale lock is ever left behind;
//   - it stays held while HDF5 opens and closes its own descriptors of the file (a classic POSIX
//     record lock would be dropped by the first close);
//   - two opens in one process conflict too (two Python threads writing one file);
//   - it does not conflict with HDF5's own flock() locks, so h5py may still watch a run.
#pragma once

#include <string>

namespace vibro::store {

class FileLock {
 public:
  FileLock() = default;
  FileLock(FileLock&& o) noexcept : fd_(o.fd_) { o.fd_ = -1; }
  FileLock& operator=(FileLock&& o) noexcept;
  FileLock(const FileLock&) = delete;
  FileLock& operator=(const FileLock&) = delete;
  ~FileLock();

  // Locks the regular file at `path`. With `create`, a missing file is created empty first
  // (O_EXCL: *created says whether this call made it). Throws InputError("PATH is in use by
  // process N ...") when another open holds the lock. Returns an empty lock, without error, when
  // the file cannot be opened for writing or is not a regular file (a device, a directory, a
  // read-only place): the caller's own open reports that.
  static FileLock Acquire(const std::string& path, bool create, bool* created = nullptr);

  bool held() const { return fd_ >= 0; }

 private:
  explicit FileLock(int fd) : fd_(fd) {}
  int fd_ = -1;
};

}  // namespace vibro::store
