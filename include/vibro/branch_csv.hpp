// Branch files from other tools (docs/validation.md): CSV with a header row, one point per row.
//   value, time, displacement_1..n, velocity_1..n   required (n: entries of the scene's [initial])
//   period, stable (0/1), sticking_fraction         optional claims (a cell may be left empty)
// Lines starting with '#' and blank lines are skipped; columns may come in any order.
#pragma once

#include <string>
#include <vector>

#include "vibro/branch_check.hpp"

namespace vibro {

// Throws InputError listing every problem as FILE:LINE:COLUMN (name): what is wrong.
std::vector<ClaimedPoint> ReadBranchCsv(const std::string& path, int n);

}  // namespace vibro
