// Another simulator's events as CSV (docs/validation.md): a header row with the columns
//   t         event time (same clock as the scene's initial.time)
//   kind      impact | accumulation | stick | release | grazing (or the HDF5 enum values 1..5)
//   velocity  optional: contact velocity ẋ_B just before the event
//   contact   optional, several contacts: the event's contact (0-based [[contact]] order); given,
//             it must be given on every row (ScoreEventTable)
// Lines starting with '#' and blank lines are skipped. The file is read within the limits of
// docs/validation.md ("Input limits": 1 GiB, 1 MiB a line, text only, a UTF-8 BOM dropped) and
// the process's stop request (stop_request.hpp) is polled while it is read.
#pragma once

#include <string>
#include <vector>

#include "vibro/score.hpp"

namespace vibro {

// The rows in the file's order, each with its line. Throws InputError listing the problems as
// FILE:LINE:COLUMN (name): what is wrong (at most 20), and Interrupted (child_process.hpp) on a
// stop request. The table's own checks (time order, the scene's span) are EventTableProblems's.
std::vector<TheirEvent> ReadEventsCsv(const std::string& path);

}  // namespace vibro
