// FileLock (io/file_lock.hpp): an open-file-description lock on an output file, and the process
// that holds it, for the refusal's message.
#include "io/file_lock.hpp"

#include <dirent.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <fstream>
#include <string>

#include <fmt/format.h>

#include "vibro/scene_file.hpp"

namespace vibro::store {
namespace {

// The process with a descriptor of the file (device, inode) that carries an OFD write lock, from
// /proc/PID/fdinfo (OFD locks report no pid through F_OFD_GETLK). 0 when none can be seen (another
// user's process, or no /proc).
long LockHolder(dev_t dev, ino_t ino) {
  DIR* proc = opendir("/proc");
  if (proc == nullptr) return 0;
  long found = 0;
  while (dirent* p = readdir(proc)) {
    char* end = nullptr;
    const long pid = std::strtol(p->d_name, &end, 10);
    if (pid <= 0 || *end != '\0') continue;
    const std::string fd_dir = fmt::format("/proc/{}/fd", pid);
    DIR* fds = opendir(fd_dir.c_str());
    if (fds == nullptr) continue;
    while (dirent* f = readdir(fds)) {
      if (f->d_name[0] == '.') continue;
      struct stat st {};
      if (stat((fd_dir + "/" + f->d_name).c_str(), &st) != 0 || st.st_dev != dev || st.st_ino != ino) continue;
      std::ifstream info(fmt::format("/proc/{}/fdinfo/{}", pid, f->d_name));
      for (std::string line; std::getline(info, line);)
        if (line.rfind("lock:", 0) == 0 && line.find("OFDLCK") != std::string::npos &&
            line.find("WRITE") != std::string::npos)
          found = pid;
      if (found != 0) break;
    }
    closedir(fds);
    if (found != 0) break;
  }
  closedir(proc);
  return found;
}

}  // namespace

FileLock& FileLock::operator=(FileLock&& o) noexcept {
  if (this != &o) {
    if (fd_ >= 0) close(fd_);
    fd_ = o.fd_;
    o.fd_ = -1;
  }
  return *this;
}

FileLock::~FileLock() {
  if (fd_ >= 0) close(fd_);  // the lock goes with the last descriptor of its open file description
}

FileLock FileLock::Acquire(const std::string& path, bool create, bool* created) {
  if (created != nullptr) *created = false;
  int fd = open(path.c_str(), O_RDWR | O_CLOEXEC | O_NOCTTY | O_NONBLOCK);
  if (fd < 0 && errno == ENOENT && create) {
    fd = open(path.c_str(), O_RDWR | O_CLOEXEC | O_CREAT | O_EXCL, 0666);
    if (fd >= 0 && created != nullptr) *created = true;
    if (fd < 0 && errno == EEXIST) fd = open(path.c_str(), O_RDWR | O_CLOEXEC | O_NOCTTY | O_NONBLOCK);
  }
  if (fd < 0) return {};
  struct stat st {};
  if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    close(fd);
    return {};
  }
  struct flock lock {};
  lock.l_type = F_WRLCK;
  lock.l_whence = SEEK_SET;  // l_start = l_len = 0: the whole file, however long it grows
  if (fcntl(fd, F_OFD_SETLK, &lock) == 0) return FileLock(fd);
  const int err = errno;
  close(fd);
  if (created != nullptr && *created) {  // cannot happen (a file this call made is locked by no one)
    unlink(path.c_str());
    *created = false;
  }
  if (err != EAGAIN && err != EACCES) return {};  // a file system without locks: nothing to hold
  const long pid = LockHolder(st.st_dev, st.st_ino);
  throw InputError({fmt::format("{} is in use by {}: a file has one writer at a time (wait for that "
                                "run to end, or choose another --out); the file was not changed",
                                path, pid > 0 ? (pid == getpid() ? fmt::format("this process ({})", pid)
                                                                 : fmt::format("process {}", pid))
                                              : std::string("another process"))});
}

}  // namespace vibro::store
