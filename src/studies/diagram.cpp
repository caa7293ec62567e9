// The automatic one-parameter diagram (see include/vibro/diagram.hpp).
#include "vibro/diagram.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <deque>
#include <limits>
#include <optional>
#include <thread>

#include <fmt/format.h>

#include "vibro/branch_switch.hpp"
#include "vibro/contact_sequence.hpp"
#include "vibro/orbit_from_state.hpp"
#include "vibro/system.hpp"

namespace vibro {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

double Seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

// An angle difference in (−π, π].
double Wrap(double d) {
  d = std::fmod(d, 2 * M_PI);
  if (d > M_PI) d -= 2 * M_PI;
  if (d <= -M_PI) d += 2 * M_PI;
  return d;
}

// The distance between two periodic motions from their summaries, invariant under a shift of
// the time origin by whole forcing periods: impacts matched contact by contact, compared by phase
// mod 2π (radians) and speed (relative to 1 + the largest speed); sticking phases by start mod 2π
// and duration. ∞ when the kinds, periods or the numbers of impacts or sticking phases differ.
double MotionDistance(const Attractor& a, const Attractor& b) {
  if (a.kind != b.kind || a.period != b.period) return kInf;
  if (a.impact_phases.size() != b.impact_phases.size() || a.stick_phases.size() != b.stick_phases.size()) return kInf;
  double scale = 1;
  for (double v : a.impact_velocities) scale = std::max(scale, 1 + std::abs(v));
  double worst = 0;
  std::vector<bool> used(b.impact_phases.size(), false);
  for (size_t i = 0; i < a.impact_phases.size(); ++i) {
    const int ci = i < a.impact_contacts.size() ? a.impact_contacts[i] : 0;
    double best = kInf;
    size_t at = 0;
    for (size_t j = 0; j < b.impact_phases.size(); ++j) {
      const int cj = j < b.impact_contacts.size() ? b.impact_contacts[j] : 0;
      if (used[j] || cj != ci) continue;
      const double d = std::max(std::abs(Wrap(a.impact_phases[i] - b.impact_phases[j])),
                                std::abs(a.impact_velocities[i] - b.impact_velocities[j]) / scale);
      if (d < best) {
        best = d;
        at = j;
      }
    }
    if (!std::isfinite(best)) return kInf;
    used[at] = true;
    worst = std::max(worst, best);
  }
  std::vector<bool> used_s(b.stick_phases.size(), false);
  for (size_t i = 0; i < a.stick_phases.size(); ++i) {
    double best = kInf;
    size_t at = 0;
    for (size_t j = 0; j < b.stick_phases.size(); ++j) {
      if (used_s[j]) continue;
      const auto& [s1, e1] = a.stick_phases[i];
      const auto& [s2, e2] = b.stick_phases[j];
      const double d = std::max(std::abs(Wrap(s1 - s2)), std::abs((e1 - s1) - (e2 - s2)));
      if (d < best) {
        best = d;
        at = j;
      }
    }
    if (!std::isfinite(best)) return kInf;
    used_s[at] = true;
    worst = std::max(worst, best);
  }
  if (a.sticking_fraction && b.sticking_fraction)
    worst = std::max(worst, std::abs(*a.sticking_fraction - *b.sticking_fraction));
  return worst;
}

bool SameSequence(const std::string& a, const std::string& b) {
  if (a.empty() || b.empty()) return a.empty() && b.empty();
  std::string pa, pb;
  const auto x = ParseContactSequence(a, -1, pa), y = ParseContactSequence(b, -1, pb);
  if (!x || !y) return a == b;
  // Every sequence vibro writes is in its canonical rotation; SameContactSequence compares the
  // cyclic words whatever rotation either is in.
  return SameContactSequence(CanonicalRotation(*x), CanonicalRotation(*y));
}

// A branch point's impacts as a summary (phases, speeds, contacts), for MotionDistance.
Attractor ImpactsOf(const BranchPoint& p) {
  Attractor a;
  a.kind = p.summary.kind;
  a.period = p.summary.period;
  for (const auto& im : p.impacts) {
    a.impact_phases.push_back(im.phase);
    a.impact_velocities.push_back(im.v_before);
    a.impact_contacts.push_back(im.contact);
  }
  a.stick_phases = p.summary.stick_phases;
  a.sticking_fraction = p.summary.sticking_fraction;
  return a;
}

// The impacts of the orbit at λ between two neighbouring points of a branch, linearly
// interpolated (impacts matched as MotionDistance matches them); none when they do not match.
std::optional<Attractor> Interpolated(const BranchPoint& a, const BranchPoint& b, double lambda) {
  Attractor x = ImpactsOf(a), y = ImpactsOf(b);
  if (!std::isfinite(MotionDistance(x, y))) return std::nullopt;
  const double w = b.value == a.value ? 0.0 : (lambda - a.value) / (b.value - a.value);
  std::vector<bool> used(y.impact_phases.size(), false);
  for (size_t i = 0; i < x.impact_phases.size(); ++i) {
    size_t at = 0;
    double best = kInf;
    for (size_t j = 0; j < y.impact_phases.size(); ++j) {
      if (used[j] || y.impact_contacts[j] != x.impact_contacts[i]) continue;
      const double d = std::abs(Wrap(x.impact_phases[i] - y.impact_phases[j]));
      if (d < best) best = d, at = j;
    }
    used[at] = true;
    x.impact_phases[i] += w * Wrap(y.impact_phases[at] - x.impact_phases[i]);
    x.impact_velocities[i] += w * (y.impact_velocities[at] - x.impact_velocities[i]);
  }
  return x;
}

int PeriodOf(const BranchPoint& p, int fallback) { return p.summary.period.value_or(fallback); }

// The least period of a point of a branch of period q, from its motion over qT: the least p
// dividing q such that shifting the time by pT maps its impacts (phase mod 2πq, speed, contact)
// and sticking phases onto themselves. A period-1 orbit continued with period 3 repeats its
// impacts three times and has least period 1. An orbit with neither impacts nor sticking
// phases gives q (nothing to tell by).
int LeastPeriod(const BranchPoint& pt, int q) {
  if (q <= 1 || (pt.impacts.empty() && pt.summary.stick_phases.empty())) return q;
  const double span = 2 * M_PI * q;
  const auto wrap = [span](double d) {
    d = std::fmod(d, span);
    if (d > span / 2) d -= span;
    if (d <= -span / 2) d += span;
    return d;
  };
  double scale = 1;
  for (const auto& im : pt.impacts) scale = std::max(scale, 1 + std::abs(im.v_before));
  constexpr double kTol = 1e-6;
  for (int p = 1; p < q; ++p) {
    if (q % p != 0 || pt.impacts.size() % static_cast<size_t>(q / p) != 0 ||
        pt.summary.stick_phases.size() % static_cast<size_t>(q / p) != 0)
      continue;
    const double shift = 2 * M_PI * p;
    bool repeats = true;
    for (const auto& a : pt.impacts) {
      bool found = false;
      for (const auto& b : pt.impacts)
        found = found || (b.contact == a.contact && std::abs(wrap(b.phase - a.phase - shift)) <= kTol &&
                          std::abs(b.v_before - a.v_before) <= kTol * scale);
      if (!(repeats = found)) break;
    }
    for (const auto& [s1, e1] : pt.summary.stick_phases) {
      if (!repeats) break;
      bool found = false;
      for (const auto& [s2, e2] : pt.summary.stick_phases)
        found = found || (std::abs(wrap(s2 - s1 - shift)) <= kTol && std::abs((e2 - s2) - (e1 - s1)) <= kTol);
      repeats = found;
    }
    if (repeats) return p;
  }
  return q;
}

// Keeps points first..last of `n` and the bifurcations, relabels and crossings within their λ
// range, widened by the largest step between them (a fold lies beyond its neighbouring points).
void KeepPoints(DiagramBranch& n, size_t first, size_t last) {
  auto& pts = n.branch.points;
  double lo = kInf, hi = -kInf, step = 0;
  for (size_t i = first; i <= last; ++i) {
    lo = std::min(lo, pts[i].value), hi = std::max(hi, pts[i].value);
    if (i > first) step = std::max(step, std::abs(pts[i].value - pts[i - 1].value));
  }
  pts.erase(pts.begin() + static_cast<std::ptrdiff_t>(last + 1), pts.end());
  pts.erase(pts.begin(), pts.begin() + static_cast<std::ptrdiff_t>(first));
  for (auto& b : n.branch.bifurcations)  // Bifurcation::point in the kept points
    b.point = b.point >= static_cast<long long>(first) && b.point <= static_cast<long long>(last)
                  ? b.point - static_cast<long long>(first)
                  : -1;
  const auto outside = [&](double v) { return v < lo - step || v > hi + step; };
  std::erase_if(n.branch.bifurcations, [&](const Bifurcation& b) { return outside(b.value); });
  std::erase_if(n.branch.relabels, [&](const Relabel& r) { return outside(r.value); });
  std::erase_if(n.branch.crossings, [&](const LevelCrossing& c) { return outside(c.value); });
  n.branch.end = fmt::format("first end: {}; last end: {}", n.end_first, n.end_last);
}

// The not-periodic uncovered entries of a coverage list grouped into windows: runs of consecutive
// entries of one source (the sweep's way up, its way down, a search's attractors at one value).
std::vector<UncoveredWindow> UncoveredWindows(const std::vector<CoverageEntry>& coverage) {
  std::vector<UncoveredWindow> windows;
  bool open = false;  // the previous entry is in windows.back()
  for (const auto& c : coverage) {
    if (!(c.branch < 0 && c.period == 0 && c.kind == "not-periodic")) {
      open = false;
      continue;
    }
    if (!open || windows.back().source != c.source || (c.source == "search" && windows.back().from != c.value))
      windows.push_back({c.value, c.value, c.source, 0, c.reason});
    auto& w = windows.back();
    w.to = c.value;
    ++w.count;
    if (w.reason != c.reason) w.reason = "not periodic (each value's reason is in the coverage list)";
    open = true;
  }
  return windows;
}

class Builder {
 public:
  explicit Builder(const DiagramRequest& req) : req_(req) {
    lo_ = std::min(req.from, req.to);
    hi_ = std::max(req.from, req.to);
    slack_ = 1e-9 * std::max(1.0, hi_ - lo_);
  }

