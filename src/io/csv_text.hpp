// The text of a CSV file from another tool, line by line, as events_csv.cpp and branch_csv.cpp
// read it (docs/validation.md, "Input limits"): at most kCsvMaxBytes in all and kCsvMaxLine per
// line, no NUL byte (a binary file or a device such as /dev/zero is refused at once), a UTF-8 BOM
// before the first line dropped (Excel's "CSV UTF-8"), and the process's stop request polled at
// every block read, so that a large file is left within a second of Ctrl-C (Interrupted).
#pragma once

#include <cstdio>
#include <memory>
#include <string>
#include <vector>

namespace vibro {

inline constexpr long long kCsvMaxBytes = 1LL << 30;  // 1 GiB
inline constexpr size_t kCsvMaxLine = 1U << 20;        // 1 MiB

class CsvText {
 public:
  // Throws InputError("PATH: cannot open the WHAT file") when it cannot be opened.
  CsvText(const std::string& path, const std::string& what);
  // The next line without its end of line ('\n', "\r\n"); false at the end of the file. Throws
  // InputError (PATH:LINE: the limit broken) and Interrupted (a stop request).
  bool Next(std::string& line);
  int number() const { return number_; }  // the line last returned, from 1

 private:
  bool Fill();
  std::string path_;
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> file_;
  std::vector<char> buffer_;
  size_t begin_ = 0, end_ = 0;
  long long total_ = 0;
  int number_ = 0;
  bool eof_ = false;
};

// The cells of a CSV line: split at commas, blanks, '\r' and double quotes trimmed from each end,
// a trailing comma giving an empty last cell.
std::vector<std::string> SplitCsvCells(const std::string& line);

// Up to this many problems are listed; the reading stops at the next one.
inline constexpr size_t kCsvMaxProblems = 20;

}  // namespace vibro
