// The whole one-parameter bifurcation diagram of a scene, automatically (`vibro diagram`,
// docs/diagram.md): seeds from a brute-force sweep and from attractor searches at a few parameter
// values, continuation of every distinct orbit found both ways, switching at every branch point and
// flip (branch_switch.hpp), branch identity, and a coverage check of the sweep's attractors.
//
// - Seeds. Every periodic attractor of the sweep (up and down, so hysteresis shows) and of the
//   searches (a grid of x_B, v_B starts at `searches` evenly spaced values) is a seed, in that
//   order, whatever its period (up to the scene's run.max_period, the longest its classification
//   tries; max_period bounds only the switching). A seed already on a branch found so far (the
//   coverage test below) is skipped; otherwise its orbit is solved from the run's final state
//   (OrbitFromState) and continued both ways to the ends of [from, to].
// - Switching. At every branch point and flip of a new branch (when the period switched to, 2q at
//   a flip, q at a branch point, is at most max_period), SwitchBranch gives the first points of
//   the other branch(es);
//   each half is continued away from the bifurcation. Recursively, up to max_branches branches.
// - Identity. A new branch is the same as a stored one when their periods divide one another and,
//   at up to six of its points spread over it (past the first fifth of a switched branch, where it
//   meets its parent), the stored branch's orbit at the same parameter has the same cyclic contact
//   sequence (SameContactSequence, on the CanonicalRotation every sequence is written in) and the
//   same impacts, phases mod 2π and speeds: interpolated between the stored branch's two points
//   around λ (within identity_tolerance plus a tenth of their difference), or solved by Newton
//   from the nearer one (within identity_tolerance), at every one of them (a sample outside the
//   stored branch's range of λ makes it a different branch). Such a branch is counted in
//   `duplicates` and not stored: a branch reached twice (from both ends, or through a loop of switches) is kept
//   once.
// - Coverage. A periodic attractor of the sweep at λ is covered by a stored branch of its period
//   when the branch's orbit at λ (Newton from the branch point nearest to λ, of a segment around λ
//   with a stable end) is stable and has the attractor's contact sequence (several contacts) and
//   impacts (phases mod 2π, speeds; or sticking phases) within coverage_tolerance. Every other
//   attractor is reported uncovered, with the reason: not periodic (chaotic, or a period above
//   run.max_period), or no stable branch there (with what became of its seed). The attractors of
//   the searches are checked the same way. The not-periodic ones are also grouped into windows of
//   consecutive sweep values (uncovered_windows).
//
// Continuations never leave [from, to]: a branch that turns back (a fold) and crosses the other
// end stops there ("left the range at …"). A stop request ends the diagram with the branches
// finished so far (status "interrupted").
#pragma once

#include <atomic>
#include <functional>
#include <string>
#include <vector>

#include "vibro/continuation.hpp"
#include "vibro/scene.hpp"
#include "vibro/studies.hpp"

namespace vibro {

struct DiagramRequest {
  std::function<Scene(double)> scene_at;  // the scene with the key at λ (throws outside its range)
  std::string param;                      // the key (for output)
  double from = 0, to = 1;
  int sweep_steps = 40;    // the sweep: steps + 1 values up, and back down
  int record = 16;         // section points kept per sweep run
  int searches = 3;        // attractor searches at this many values (0: none)
  int search_grid = 6;     // each a search_grid × search_grid grid of (x_B, v_B) starts
  int max_period = 4;      // longest period switched to (forcing periods); seeds: any period
  int max_branches = 24;   // branches stored at most
  int max_points = 400;    // per continuation
  double coverage_tolerance = 1e-4;
  double identity_tolerance = 1e-6;
  int threads = 0;         // searches (oneTBB; 0: all cores)
  const std::atomic<bool>* stop_requested = nullptr;
  std::function<void(const std::string& stage, long long branches)> progress;
};

struct DiagramBranch {
  Branch branch;  // points in order along the branch (param set)
  // How it was found: "seed" (an attractor of the sweep or a search at `born_at`) or the
  // bifurcation it was switched from: "branch-point" or "flip", of branch `parent` at `born_at`.
  std::string origin;
  int parent = -1;
  double born_at = 0;
  // Why each end stopped, in words ("reached the end value", "grazing (the orbit does not go on)",
  // "left the range at …"), and where: the λ of its first and last points. A seed branch's first
  // end is where its continuation towards `from` stopped; a switched branch's first end is its
  // bifurcation.
  std::string end_first, end_last;
};

struct CoverageEntry {
  double value = 0;
  bool upward = true;          // from the sweep's way up, or down
  std::string source;          // "sweep up" | "sweep down" | "search" (a grid search's attractor)
  std::string kind;            // the attractor's kind
  int period = 0;              // 0: not periodic
  int branch = -1;             // the covering branch (−1: uncovered)
  double distance = 0;         // relative distance to its orbit (covered)
  std::string reason;          // why uncovered
};

// A run of consecutive attractors of one source (the sweep up, the sweep down, or a search's
// value) that are uncovered because they are not periodic: the chaotic windows, [from, to] in the
// order of the sweep's values (from = to for a single value).
struct UncoveredWindow {
  double from = 0, to = 0;
  std::string source;  // "sweep up" | "sweep down" | "search"
  int count = 0;       // attractors in it
  std::string reason;  // their common reason, or a summary when they differ
};

struct DiagramResult {
  std::string status = "ok";  // "ok" | "interrupted"
  std::string param;
  double from = 0, to = 1;
  std::vector<SweepPoint> sweep;
  std::vector<DiagramBranch> branches;
  // One per sweep point, in sweep order, then one per attractor of the searches.
  std::vector<CoverageEntry> coverage;
  // The not-periodic uncovered entries of `coverage`, grouped into windows (each entry in one).
  std::vector<UncoveredWindow> uncovered_windows;
  int duplicates = 0;        // branches found again and not stored
  int seeds_tried = 0;       // seeds continued (not already covered)
  std::vector<std::string> notes;  // switches and seeds that gave nothing, and why
  // Wall time of each stage, seconds.
  double sweep_seconds = 0, search_seconds = 0, continuation_seconds = 0, switching_seconds = 0,
         coverage_seconds = 0;
};

DiagramResult Diagram(const DiagramRequest& request);

}  // namespace vibro
