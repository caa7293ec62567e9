// Another simulator's events as CSV (docs/validation.md): a header row with the columns
//   t         event time (same clock as the scene's initial.time)
//   kind      impact | accumulation | stick | release | grazing (or the HDF5 enum values 1..5)
//   velocity  optional: contact velocity ẋ_B just before the event
// Lines starting with '#' and blank lines are skipped; rows are sorted by time.
#pragma once

#include <string>
#include <vector>

#include "vibro/score.hpp"

namespace vibro {

// Throws InputError listing every problem as FILE:LINE:COLUMN (name): what is wrong.
std::vector<TheirEvent> ReadEventsCsv(const std::string& path);

}  // namespace vibro
