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
//   each half is continued away from the bifurcation. Recursively: a seed's branch is switched
//   at as soon as it is stored, and so are the branches that gives, before the next seed.
// - The cap. At most max_branches branches are stored, and the seeds come first (their branches
//   hold the attractors the coverage check is about): a switch is followed during the seeding
//   only when the cap leaves room for both its halves and for every periodic attractor still to
//   be tried as a seed; the switches that would not are deferred until every seed is continued,
//   then followed in order, breadth first, while the cap allows. Once it is reached nothing more
//   is continued: every seed and every switch left out is named in the notes and counted
//   (seeds_left_out, switches_left_out), and an attractor whose seed was left out is reported
//   uncovered with that reason. Below the cap (the default leaves ample room) the order is the
//   depth-first one above.
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

// The defaults of a diagram's options, in one place: the library's DiagramRequest, `vibro
// diagram`'s options (src/frontend/diagram.hpp) and Python's `vibro.diagram` (which reads them
// from the extension module) all take them from here (docs/diagram.md, "The cap on branches, and the defaults").
struct DiagramDefaults {
  static constexpr int sweep_steps = 40;
  static constexpr int record = 16;
  static constexpr int searches = 3;
  static constexpr int search_grid = 6;
  static constexpr int max_period = 4;
  // A bound against runaway switching, not a budget: the tube scene over ω ∈ [0.4, 1.6] stores
  // 40 branches (docs/diagram.md), the two-sided oscillator over a ∈ [1, 8] 15.
  static constexpr int max_branches = 100;
  static constexpr int max_points = 400;
  // Relative distance between a simulated attractor's impacts and a branch's orbit (phases mod
  // 2π in radians, speeds relative to 1 + the largest speed).
  static constexpr double coverage_tolerance = 1e-3;
  static constexpr double identity_tolerance = 1e-6;
  static constexpr int threads = 0;
};

struct DiagramRequest {
  std::function<Scene(double)> scene_at;  // the scene with the key at λ (throws outside its range)
  std::string param;                      // the key (for output)
  double from = 0, to = 1;
  int sweep_steps = DiagramDefaults::sweep_steps;    // the sweep: steps + 1 values up, and back down
  int record = DiagramDefaults::record;              // section points kept per sweep run
  int searches = DiagramDefaults::searches;          // attractor searches at this many values (0: none)
  int search_grid = DiagramDefaults::search_grid;    // each a search_grid × search_grid grid of (x_B, v_B) starts
  int max_period = DiagramDefaults::max_period;      // longest period switched to (forcing periods); seeds: any
  int max_branches = DiagramDefaults::max_branches;  // branches stored at most (a hard bound)
  int max_points = DiagramDefaults::max_points;      // per continuation
  double coverage_tolerance = DiagramDefaults::coverage_tolerance;
  double identity_tolerance = DiagramDefaults::identity_tolerance;
  int threads = DiagramDefaults::threads;            // searches (oneTBB; 0: all cores)
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
  // max_branches reached: the seeds not continued and the switches (a bifurcation, or one half
  // of it) not followed because of it, each also named in `notes`.
  bool cap_reached = false;
  int seeds_left_out = 0, switches_left_out = 0;
  std::vector<std::string> notes;  // switches and seeds that gave nothing, and why
  // Wall time of each stage, seconds.
  double sweep_seconds = 0, search_seconds = 0, continuation_seconds = 0, switching_seconds = 0,
         coverage_seconds = 0;
};

DiagramResult Diagram(const DiagramRequest& request);

}  // namespace vibro
