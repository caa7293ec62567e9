#include "cli/progress.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstdio>

#include <fmt/format.h>

namespace vibro::cli {

Progress::Progress(std::string label, bool json)
    : label_(std::move(label)), active_(!json && isatty(STDERR_FILENO) != 0) {}

Progress::~Progress() {
  if (drawn_) fmt::print(stderr, "\n");
}

void Progress::Update(long long done, long long total, const std::string& note) {
  if (!active_) return;
  done = std::clamp(done, 0LL, std::max(total, 0LL));
  std::lock_guard<std::mutex> lock(mutex_);
  if (done <= shown_) return;
  const auto now = std::chrono::steady_clock::now();
  if (done < total && drawn_ && now - last_ < std::chrono::milliseconds(200)) return;
  shown_ = done;
  last_ = now;
  drawn_ = true;
  const long long pct = total > 0 ? 100 * done / total : 100;
  const auto bar = static_cast<size_t>(pct * 30 / 100);
  fmt::print(stderr, "\r{} [{}{}] {:3d}% ({} / {}){}\x1b[K", label_, std::string(bar, '#'),
             std::string(30 - bar, ' '), pct, done, total, note.empty() ? "" : "  " + note);
  std::fflush(stderr);
}

}  // namespace vibro::cli
