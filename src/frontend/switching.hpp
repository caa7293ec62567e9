// Branch switching from a stored branch (`vibro continue --from FILE --point K --switch` and
// Python's `vibro.continue_(..., from_=FILE, point=K, switch=True)`, docs/orbits.md): which
// bifurcation of the file, the switch itself (vibro/branch_switch.hpp) and which half of the new
// branch is continued.
#pragma once

#include <atomic>
#include <functional>
#include <stdexcept>
#include <string>

#include "frontend/limits.hpp"
#include "vibro/branch_switch.hpp"
#include "vibro/hdf5_branch.hpp"
#include "vibro/scene.hpp"

namespace vibro::frontend {

// No second branch was found (a numerical outcome: the caller exits 3 and writes nothing).
struct SwitchFailed : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct SwitchedStart : SwitchStart {
  std::string kind;  // "branch-point" or "flip"
  double at = 0;     // the bifurcation's parameter value, as the switch located it
  std::string half;  // which half was taken, in words
};

// The start of the other branch through the branch-point or flip of `file` that lies between its
// points k − 1 and k + 1 (the one nearest to point k when there are several); `pt` is point k. Of the
// new branch's halves, the one leaving the bifurcation towards `to`, and when both do, the one
// whose x_B at the section lies on `side` ("above" or "below") of the old branch.
// InputError (options named as `naming` writes them) when no such bifurcation is stored or the new
// branch does not head for `to`; SwitchFailed when no second branch is found; Interrupted on a
// stop request.
SwitchedStart SwitchAtStoredPoint(const std::function<Scene(double)>& scene_at, const std::string& key, double to,
                                  const std::string& file, long long k, const StoredBranchPoint& pt,
                                  const std::string& side, Naming naming, const std::atomic<bool>* stop);

}  // namespace vibro::frontend