  DiagramResult Run();

 private:
  bool Stopped() const { return req_.stop_requested && req_.stop_requested->load(); }
  void Progress(const std::string& stage) const {
    if (req_.progress) req_.progress(stage, static_cast<long long>(out_.branches.size()));
  }

  // The orbit of branch `b` at λ: Newton (OrbitFromState) from each of its points next to λ (the
  // nearer end of every segment [λ_i, λ_i+1] that holds λ), with the section kept at the same
  // forcing phase. `stable_end`: only segments with a stable end.
  std::vector<OrbitResult> OrbitsAt(const DiagramBranch& b, double lambda, bool stable_end) const;
  // Whether a motion at λ lies on a stored branch: (branch, distance), or (−1, reason).
  std::pair<int, double> CoveredBy(double lambda, const Attractor& a, std::string& reason) const;
  // Whether `n` repeats `e`: its orbits at its sampled points within e's range (at least half of
  // them) lie on `e`.
  bool Repeats(const DiagramBranch& n, const DiagramBranch& e) const;
  // The index of a stored branch that `n` repeats, or −1.
  int DuplicateOf(const DiagramBranch& n) const;
  // Whether stored branch `e` holds the orbit of `p` (same period assumed): (λ bracketed by two
  // of e's points, the same orbit); `newton`: also by Newton from e's points next to λ.
  std::pair<bool, bool> Holds(const DiagramBranch& e, const BranchPoint& p, bool newton) const;
  // Keeps of `n` only its stretch around `birth` whose orbits no stored branch holds: a branch
  // that runs into a stored one (through a crossing at a grazing, say) ends where it joins it.
  // Returns the stored branch it joins when fewer than three points are left (then `n` is that
  // branch again), else −1.
  int TrimOverlap(DiagramBranch& n, size_t birth) const;
  // Continues from `orbit` at λ0 towards `to`, never beyond [lo, hi].
  Branch Follow(double lambda0, double to, const OrbitRequest& orbit) const;
  // Stores `n` unless it repeats a stored branch; then switches at its bifurcations (SwitchAt).
  // `birth`: the index of the point it was found at (a seed's orbit; 0 for a switched branch).
  void Add(DiagramBranch n, size_t birth = 0);
  bool Full() const { return static_cast<int>(out_.branches.size()) >= req_.max_branches; }
  // Notes that the cap was reached (once).
  void NoteFull();
  // Keeps of `n` only its stretch around `birth` whose orbits have least period n.branch.period
  // (a continuation may run into the orbit of a divisor period, continued as a multiple: that
  // stretch is the shorter period's branch again); false when the orbit at `birth` has a shorter
  // least period itself.
  bool KeepLeastPeriod(DiagramBranch& n, size_t birth);
  // Switches at the branch points and flips of stored branch `stored`, from its bifurcation
  // `first` on; the branches found are stored by Add. During the seeding (seeding_) it switches
  // depth first (recursively, through Add) as long as the cap leaves room for both halves of the
  // switch and for every seed still to come (reserve_); the switches that would not leave that
  // room are deferred (deferred_) until every seed is continued. After the seeding, Add only
  // queues the branches it stores (breadth first).
  void SwitchAt(size_t stored, size_t first = 0);
  void Seed(double lambda, const Attractor& a, const Eigen::VectorXd& X, const Eigen::VectorXd& V,
            const std::string& source);

