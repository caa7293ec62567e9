// Branch files from other tools (docs/validation.md): CSV with a header row, one point per row.
//   value, time, displacement_1..n, velocity_1..n   required (n: entries of the scene's [initial])
//   period, stable (0/1), sticking_fraction         optional claims (a cell may be left empty)
//   sequence                                        optional claim, several contacts: the orbit's
//                                                   contact sequence ("0:impact 1:impact*3 0:stick")
//   strobe_0..strobe_{m-1}                          ignored: each contact's coordinate at the
//                                                   start's forcing phase, as scripts/branch_to_csv.py
//                                                   writes it for plots (docs/output.md), no claim
// Lines starting with '#' and blank lines are skipped; columns may come in any order. The file is
// read within the limits of docs/validation.md ("Input limits": 1 GiB, 1 MiB a line, text only, a
// UTF-8 BOM dropped) and the process's stop request (stop_request.hpp) is polled while it is read.
#pragma once

#include <string>
#include <vector>

#include "vibro/branch_check.hpp"

namespace vibro {

// Throws InputError listing the problems as FILE:LINE:COLUMN (name): what is wrong (at most 20),
// and Interrupted (child_process.hpp) on a stop request.
std::vector<ClaimedPoint> ReadBranchCsv(const std::string& path, int n);

// "strobe_J" (J a contact index): a column of the stroboscopic state, read past as no claim.
bool IsStrobeColumn(const std::string& name);

}  // namespace vibro
