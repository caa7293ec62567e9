#include "cli/progress.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <fmt/format.h>

namespace vibro::cli {
namespace {

// A duration for people: "8.2 s", "3 min 20 s", "2 h 05 min".
std::string Duration(double seconds) {
  if (!(seconds < 1e9)) return "?";
  if (seconds < 60) return fmt::format("{:.1f} s", seconds);
  const auto s = static_cast<long long>(std::llround(seconds));
  if (s < 3600) return fmt::format("{} min {:02d} s", s / 60, s % 60);
  return fmt::format("{} h {:02d} min", s / 3600, (s % 3600) / 60);
}

}  // namespace

Progress::Progress(std::string label, bool json)
    : label_(std::move(label)),
      style_(json ? Style::kOff : isatty(STDERR_FILENO) != 0 ? Style::kBar : Style::kLines) {}

Progress::~Progress() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (style_ == Style::kBar && drawn_) fmt::print(stderr, "\n");
  if (style_ == Style::kLines && drawn_)
    fmt::print(stderr, "{}: {}\n", label_, State(Clock::now(), true));
  std::fflush(stderr);
}

std::string Progress::State(Clock::time_point now, bool final) const {
  const long long pct = total_ > 0 ? 100 * done_ / total_ : 100;
  std::string text = fmt::format("{:3d}% ({} / {})", pct, done_, total_);
  const double elapsed = std::chrono::duration<double>(now - first_).count();
  const long long gained = done_ - first_done_;
  if (final) {
    text += fmt::format(" after {}", Duration(elapsed));
  } else if (gained > 0 && elapsed >= 0.5) {
    const double rate = static_cast<double>(gained) / elapsed;
    text += fmt::format(", {:.3g}/s, {} left", rate, Duration(static_cast<double>(total_ - done_) / rate));
  }
  return note_.empty() ? text : text + "  " + note_;
}

void Progress::Update(long long done, long long total, const std::string& note) {
  if (style_ == Style::kOff) return;
  done = std::clamp(done, 0LL, std::max(total, 0LL));
  std::lock_guard<std::mutex> lock(mutex_);
  if (done <= done_) return;
  const auto now = Clock::now();
  if (first_done_ < 0) {
    first_done_ = done;
    first_ = last_ = now;
  }
  done_ = done;
  total_ = total;
  note_ = note;
  if (style_ == Style::kLines) {
    if (now - last_ < std::chrono::duration<double>(kLineSeconds)) return;
    last_ = now;
    drawn_ = true;
    fmt::print(stderr, "{}: {}\n", label_, State(now, false));
    std::fflush(stderr);
    return;
  }
  if (done < total && drawn_ && now - last_ < std::chrono::milliseconds(200)) return;
  last_ = now;
  drawn_ = true;
  const auto bar = static_cast<size_t>((total > 0 ? 100 * done / total : 100) * 30 / 100);
  fmt::print(stderr, "\r{} [{}{}] {}\x1b[K", label_, std::string(bar, '#'), std::string(30 - bar, ' '),
             State(now, false));
  std::fflush(stderr);
}

}  // namespace vibro::cli