  const DiagramRequest& req_;
  double lo_ = 0, hi_ = 1, slack_ = 0;
  DiagramResult out_;
  bool full_noted_ = false;
  // The periodic attractors still to be tried as seeds after the current one: room kept under
  // the cap while seeds are still to come (an upper bound: some of them will be covered).
  int reserve_ = 0;
  bool seeding_ = true;
  // Switches not followed yet, (branch, index of its first bifurcation not switched at), in
  // order: deferred while seeds were still to come, then the branches stored after the seeds.
  std::deque<std::pair<size_t, size_t>> deferred_;
  // What became of Add's last branch when it was not stored (empty: stored).
  std::string not_stored_;
  // Seeds whose branch was not stored, and why: (λ, period, why), named by the coverage check.
  struct SeedOutcome {
    double value;
    int period;
    std::string why;
  };
  std::vector<SeedOutcome> seed_outcomes_;
};

std::vector<OrbitResult> Builder::OrbitsAt(const DiagramBranch& b, double lambda, bool stable_end) const {
  std::vector<OrbitResult> found;
  const auto& pts = b.branch.points;
  const Scene scene = req_.scene_at(lambda);
  const System sys(scene);
  for (size_t i = 0; i < pts.size(); ++i) {
    const size_t j = std::min(i + 1, pts.size() - 1);
    if (j == i && pts.size() > 1) break;
    const double a = std::min(pts[i].value, pts[j].value), c = std::max(pts[i].value, pts[j].value);
    if (lambda < a - slack_ || lambda > c + slack_) continue;
    if (stable_end && !pts[i].stable && !pts[j].stable) continue;
    const auto& near = std::abs(pts[i].value - lambda) <= std::abs(pts[j].value - lambda) ? pts[i] : pts[j];
    // Same forcing phase ωt0 at the new λ (the key may be the frequency).
    const Scene at_near = req_.scene_at(near.value);
    InitialOverride start{near.section_time * at_near.frequency / scene.frequency, near.X, near.V};
    OrbitRequest r;
    r.kind = OrbitKind::kAuto;
    r.period = b.branch.period;
    r.transient_periods = 0;
    auto orbit = OrbitFromState(sys, scene, start, r);
    if (orbit.status == "converged") found.push_back(std::move(orbit));
  }
  return found;
}

std::pair<int, double> Builder::CoveredBy(double lambda, const Attractor& a, std::string& reason) const {
  if (a.kind == "not-periodic" || !a.period) {
    reason = a.recurrence_period
                 ? fmt::format("not periodic within run.max_period = {} (its section recurs after {} periods)",
                               a.searched_period.value_or(0), *a.recurrence_period)
                 : fmt::format("not periodic (chaotic, or a period above run.max_period = {})",
                               a.searched_period.value_or(0));
    return {-1, 0};
  }
  double nearest = kInf;
  for (size_t k = 0; k < out_.branches.size(); ++k) {
    const auto& b = out_.branches[k];
    if (b.branch.points.empty() || PeriodOf(b.branch.points.front(), b.branch.period) != *a.period) continue;
    for (const auto& orbit : OrbitsAt(b, lambda, true)) {
      const double d = MotionDistance(orbit.summary, a);
      if (orbit.stable && d <= req_.coverage_tolerance) return {static_cast<int>(k), d};
      nearest = std::min(nearest, d);
    }
  }
  reason = std::isfinite(nearest)
               ? fmt::format("no stable branch within {:.1e} (nearest orbit of a branch: {:.2e})",
                             req_.coverage_tolerance, nearest)
               : "no stable continued branch of its period holds it";
  for (const auto& o : seed_outcomes_)  // each outcome once (the sweep up and down may share a λ)
    if (o.period == *a.period && std::abs(o.value - lambda) <= slack_ && reason.find(o.why) == std::string::npos)
      reason += "; " + o.why;
  return {-1, 0};
}

int Builder::DuplicateOf(const DiagramBranch& n) const {
  for (size_t k = 0; k < out_.branches.size(); ++k)
    if (Repeats(n, out_.branches[k])) return static_cast<int>(k);
  return -1;
}


std::pair<bool, bool> Builder::Holds(const DiagramBranch& e, const BranchPoint& p, bool newton) const {
  // The stored branch's orbit at λ: between its two points around λ (interpolated, within a
  // tenth of their difference), or Newton from the nearer one.
  bool bracketed = false, same = false;
  const auto& ep = e.branch.points;
  const Attractor mine = ImpactsOf(p);
  for (size_t j = 0; j + 1 < ep.size() && !same; ++j) {
    const double lo = std::min(ep[j].value, ep[j + 1].value), hi = std::max(ep[j].value, ep[j + 1].value);
    if (p.value < lo - slack_ || p.value > hi + slack_) continue;
    bracketed = true;
    if (!SameSequence(ep[j].sequence, p.sequence)) continue;
    const auto at = Interpolated(ep[j], ep[j + 1], p.value);
    if (!at) continue;
    const double spread = MotionDistance(ImpactsOf(ep[j]), ImpactsOf(ep[j + 1]));
    same = MotionDistance(*at, mine) <= req_.identity_tolerance + 0.1 * spread;
  }
  if (newton && !same && bracketed)
    for (const auto& o : OrbitsAt(e, p.value, false))
      same = same || (SameSequence(o.sequence, p.sequence) &&
                      MotionDistance(o.summary, p.summary) <= req_.identity_tolerance);
  return {bracketed, same};
}

bool Builder::Repeats(const DiagramBranch& n, const DiagramBranch& e) const {
  const auto& pts = n.branch.points;
  // Every stored branch's orbits have least period its period (KeepLeastPeriod): branches of
  // different periods never hold the same orbit.
  if (pts.empty() || e.branch.points.empty() || e.branch.period != n.branch.period) return false;
  // Samples away from the birth of a switched branch (where it meets its parent).
  const size_t first = n.origin == "seed" ? 0 : std::min(pts.size() - 1, pts.size() / 5 + 1);
  std::vector<size_t> samples;
  const size_t count = std::min<size_t>(6, pts.size() - first);
  for (size_t s = 0; s < count; ++s)
    samples.push_back(first + (count > 1 ? s * (pts.size() - 1 - first) / (count - 1) : 0));
  // Every sample must be held: a sample outside e's range of λ is an orbit e does not have (the
  // new branch reaches further, e.g. a seed's branch running into a stored one from outside it).
  // Such a branch is not a repeat; TrimOverlap keeps its stretch that no stored branch holds.
  for (size_t i : samples) {
    const auto [bracketed, same] = Holds(e, pts[i], true);
    if (!bracketed || !same) return false;
  }
  return true;
}

int Builder::TrimOverlap(DiagramBranch& n, size_t birth) const {
  auto& pts = n.branch.points;
  birth = std::min(birth, pts.size() - 1);
  // Near the birth of a switched branch its orbits are close to its parent's.
  const size_t near = n.origin == "seed" ? 0 : pts.size() / 5 + 1;
  const auto held = [&](size_t i) -> int {
    const size_t from_birth = i > birth ? i - birth : birth - i;
    for (size_t k = 0; k < out_.branches.size(); ++k) {
      const auto& e = out_.branches[k];
      if (e.branch.period != n.branch.period || (static_cast<int>(k) == n.parent && from_birth < near)) continue;
      if (Holds(e, pts[i], false).second) return static_cast<int>(k);
    }
    return -1;
  };
  size_t first = birth, last = birth;
  int before = -1, after = -1;
  while (first > 0 && (before = held(first - 1)) < 0) --first;
  while (last + 1 < pts.size() && (after = held(last + 1)) < 0) ++last;
  if (first == 0 && last + 1 == pts.size()) return -1;
  if (last - first < 2) return first > 0 ? before : after;
  const auto joins = [&](size_t keep, size_t next, int k) {
    return fmt::format("joins branch {} after {} = {:.12g} (its orbits from {:.12g} on are that branch's)", k,
                       out_.param, pts[keep].value, pts[next].value);
  };
  if (first > 0) n.end_first = joins(first, first - 1, before);
  if (last + 1 < pts.size()) n.end_last = joins(last, last + 1, after);
  KeepPoints(n, first, last);
  return -1;
}

Branch Builder::Follow(double lambda0, double to, const OrbitRequest& orbit) const {
  ContinuationRequest c;
  c.scene_at = req_.scene_at;
  c.from = lambda0;
  c.to = to;
  c.step = (hi_ - lo_) / 100;
  c.max_step = (hi_ - lo_) / 40;
  c.max_points = req_.max_points;
  c.orbit = orbit;
  // The continuation's stop flag: the caller's stop request, or the branch leaving [lo, hi] (it
  // may turn back at a fold and run past the other end).
  std::atomic<bool> halt{false};
  bool left = false;
  double left_at = 0;
  c.stop_requested = &halt;
  c.progress = [&](size_t, double v) {
    if (v < lo_ - slack_ || v > hi_ + slack_) {
      left = true;
      left_at = v;
      halt = true;
    }
  };
  std::jthread relay([&](std::stop_token st) {
    while (!st.stop_requested()) {
      if (Stopped()) {
        halt = true;
        return;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  });
  Branch br = Continue(c);
  relay.request_stop();
  relay.join();
  br.param = out_.param;
  if (left && !Stopped()) {
    // The points beyond the range are dropped; the branch ended there, not by an interruption.
    const auto beyond = [&](const BranchPoint& p) { return p.value < lo_ - slack_ || p.value > hi_ + slack_; };
    std::vector<long long> kept(br.points.size(), -1);  // Bifurcation::point in the kept points
    for (size_t i = 0, k = 0; i < br.points.size(); ++i)
      if (!beyond(br.points[i])) kept[i] = static_cast<long long>(k++);
    for (auto& b : br.bifurcations)
      b.point = b.point >= 0 && b.point < static_cast<long long>(kept.size()) ? kept[static_cast<size_t>(b.point)] : -1;
    std::erase_if(br.points, beyond);
    std::erase_if(br.bifurcations, [&](const Bifurcation& b) { return b.value < lo_ - slack_ || b.value > hi_ + slack_; });
    br.status = "ok";
    br.end = fmt::format("left [{:.12g}, {:.12g}] (turned back at a fold; next point at {:.12g})", lo_, hi_, left_at);
  }
  return br;
}

bool Builder::KeepLeastPeriod(DiagramBranch& n, size_t birth) {
  auto& pts = n.branch.points;
  const int q = n.branch.period;
  birth = std::min(birth, pts.size() - 1);
  const auto full = [&](size_t i) { return LeastPeriod(pts[i], q) == q; };
  if (!full(birth)) {
    out_.notes.push_back(fmt::format("the {} at {} = {:.12g}: its orbit has least period {}, not {} (not stored "
                                     "as a period-{} branch)",
                                     n.origin, out_.param, n.born_at, LeastPeriod(pts[birth], q), q, q));
    return false;
  }
  size_t first = birth, last = birth;
  while (first > 0 && full(first - 1)) --first;
  while (last + 1 < pts.size() && full(last + 1)) ++last;
  if (first == 0 && last + 1 == pts.size()) return true;
  const auto cut = [&](size_t keep, size_t next) {
    return fmt::format("runs into an orbit of least period {} after {} = {:.12g} (next point at {:.12g}; "
                       "continued with period {} it would repeat that orbit's branch)",
                       LeastPeriod(pts[next], q), out_.param, pts[keep].value, pts[next].value, q);
  };
  if (first > 0) n.end_first = cut(first, first - 1);
  if (last + 1 < pts.size()) n.end_last = cut(last, last + 1);
  KeepPoints(n, first, last);
  return true;
}

void Builder::Add(DiagramBranch n, size_t birth) {
  not_stored_ = "no points";
  if (n.branch.points.empty()) return;
  not_stored_ = "its orbit has a shorter least period";
  if (!KeepLeastPeriod(n, birth)) return;
  const int dup = DuplicateOf(n);
  if (dup >= 0) {
    not_stored_ = fmt::format("its branch repeats branch {}", dup);
    ++out_.duplicates;
    out_.notes.push_back(fmt::format("the {} at {} = {:.12g} leads to branch {} again (not stored twice)",
                                     n.origin == "seed" ? "seed" : n.origin, out_.param, n.born_at, dup));
    return;
  }
  const int joined = TrimOverlap(n, birth);
  if (joined >= 0) {
    not_stored_ = fmt::format("its branch joins branch {} at once", joined);
    ++out_.duplicates;
    out_.notes.push_back(fmt::format("the {} at {} = {:.12g} joins branch {} at once (not stored)", n.origin,
                                     out_.param, n.born_at, joined));
    return;
  }
  if (Full()) {  // reached since its continuation began (another half of the same switch)
    not_stored_ = fmt::format("--max-branches {} was reached before it", req_.max_branches);
    NoteFull();
    if (n.origin == "seed") {
      ++out_.seeds_left_out;
      out_.notes.push_back(fmt::format("the seed at {} = {:.12g} was continued but not stored: --max-branches {} "
                                       "reached",
                                       out_.param, n.born_at, req_.max_branches));
    } else {
      ++out_.switches_left_out;
      out_.notes.push_back(fmt::format("branch {}: a half of its {} at {} = {:.12g} was continued but not stored: "
                                       "--max-branches {} reached",
                                       n.parent, n.origin, out_.param, n.born_at, req_.max_branches));
    }
    return;
  }
  not_stored_.clear();
  out_.branches.push_back(std::move(n));
  if (seeding_)
    SwitchAt(out_.branches.size() - 1);
  else
    deferred_.emplace_back(out_.branches.size() - 1, 0);
}

void Builder::NoteFull() {
  out_.cap_reached = true;
  if (full_noted_) return;
  full_noted_ = true;
  out_.notes.push_back(fmt::format("--max-branches {} reached: nothing more was continued; each seed and switch "
                                   "left out is named below",
                                   req_.max_branches));
}

void Builder::SwitchAt(size_t stored, size_t first) {
  const int index = static_cast<int>(stored);
  Progress("switching");
  // Switching at its branch points and flips (a copy: out_.branches grows below).
  const DiagramBranch b = out_.branches[stored];
  for (size_t at = first; at < b.branch.bifurcations.size(); ++at) {
    const auto& bif = b.branch.bifurcations[at];
    if (Stopped()) return;
    if (bif.kind != "branch-point" && bif.kind != "flip") continue;
    // Where the branch was born: switching there leads back to its parent.
    if (b.origin != "seed" && std::abs(bif.value - b.born_at) <= 1e-6 * std::max(1.0, std::abs(b.born_at))) continue;
    // The period of the branch(es) switched to: 2q at a flip, q at a branch point (a seeded
    // branch may have any period the sweep found; switching is bounded by max_period).
    const int switched_period = bif.kind == "flip" ? 2 * b.branch.period : b.branch.period;
    if (switched_period > req_.max_period) {
      out_.notes.push_back(fmt::format("branch {}: the {} at {} = {:.12g} was not switched at (period {} above "
                                       "--max-period {})",
                                       index, bif.kind, out_.param, bif.value, switched_period, req_.max_period));
      continue;
    }
    if (seeding_ && static_cast<int>(out_.branches.size()) + 2 + reserve_ > req_.max_branches) {
      deferred_.emplace_back(stored, at);  // the room is kept for the seeds still to come
      return;
    }
    if (Full()) {
      NoteFull();
      ++out_.switches_left_out;
      out_.notes.push_back(fmt::format("branch {}: the {} at {} = {:.12g} was not switched at: --max-branches {} "
                                       "reached",
                                       index, bif.kind, out_.param, bif.value, req_.max_branches));
      continue;
    }
    const auto t0 = std::chrono::steady_clock::now();
    const auto& pts = b.branch.points;
    // The point next to it: on a segment around its λ across which a real multiplier crosses +1
    // (branch point) or −1 (flip), the nearer end (a branch that folds may pass its λ on several
    // sheets); the point nearest in λ if no segment shows the crossing.
    const double target = bif.kind == "flip" ? -1.0 : 1.0;
    const auto beyond = [&](const BranchPoint& p) {
      int n = 0;
      for (const auto& m : p.multipliers)
        if (std::abs(m.imag()) <= 1e-9 * std::max(1.0, std::abs(m)) && (m.real() - target) * target > 0) ++n;
      return n;
    };
    auto near = std::min_element(pts.begin(), pts.end(), [&](const BranchPoint& x, const BranchPoint& y) {
      return std::abs(x.value - bif.value) < std::abs(y.value - bif.value);
    });
    double gap = kInf;
    for (size_t i = 0; i + 1 < pts.size(); ++i) {
      const double lo = std::min(pts[i].value, pts[i + 1].value), hi = std::max(pts[i].value, pts[i + 1].value);
      if (bif.value < lo - slack_ || bif.value > hi + slack_ || beyond(pts[i]) == beyond(pts[i + 1])) continue;
      const size_t k = std::abs(pts[i].value - bif.value) <= std::abs(pts[i + 1].value - bif.value) ? i : i + 1;
      if (std::abs(pts[k].value - bif.value) < gap) gap = std::abs(pts[k].value - bif.value), near = pts.begin() + static_cast<std::ptrdiff_t>(k);
    }
    SwitchRequest s;
    s.scene_at = req_.scene_at;
    s.kind = bif.kind;
    s.value = bif.value;
    s.from_value = near->value;
    s.section_time = near->section_time;
    s.X = near->X;
    s.V = near->V;
    s.period = b.branch.period;
    s.stop_requested = req_.stop_requested;
    const SwitchResult r = SwitchBranch(s);
    out_.switching_seconds += Seconds(t0);
    if (Stopped()) return;
    if (!r.ok) {
      out_.notes.push_back(fmt::format("branch {}: no other branch found at the {} at {} = {:.12g}: {}", index,
                                       bif.kind, out_.param, bif.value, r.message));
      continue;
    }
    for (const auto& half : r.starts) {
      const double to = half.direction > 0 ? hi_ : lo_;
      if (std::abs(to - half.value) <= slack_) continue;
      OrbitRequest o;
      o.kind = OrbitKind::kAuto;
      o.period = half.period;
      o.transient_periods = 0;
      o.start = InitialOverride{half.section_time, half.X, half.V};
      const auto t1 = std::chrono::steady_clock::now();
      DiagramBranch child;
      child.branch = Follow(half.value, to, o);
      out_.continuation_seconds += Seconds(t1);
      if (Stopped() || child.branch.status == "interrupted") return;
      child.origin = bif.kind;
      child.parent = index;
      child.born_at = r.located;
      child.end_first = fmt::format("born at the {} of branch {} at {} = {:.15g}", bif.kind, index, out_.param,
                                    r.located);
      child.end_last = child.branch.end;
      if (child.branch.status == "no-orbit") {
        out_.notes.push_back(fmt::format("branch {}: the half of the {} at {} = {:.12g} could not be continued: {}",
                                         index, bif.kind, out_.param, r.located, child.branch.end));
        continue;
      }
      Add(std::move(child));
    }
  }
}

void Builder::Seed(double lambda, const Attractor& a, const Eigen::VectorXd& X, const Eigen::VectorXd& V,
                   const std::string& source) {
  // Every periodic attractor is a seed, whatever its period (up to the run.max_period its
  // classification tried): --max-period bounds only the switching.
  if (a.kind == "not-periodic" || !a.period || X.size() == 0) return;
  std::string reason;
  const auto t0 = std::chrono::steady_clock::now();
  const bool covered = CoveredBy(lambda, a, reason).first >= 0;
  out_.coverage_seconds += Seconds(t0);
  if (covered) return;
  if (Full()) {
    NoteFull();
    ++out_.seeds_left_out;
    out_.notes.push_back(fmt::format("the {} attractor (period {}) of the {} at {} = {:.12g} was not continued: "
                                     "--max-branches {} reached",
                                     a.kind, *a.period, source, out_.param, lambda, req_.max_branches));
    seed_outcomes_.push_back(
        {lambda, *a.period, fmt::format("its seed was not continued: --max-branches {} reached", req_.max_branches)});
    return;
  }
  ++out_.seeds_tried;
  const Scene scene = req_.scene_at(lambda);
  OrbitRequest o;
  o.kind = OrbitKind::kAuto;
  o.period = *a.period;
  o.transient_periods = 0;
  o.start = InitialOverride{scene.initial_time, X, V};
  const auto t1 = std::chrono::steady_clock::now();
  Branch down, up;
  const bool has_down = lambda - lo_ > slack_, has_up = hi_ - lambda > slack_;
  if (has_down) down = Follow(lambda, lo_, o);
  if (!Stopped() && has_up) up = Follow(lambda, hi_, o);
  out_.continuation_seconds += Seconds(t1);
  if (Stopped() || down.status == "interrupted" || up.status == "interrupted") return;
  if ((has_down && down.status == "no-orbit") || (has_up && up.status == "no-orbit")) {
    out_.notes.push_back(fmt::format("the {} attractor of the {} at {} = {:.12g} gave no orbit: {}", a.kind, source,
                                     out_.param, lambda, (has_down ? down : up).end));
    seed_outcomes_.push_back({lambda, *a.period, "its seed gave no orbit: " + (has_down ? down : up).end});
    return;
  }
  DiagramBranch n;
  n.origin = "seed";
  n.born_at = lambda;
  Branch& br = n.branch;
  br.param = out_.param;
  br.period = has_up ? up.period : down.period;
  br.status = "ok";
  // The points in order along the branch: the way down reversed, then the way up (its first
  // point, the seed's orbit, is the way down's first).
  for (auto it = down.points.rbegin(); it != down.points.rend(); ++it) br.points.push_back(*it);
  for (size_t i = has_down && !down.points.empty() ? 1 : 0; i < up.points.size(); ++i) br.points.push_back(up.points[i]);
  const long long seed_at = has_down && !down.points.empty() ? static_cast<long long>(down.points.size()) - 1 : 0;
  for (const Branch* h : {&down, &up}) {
    for (Bifurcation b : h->bifurcations) {  // Bifurcation::point in the joined points
      if (b.point >= 0) b.point = h == &down ? seed_at - b.point : seed_at + b.point;
      br.bifurcations.push_back(std::move(b));
    }
    br.relabels.insert(br.relabels.end(), h->relabels.begin(), h->relabels.end());
    br.crossings.insert(br.crossings.end(), h->crossings.begin(), h->crossings.end());
    br.quad_evaluations += h->quad_evaluations;
  }
  std::sort(br.bifurcations.begin(), br.bifurcations.end(),
            [](const Bifurcation& x, const Bifurcation& y) { return x.value < y.value; });
  n.end_first = has_down ? down.end : "the seed lies at the end of the range";
  n.end_last = has_up ? up.end : "the seed lies at the end of the range";
  br.end = fmt::format("towards {:.12g}: {}; towards {:.12g}: {}", lo_, n.end_first, hi_, n.end_last);
  const size_t birth = has_down && !down.points.empty() ? down.points.size() - 1 : 0;
  Add(std::move(n), birth);
  if (!not_stored_.empty()) seed_outcomes_.push_back({lambda, *a.period, "its seed was continued, but " + not_stored_});
}

DiagramResult Builder::Run() {
  out_.param = req_.param;
  out_.from = req_.from;
  out_.to = req_.to;
  // 1. The sweep, up and down.
  auto t0 = std::chrono::steady_clock::now();
  Progress("sweep");
  SweepRequest sw;
  sw.scene_at = req_.scene_at;
  sw.from = req_.from;
  sw.to = req_.to;
  sw.steps = req_.sweep_steps;
  sw.record = req_.record;
  sw.both_ways = true;
  out_.sweep = Sweep(sw, req_.stop_requested);
  out_.sweep_seconds = Seconds(t0);
  // 2. Attractor searches: a grid of starts over the sweep's range of (x_B, ẋ_B), widened.
  struct Found {
    double value;
    Attractor attractor;
    Eigen::VectorXd X, V;
  };
  std::vector<Found> searched;
  t0 = std::chrono::steady_clock::now();
  if (req_.searches > 0 && !Stopped()) {
    Progress("search");
    double xmin = kInf, xmax = -kInf, vmin = kInf, vmax = -kInf;
    for (const auto& p : out_.sweep) {
      for (double x : p.x_B) xmin = std::min(xmin, x), xmax = std::max(xmax, x);
      for (double v : p.v_B) vmin = std::min(vmin, v), vmax = std::max(vmax, v);
    }
    if (!std::isfinite(xmin)) xmin = -1, xmax = 1, vmin = -1, vmax = 1;
    const double mx = 0.25 * std::max(xmax - xmin, 1e-3), mv = 0.25 * std::max(vmax - vmin, 1e-3);
    const Coordinate cx{"x_B", xmin - mx, xmax + mx}, cv{"v_B", vmin - mv, vmax + mv};
    const auto grid = GridPoints(cx, cv, req_.search_grid, req_.search_grid);
    std::vector<size_t> all(grid.size());
    for (size_t i = 0; i < all.size(); ++i) all[i] = i;
    for (int j = 0; j < req_.searches && !Stopped(); ++j) {
      const double lambda = req_.from + (req_.to - req_.from) * (j + 0.5) / req_.searches;
      const Scene scene = req_.scene_at(lambda);
      const System sys(scene);
      StudyOptions so;
      so.threads = req_.threads;
      so.stop_requested = req_.stop_requested;
      so.lyapunov = false;
      std::vector<CellResult> cells(grid.size());
      RunCells(sys, scene, cx, cv, grid, all, cells, so);
      if (Stopped()) break;
      const StudyResult st = LabelCells(sys, scene, grid, cells, so);
      for (size_t k = 0; k < st.attractors.size(); ++k)
        for (size_t i = 0; i < st.labels.size(); ++i)
          if (st.labels[i] == static_cast<int>(k) && cells[i].z.size() > 0) {
            const auto n = cells[i].z.size() / 2;
            searched.push_back({lambda, cells[i].attractor, cells[i].z.head(n), cells[i].z.tail(n)});
            break;
          }
    }
  }
  out_.search_seconds = Seconds(t0);
  // 3. Seeds, in order: the sweep's attractors, then the searches'; each seed's branch is
  // switched at as soon as it is stored while the cap leaves room for the seeds still to come.
  Progress("continuation");
  const auto candidate = [](const Attractor& a, const Eigen::VectorXd& X) {
    return a.kind != "not-periodic" && a.period && X.size() > 0;
  };
  reserve_ = 0;
  for (const auto& p : out_.sweep) reserve_ += p.status == "ok" && candidate(p.attractor, p.X) ? 1 : 0;
  for (const auto& f : searched) reserve_ += candidate(f.attractor, f.X) ? 1 : 0;
  for (const auto& p : out_.sweep) {
    if (Stopped()) break;
    if (p.status != "ok") continue;
    if (candidate(p.attractor, p.X)) --reserve_;
    Seed(p.value, p.attractor, p.X, p.V, p.upward ? "sweep up" : "sweep down");
  }
  for (const auto& f : searched) {
    if (Stopped()) break;
    if (candidate(f.attractor, f.X)) --reserve_;
    Seed(f.value, f.attractor, f.X, f.V, "search");
  }
  // 4. The switches deferred to keep room for the seeds, then those of the branches they give,
  // breadth first, up to the cap.
  seeding_ = false;
  reserve_ = 0;
  while (!deferred_.empty() && !Stopped()) {
    const auto [k, first] = deferred_.front();
    deferred_.pop_front();
    SwitchAt(k, first);
  }
  // 5. Coverage of every attractor of the sweep and of the searches.
  t0 = std::chrono::steady_clock::now();
  Progress("coverage");
  const auto cover = [&](double value, bool upward, const Attractor& a, const std::string& status) {
    CoverageEntry c;
    c.value = value;
    c.upward = upward;
    c.source = upward ? "sweep up" : "sweep down";
    c.kind = status == "ok" ? a.kind : "failed";
    c.period = a.period.value_or(0);
    if (status != "ok") {
      c.reason = "the sweep's run failed here (" + status + ")";
    } else {
      const auto [k, d] = CoveredBy(value, a, c.reason);
      c.branch = k;
      c.distance = d;
      if (k >= 0) c.reason.clear();
    }
    out_.coverage.push_back(std::move(c));
  };
  for (const auto& p : out_.sweep) {
    if (Stopped()) break;
    cover(p.value, p.upward, p.attractor, p.status);
  }
  for (const auto& f : searched) {
    if (Stopped()) break;
    cover(f.value, true, f.attractor, "ok");
    out_.coverage.back().source = "search";
  }
  out_.coverage_seconds += Seconds(t0);
  out_.uncovered_windows = UncoveredWindows(out_.coverage);
  if (Stopped()) out_.status = "interrupted";
  return std::move(out_);
}

}  // namespace

DiagramResult Diagram(const DiagramRequest& request) {
  Builder b(request);
  return b.Run();
}

}  // namespace vibro
