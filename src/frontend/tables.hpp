// Tables given as columns of numbers (Python's numpy arrays) instead of CSV files: the same rows
// the CSV readers (vibro/events_csv.hpp, vibro/branch_csv.hpp) produce from a file, with the same
// column names and the same checks of each value. A row is named "NAME row K" (K from 0, as numpy
// counts) where the readers say FILE:LINE; its `line` is K.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "vibro/branch_check.hpp"
#include "vibro/score.hpp"

namespace vibro::frontend {

// Another simulator's events: `t`, `kind` (impact, accumulation, stick, release, grazing or the
// HDF5 enum values 1..5, as text) and optionally `velocity` (NaN: not given, as an empty CSV cell).
// Rows in the arrays' order, as the CSV reader keeps the file's (the order is checked by
// ScoreEventTable, commands.hpp). Throws InputError with every problem.
// `contact` (optional, several contacts): each event's contact, NaN: none.
std::vector<TheirEvent> EventTable(const std::vector<double>& t, const std::vector<std::string>& kind,
                                   const std::optional<std::vector<double>>& velocity,
                                   const std::optional<std::vector<double>>& contact = std::nullopt);

// A branch from another tool: the columns of a branch CSV by name (value, time,
// displacement_1..n, velocity_1..n; optionally period, stable, sticking_fraction, where NaN is a
// claim not made, as an empty cell), all of one length, and optionally the column `sequence` of
// claimed contact sequences ("" makes no claim). Throws InputError with every problem.
std::vector<ClaimedPoint> BranchTable(const std::map<std::string, std::vector<double>>& columns, int n,
                                      const std::optional<std::vector<std::string>>& sequences = std::nullopt);

}  // namespace vibro::frontend
