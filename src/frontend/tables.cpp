// Tables given as columns of numbers instead of CSV files (tables.hpp).
#include "frontend/tables.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "vibro/branch_csv.hpp"
#include "vibro/contact_sequence.hpp"
#include "vibro/scene_file.hpp"

namespace vibro::frontend {

std::vector<TheirEvent> EventTable(const std::vector<double>& t, const std::vector<std::string>& kind,
                                   const std::optional<std::vector<double>>& velocity,
                                   const std::optional<std::vector<double>>& contact) {
  static const std::map<std::string, EventKind> kKinds = {
      {"impact", EventKind::kImpact},   {"1", EventKind::kImpact},
      {"accumulation", EventKind::kAccumulation}, {"2", EventKind::kAccumulation},
      {"stick", EventKind::kStick},     {"3", EventKind::kStick},
      {"release", EventKind::kRelease}, {"4", EventKind::kRelease},
      {"grazing", EventKind::kGrazing}, {"5", EventKind::kGrazing}};
  std::vector<std::string> problems;
  if (kind.size() != t.size() || (velocity && velocity->size() != t.size()) || (contact && contact->size() != t.size()))
    throw InputError({fmt::format("events: columns of different lengths (t {}, kind {}{}{})", t.size(), kind.size(),
                                  velocity ? fmt::format(", velocity {}", velocity->size()) : "",
                                  contact ? fmt::format(", contact {}", contact->size()) : "")});
  if (t.empty()) throw InputError({"events: no rows (expected columns t, kind and optionally velocity)"});
  std::vector<TheirEvent> out;
  for (size_t i = 0; i < t.size(); ++i) {
    TheirEvent e;
    e.line = static_cast<int>(i);
    if (std::isfinite(t[i])) e.t = t[i];
    else problems.push_back(fmt::format("events row {} (t): {} is not a finite number", i, t[i]));
    const auto it = kKinds.find(kind[i]);
    if (it == kKinds.end())
      problems.push_back(fmt::format("events row {} (kind): '{}' is not impact, accumulation, stick, release or "
                                     "grazing (or 1..5)",
                                     i, kind[i]));
    else
      e.kind = it->second;
    if (velocity && !std::isnan((*velocity)[i])) {
      if (std::isfinite((*velocity)[i])) e.velocity = (*velocity)[i];
      else problems.push_back(fmt::format("events row {} (velocity): {} is not a finite number", i, (*velocity)[i]));
    }
    if (contact && !std::isnan((*contact)[i])) {
      const double c = (*contact)[i];
      if (c >= 0 && c <= 1e6 && c == std::floor(c)) e.contact = static_cast<int>(c);
      else problems.push_back(fmt::format("events row {} (contact): {} is not a contact index (a whole number ≥ 0)", i, c));
    }
    out.push_back(e);
  }
  if (!problems.empty()) throw InputError(problems);
  return out;
}

std::vector<ClaimedPoint> BranchTable(const std::map<std::string, std::vector<double>>& columns, int n,
                                      const std::optional<std::vector<std::string>>& sequences) {
  std::vector<std::string> known = {"value", "time", "period", "stable", "sticking_fraction"};
  std::vector<std::string> required = {"value", "time"};
  for (int i = 1; i <= n; ++i) {
    known.push_back(fmt::format("displacement_{}", i));
    known.push_back(fmt::format("velocity_{}", i));
  }
  for (int i = 1; i <= n; ++i) required.push_back(fmt::format("displacement_{}", i));
  for (int i = 1; i <= n; ++i) required.push_back(fmt::format("velocity_{}", i));
  std::vector<std::string> problems;
  size_t rows = 0;
  bool first = true;
  for (const auto& [name, values] : columns) {
    if (std::find(known.begin(), known.end(), name) == known.end() && !IsStrobeColumn(name))
      problems.push_back(fmt::format("branch: unknown column '{}' (expected value, time, displacement_1..{}, "
                                     "velocity_1..{}, and optionally period, stable, sticking_fraction, "
                                     "sequence, strobe_0..)",
                                     name, n, n));
    if (!first && values.size() != rows)
      problems.push_back(fmt::format("branch: column '{}' has {} rows, the others {}", name, values.size(), rows));
    rows = first ? values.size() : rows;
    first = false;
  }
  if (sequences && !first && sequences->size() != rows)
    problems.push_back(fmt::format("branch: column 'sequence' has {} rows, the others {}", sequences->size(), rows));
  for (const auto& name : required)
    if (!columns.count(name)) problems.push_back(fmt::format("branch: missing column '{}'", name));
  if (!problems.empty()) throw InputError(problems);
  if (rows == 0) throw InputError({"branch: no rows"});
  const auto at = [&](const std::string& name, size_t row) -> std::optional<double> {
    const auto it = columns.find(name);
    if (it == columns.end() || std::isnan(it->second[row])) return std::nullopt;
    return it->second[row];
  };
  std::vector<ClaimedPoint> points;
  for (size_t r = 0; r < rows; ++r) {
    const auto required_number = [&](const std::string& name) {
      const double v = columns.at(name)[r];
      if (std::isfinite(v)) return v;
      problems.push_back(fmt::format("branch row {} ({}): {} is not a finite number", r, name, v));
      return 0.0;
    };
    ClaimedPoint p;
    p.line = static_cast<int>(r);
    p.value = required_number("value");
    p.time = required_number("time");
    p.displacement.resize(n);
    p.velocity.resize(n);
    for (int i = 0; i < n; ++i) {
      p.displacement[i] = required_number(fmt::format("displacement_{}", i + 1));
      p.velocity[i] = required_number(fmt::format("velocity_{}", i + 1));
    }
    if (const auto q = at("period", r)) {
      if (*q >= 1 && *q == std::floor(*q) && *q <= 1e6)
        p.period = static_cast<int>(*q);
      else
        problems.push_back(fmt::format("branch row {} (period): {} is not a whole number of forcing periods ≥ 1",
                                       r, *q));
    }
    if (const auto s = at("stable", r)) {
      if (*s == 0 || *s == 1) p.stable = *s == 1;
      else problems.push_back(fmt::format("branch row {} (stable): {} is not 0 or 1", r, *s));
    }
    if (const auto sp = at("sticking_fraction", r)) {
      if (*sp >= 0 && *sp <= 1) p.sticking_fraction = *sp;
      else problems.push_back(fmt::format("branch row {} (sticking_fraction): {} is not in [0, 1]", r, *sp));
    }
    if (sequences) {
      std::string why;
      p.sequence = (*sequences)[r];
      if (!ParseContactSequence(p.sequence, -1, why)) problems.push_back(fmt::format("branch row {} (sequence): {}", r, why));
    }
    points.push_back(std::move(p));
  }
  if (!problems.empty()) throw InputError(problems);
  return points;
}

}  // namespace vibro::frontend
