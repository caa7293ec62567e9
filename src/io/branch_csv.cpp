// Branch files from other tools (see include/vibro/branch_csv.hpp).
#include "vibro/branch_csv.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <string_view>

#include <fmt/format.h>

#include "io/csv_text.hpp"
#include "vibro/contact_sequence.hpp"
#include "vibro/scene_file.hpp"

namespace vibro {

bool IsStrobeColumn(const std::string& name) {
  constexpr std::string_view kPrefix = "strobe_";
  return name.size() > kPrefix.size() && name.size() <= kPrefix.size() + 6 && name.starts_with(kPrefix) &&
         std::all_of(name.begin() + kPrefix.size(), name.end(), [](char c) { return c >= '0' && c <= '9'; });
}

std::vector<ClaimedPoint> ReadBranchCsv(const std::string& path, int n) {
  CsvText in(path, "branch");
  std::vector<std::string> problems;
  std::vector<ClaimedPoint> points;
  std::map<std::string, size_t> column;  // name → index
  std::vector<size_t> strobes;           // the strobe_J columns
  std::vector<std::string> names;
  std::string line;
  int number = 0;
  bool header = false;
  const auto where = [&](size_t c) {
    return fmt::format("{}:{}:{}{}", path, number, c + 1, c < names.size() ? " (" + names[c] + ")" : "");
  };
  while (problems.size() < kCsvMaxProblems && in.Next(line)) {
    number = in.number();
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    const auto cells = SplitCsvCells(line);
    if (!header) {
      header = true;
      names = cells;
      std::vector<std::string> known = {"value", "time", "period", "stable", "sticking_fraction", "sequence"};
      for (int i = 1; i <= n; ++i) {
        known.push_back(fmt::format("displacement_{}", i));
        known.push_back(fmt::format("velocity_{}", i));
      }
      for (size_t c = 0; c < cells.size(); ++c) {
        // strobe_J: no claim (plots), but read as every column is: once, empty or a finite number.
        if (IsStrobeColumn(cells[c])) {
          if (column.count(cells[c]))
            problems.push_back(fmt::format("{}: column '{}' given twice", where(c), cells[c]));
          else
            strobes.push_back(column[cells[c]] = c);
          continue;
        }
        if (std::find(known.begin(), known.end(), cells[c]) == known.end())
          problems.push_back(fmt::format("{}: unknown column '{}' (expected value, time, displacement_1..{}, "
                                         "velocity_1..{}, and optionally period, stable, sticking_fraction, "
                                         "sequence, strobe_0..)",
                                         where(c), cells[c], n, n));
        else if (column.count(cells[c]))
          problems.push_back(fmt::format("{}: column '{}' given twice", where(c), cells[c]));
        else
          column[cells[c]] = c;
      }
      for (size_t k = 0; k < 2 + 2 * static_cast<size_t>(n); ++k)
        if (!column.count(known[k < 2 ? k : k + 4]))
          problems.push_back(fmt::format("{}:{}: missing column '{}'", path, number, known[k < 2 ? k : k + 4]));
      if (!problems.empty()) throw InputError(problems);
      continue;
    }
    if (cells.size() != names.size()) {
      problems.push_back(fmt::format("{}:{}: {} cells, the header has {}", path, number, cells.size(), names.size()));
      continue;
    }
    const auto number_at = [&](const std::string& name, bool required) -> std::optional<double> {
      const auto it = column.find(name);
      if (it == column.end()) return std::nullopt;
      const std::string& text = cells[it->second];
      if (text.empty()) {
        if (required) problems.push_back(fmt::format("{}: empty cell (a number is required)", where(it->second)));
        return std::nullopt;
      }
      try {
        size_t used = 0;
        const double v = std::stod(text, &used);
        if (used != text.size() || !std::isfinite(v)) throw std::invalid_argument(text);
        return v;
      } catch (const std::exception&) {
        problems.push_back(fmt::format("{}: '{}' is not a finite number", where(it->second), text));
        return std::nullopt;
      }
    };
    for (const size_t c : strobes) number_at(names[c], false);  // checked, not kept
    ClaimedPoint p;
    p.line = number;
    p.value = number_at("value", true).value_or(0.0);
    p.time = number_at("time", true).value_or(0.0);
    p.displacement.resize(n);
    p.velocity.resize(n);
    for (int i = 0; i < n; ++i) {
      p.displacement[i] = number_at(fmt::format("displacement_{}", i + 1), true).value_or(0.0);
      p.velocity[i] = number_at(fmt::format("velocity_{}", i + 1), true).value_or(0.0);
    }
    if (const auto q = number_at("period", false)) {
      if (*q >= 1 && *q == std::floor(*q) && *q <= 1e6)
        p.period = static_cast<int>(*q);
      else
        problems.push_back(fmt::format("{}: period {} is not a whole number of forcing periods ≥ 1",
                                       where(column["period"]), *q));
    }
    if (column.count("stable")) {
      const std::string& s = cells[column["stable"]];
      if (s == "1" || s == "true" || s == "True" || s == "yes") p.stable = true;
      else if (s == "0" || s == "false" || s == "False" || s == "no") p.stable = false;
      else if (!s.empty())
        problems.push_back(fmt::format("{}: '{}' is not 0 or 1", where(column["stable"]), s));
    }
    if (const auto sp = number_at("sticking_fraction", false)) {
      if (*sp >= 0 && *sp <= 1) p.sticking_fraction = *sp;
      else problems.push_back(fmt::format("{}: sticking fraction {} is not in [0, 1]", where(column["sticking_fraction"]), *sp));
    }
    if (column.count("sequence")) {
      // The claimed contact sequence (several contacts): its syntax here, its contacts against the
      // scene's when the rows are prepared.
      std::string why;
      p.sequence = cells[column["sequence"]];
      if (!ParseContactSequence(p.sequence, -1, why))
        problems.push_back(fmt::format("{}: {}", where(column["sequence"]), why));
    }
    points.push_back(std::move(p));
  }
  if (problems.size() >= kCsvMaxProblems)
    problems.push_back(fmt::format("{}: stopped reading after {} problems", path, kCsvMaxProblems));
  else if (!header) problems.push_back(fmt::format("{}: no header row (value,time,displacement_1,...)", path));
  else if (points.empty() && problems.empty()) problems.push_back(fmt::format("{}: no points after the header", path));
  if (!problems.empty()) throw InputError(problems);
  return points;
}

}  // namespace vibro
