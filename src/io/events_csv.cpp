// Another simulator's events as CSV (see include/vibro/events_csv.hpp).
#include "vibro/events_csv.hpp"

#include <cmath>
#include <map>

#include <fmt/format.h>

#include "io/csv_text.hpp"
#include "vibro/scene_file.hpp"

namespace vibro {

std::vector<TheirEvent> ReadEventsCsv(const std::string& path) {
  CsvText in(path, "events");
  static const std::map<std::string, EventKind> kKinds = {
      {"impact", EventKind::kImpact},   {"1", EventKind::kImpact},
      {"accumulation", EventKind::kAccumulation}, {"2", EventKind::kAccumulation},
      {"stick", EventKind::kStick},     {"3", EventKind::kStick},
      {"release", EventKind::kRelease}, {"4", EventKind::kRelease},
      {"grazing", EventKind::kGrazing}, {"5", EventKind::kGrazing}};
  std::vector<std::string> problems, names;
  std::vector<TheirEvent> out;
  int ct = -1, ck = -1, cv = -1, cc = -1;
  std::string line;
  bool header = false;
  while (problems.size() < kCsvMaxProblems && in.Next(line)) {
    const int number = in.number();
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    const std::vector<std::string> cells = SplitCsvCells(line);
    if (!header) {
      header = true;
      names = cells;
      for (size_t i = 0; i < cells.size(); ++i) {
        const int k = static_cast<int>(i);
        int* column = cells[i] == "t"          ? &ct
                      : cells[i] == "kind"     ? &ck
                      : cells[i] == "velocity" ? &cv
                      : cells[i] == "contact"  ? &cc
                                               : nullptr;
        if (!column)
          problems.push_back(fmt::format("{}:{}:{}: unknown column '{}' (expected t, kind and optionally velocity, "
                                         "contact)",
                                         path, number, i + 1, cells[i]));
        else if (*column >= 0)
          problems.push_back(fmt::format("{}:{}:{}: column '{}' given twice (first as column {})", path, number,
                                         i + 1, cells[i], *column + 1));
        else
          *column = k;
      }
      if (ct < 0) problems.push_back(fmt::format("{}:{}: missing column 't'", path, number));
      if (ck < 0) problems.push_back(fmt::format("{}:{}: missing column 'kind'", path, number));
      if (!problems.empty()) throw InputError(problems);
      continue;
    }
    if (cells.size() != names.size()) {
      problems.push_back(fmt::format("{}:{}: {} cells, the header has {}", path, number, cells.size(), names.size()));
      continue;
    }
    const auto num = [&](int c, bool required) -> std::optional<double> {
      const std::string& s = cells[static_cast<size_t>(c)];
      if (s.empty()) {
        if (required) problems.push_back(fmt::format("{}:{}:{} ({}): empty cell", path, number, c + 1, names[static_cast<size_t>(c)]));
        return std::nullopt;
      }
      try {
        size_t used = 0;
        const double v = std::stod(s, &used);
        if (used == s.size() && std::isfinite(v)) return v;
      } catch (const std::exception&) {
      }
      problems.push_back(fmt::format("{}:{}:{} ({}): '{}' is not a finite number", path, number, c + 1,
                                     names[static_cast<size_t>(c)], s));
      return std::nullopt;
    };
    TheirEvent e;
    e.line = number;
    e.t = num(ct, true).value_or(0.0);
    const auto it = kKinds.find(cells[static_cast<size_t>(ck)]);
    if (it == kKinds.end())
      problems.push_back(fmt::format("{}:{}:{} (kind): '{}' is not impact, accumulation, stick, release or grazing",
                                     path, number, ck + 1, cells[static_cast<size_t>(ck)]));
    else
      e.kind = it->second;
    if (cv >= 0) e.velocity = num(cv, false);
    if (cc >= 0) {  // several contacts: a whole number ≥ 0 (the scene's count is checked by ScoreEventTable)
      if (const auto c = num(cc, false)) {
        if (*c >= 0 && *c <= 1e6 && *c == std::floor(*c)) e.contact = static_cast<int>(*c);
        else problems.push_back(fmt::format("{}:{}:{} (contact): {} is not a contact index (a whole number ≥ 0)", path,
                                            number, cc + 1, *c));
      }
    }
    out.push_back(e);
  }
  if (problems.size() >= kCsvMaxProblems)
    problems.push_back(fmt::format("{}: stopped reading after {} problems", path, kCsvMaxProblems));
  else if (!header) problems.push_back(fmt::format("{}: no header row (t,kind[,velocity])", path));
  else if (out.empty() && problems.empty()) problems.push_back(fmt::format("{}: no events after the header", path));
  if (!problems.empty()) throw InputError(problems);
  // Time order and the scene's span are checked by ScoreEventTable (score.hpp): the rows stay
  // in the file's order.
  return out;
}

}  // namespace vibro
