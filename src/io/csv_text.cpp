// The text of a CSV file from another tool (see csv_text.hpp).
#include "io/csv_text.hpp"

#include <algorithm>
#include <cstring>

#include <fmt/format.h>

#include "vibro/child_process.hpp"
#include "vibro/scene_file.hpp"
#include "vibro/stop_request.hpp"

namespace vibro {
namespace {
constexpr size_t kBlock = 1U << 16;
}  // namespace

CsvText::CsvText(const std::string& path, const std::string& what)
    : path_(path), file_(std::fopen(path.c_str(), "rb"), &std::fclose) {
  if (!file_) throw InputError({fmt::format("{}: cannot open the {} file", path, what)});
  buffer_.resize(kBlock);
}

bool CsvText::Fill() {
  if (eof_) return false;
  if (const auto* stop = ProcessStopFlag(); stop && stop->load())
    throw Interrupted(fmt::format("{}: reading interrupted at line {}", path_, number_ + 1));
  // Keep the unfinished line, read the next block after it.
  if (begin_ > 0) {
    std::memmove(buffer_.data(), buffer_.data() + begin_, end_ - begin_);
    end_ -= begin_;
    begin_ = 0;
  }
  if (buffer_.size() - end_ < kBlock) buffer_.resize(end_ + kBlock);
  const size_t got = std::fread(buffer_.data() + end_, 1, kBlock, file_.get());
  if (got == 0) {
    eof_ = true;
    return false;
  }
  if (std::memchr(buffer_.data() + end_, '\0', got))
    throw InputError({fmt::format("{}:{}: a NUL byte: not a text (CSV) file", path_, number_ + 1)});
  total_ += static_cast<long long>(got);
  if (total_ > kCsvMaxBytes)
    throw InputError({fmt::format("{}:{}: the file is larger than {} bytes (1 GiB), the limit of a CSV input",
                                  path_, number_ + 1, kCsvMaxBytes)});
  end_ += got;
  return true;
}

bool CsvText::Next(std::string& line) {
  size_t scanned = begin_;
  for (;;) {
    const char* from = buffer_.data() + scanned;
    const void* nl = std::memchr(from, '\n', end_ - scanned);
    if (nl) {
      const size_t at = static_cast<size_t>(static_cast<const char*>(nl) - buffer_.data());
      line.assign(buffer_.data() + begin_, at - begin_);
      begin_ = at + 1;
      break;
    }
    if (end_ - begin_ > kCsvMaxLine)
      throw InputError({fmt::format("{}:{}: a line longer than {} bytes (1 MiB), the limit of a CSV line", path_,
                                    number_ + 1, kCsvMaxLine)});
    const size_t kept = end_ - begin_;
    if (!Fill()) {
      if (end_ == begin_) return false;
      line.assign(buffer_.data() + begin_, end_ - begin_);  // the last line, without '\n'
      begin_ = end_;
      break;
    }
    scanned = begin_ + kept;
  }
  if (line.size() > kCsvMaxLine)
    throw InputError({fmt::format("{}:{}: a line longer than {} bytes (1 MiB), the limit of a CSV line", path_,
                                  number_ + 1, kCsvMaxLine)});
  if (!line.empty() && line.back() == '\r') line.pop_back();
  if (++number_ == 1 && line.compare(0, 3, "\xEF\xBB\xBF") == 0) line.erase(0, 3);  // UTF-8 BOM
  return true;
}

std::vector<std::string> SplitCsvCells(const std::string& line) {
  std::vector<std::string> cells;
  size_t start = 0;
  for (;;) {
    const size_t comma = line.find(',', start);
    const std::string cell = line.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    const auto a = cell.find_first_not_of(" \t\r\"");
    const auto b = cell.find_last_not_of(" \t\r\"");
    cells.push_back(a == std::string::npos ? "" : cell.substr(a, b - a + 1));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return cells;
}

}  // namespace vibro
