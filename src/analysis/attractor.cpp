// Attractor classification from the stroboscopic section and the event log.
#include "vibro/attractor.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <tuple>

namespace vibro {

AttractorRecorder::AttractorRecorder(const System& system, const Scene& scene)
    : sys_(system),
      phase0_(std::fmod(system.frequency() * scene.initial_time, 2.0 * M_PI)),
      max_period_(scene.run.max_period),
      tolerance_(scene.run.period_tolerance) {}

void AttractorRecorder::OnEvent(const Event& e) {
  if (events_.size() >= max_events_) {
    // The oldest event goes, and every section point that begins a window holding it: a window
    // (k·T, …] starting at a kept point k > period of the dropped event has all its events.
    const long long dropped = events_.front().clock.period;
    events_.pop_front();
    ++events_dropped_;
    while (!sections_.empty() && sections_.front().k <= dropped) sections_.pop_front();
  }
  events_.push_back(e);
}

void AttractorRecorder::OnSection(const Sample& s) {
  const auto keep = static_cast<size_t>(4 * max_period_ + 2);  // four windows of the longest period
  Eigen::VectorXd z;
  if (sections_.size() >= keep) {  // the oldest point's storage is reused: no allocation per period
    z = std::move(sections_.front().z);
    sections_.pop_front();
  }
  z.resize(2 * s.X.size());
  z << s.X, s.V;
  const double amax = z.cwiseAbs().maxCoeff();
  int held = s.held;
  if (held < 0) {
    // Not known (a section read back from a file to resume): the contacts at zero gap and zero gap
    // velocity within 1e-9 of their scale, at least one when sticking.
    held = 0;
    for (const ContactModel& c : sys_.contacts()) {
      const double scale = 1.0 + std::abs(c.stop) + c.shape.cwiseProduct(s.X).cwiseAbs().sum();
      if (std::abs(c.shape.dot(s.X) - c.stop) <= 1e-9 * scale &&
          std::abs(c.shape.dot(s.V)) <= 1e-9 * (1.0 + c.shape.cwiseProduct(s.V).cwiseAbs().sum()))
        ++held;
    }
    if (s.mode == Mode::kSticking) held = std::max(held, 1);
  }
  sections_.push_back({s.clock.period, std::move(z), amax, s.mode, held});
  while (sections_.size() > keep) sections_.pop_front();
  const long long oldest = sections_.front().k;
  while (!events_.empty() && events_.front().clock.period < oldest - 1) events_.pop_front();

  // The ring of section points for the recurrence search: only when it can see further than
  // max_period (three windows of a period beyond it).
  if (max_period_ >= kRecurrenceMax) return;
  const auto m = static_cast<size_t>(sections_.back().z.size());
  const size_t capacity = 3 * static_cast<size_t>(kRecurrenceMax) + 1;
  if (ring_mode_.size() < capacity) {
    ring_.insert(ring_.end(), sections_.back().z.data(), sections_.back().z.data() + m);
    ring_mode_.push_back(s.mode);
  } else {
    std::copy(sections_.back().z.data(), sections_.back().z.data() + m, ring_.begin() + static_cast<long>(ring_next_ * m));
    ring_mode_[ring_next_] = s.mode;
    ring_next_ = (ring_next_ + 1) % capacity;
  }
}

void AttractorRecorder::FindRecurrence(Attractor& a) const {
  const size_t n = ring_mode_.size();
  if (n == 0) return;
  const size_t m = ring_.size() / n;
  // Section point j periods before the last one (j < n).
  const auto at = [&](size_t j) { return (ring_next_ + n - 1 - j) % n; };
  const auto distance = [&](size_t i, size_t j) {  // relative, as Difference
    const size_t a_ = at(i), b = at(j);
    if (ring_mode_[a_] != ring_mode_[b]) return std::numeric_limits<double>::infinity();
    double d = 0, amax = 0;
    for (size_t k = 0; k < m; ++k) {
      const double x = ring_[a_ * m + k], y = ring_[b * m + k];
      d = std::max(d, std::abs(x - y));
      amax = std::max({amax, std::abs(x), std::abs(y)});
    }
    return d / (1.0 + amax);
  };
  const int first = *a.searched_period + 1;
  for (int p = first; p <= kRecurrenceMax && 3 * static_cast<size_t>(p) < n; ++p) {
    const auto q = static_cast<size_t>(p);
    if (!(distance(0, q) <= tolerance_)) continue;  // cheap rejection of most p
    // The last two windows each repeat the window before (2p differences), without a decaying
    // transient (the rule of Classify on two windows).
    double d[2] = {0, 0};
    for (size_t w = 0; w < 2 && d[0] <= tolerance_; ++w)
      for (size_t j = 0; j < q && d[w] <= tolerance_; ++j) d[w] = std::max(d[w], distance(j + w * q, j + (w + 1) * q));
    if (!(d[0] <= tolerance_ && d[1] <= tolerance_)) continue;
    if (d[0] < d[1] && d[0] > 1e-3 * tolerance_) {
      const double l = d[0] / d[1];
      if (d[0] * l / (1 - l) > tolerance_) continue;
    }
    a.recurrence_period = p;
    a.recurrence_distance = std::max(d[0], d[1]);
    return;
  }
}

double AttractorRecorder::Phase(const Clock& c, int p) const {
  const double whole = 2.0 * M_PI * static_cast<double>(c.period % p);
  double ph = std::fmod(phase0_ + sys_.frequency() * c.offset + whole, 2.0 * M_PI * p);
  if (ph < 0) ph += 2.0 * M_PI * p;
  return ph;
}

inline double AttractorRecorder::Difference(size_t i, size_t j) const {
  const Section& x = sections_[i];
  const Section& y = sections_[j];
  if (x.mode != y.mode) return std::numeric_limits<double>::infinity();
  // At every section point once the points repeat (Settled): a plain loop, the scales cached.
  double d = 0.0;
  for (Eigen::Index k = 0; k < x.z.size(); ++k) d = std::max(d, std::abs(x.z[k] - y.z[k]));
  return d / (1.0 + std::max(x.amax, y.amax));
}

bool AttractorRecorder::Settled(double remainder) const {
  const size_t n = sections_.size();
  // The decay test of a candidate period p: the differences δ1, δ2 of the last two windows of p
  // section points vanish or fall geometrically to a remaining distance below `remainder`.
  const auto decayed = [&](size_t p) {
    double d1 = 0, d2 = 0;
    for (size_t j = 0; j < p; ++j) {
      d1 = std::max(d1, Difference(n - 1 - j, n - 1 - j - p));
      d2 = std::max(d2, Difference(n - 1 - j - p, n - 1 - j - 2 * p));
    }
    if (d1 == 0) return true;  // repeats to the bit (1-DOF sticking orbits)
    if (!(d2 > 0)) return false;
    const double lambda = d1 / d2;
    return lambda < 0.95 && d1 * lambda / (1 - lambda) <= remainder;
  };
  // Cheap test first, on every p the classification could return (its last section point repeats
  // within the tolerance, relaxed by rounding): unless one of them has decayed, the full
  // classification (a quarter of a basin's work when it ran at every period) cannot say settled.
  bool candidate = false;
  for (size_t p = 1; p <= static_cast<size_t>(max_period_) && 3 * p < n && !candidate; ++p)
    candidate = Difference(n - 1, n - 1 - p) <= tolerance_ * (1 + 1e-9) && decayed(p);
  if (!candidate) return false;
  const Attractor a = ClassifyRecord(false);
  if (!a.period) return false;
  const auto p = static_cast<size_t>(*a.period);
  if (3 * p >= n) return false;  // two windows of differences needed
  return decayed(p);
}

Attractor AttractorRecorder::Classify() const { return ClassifyRecord(true); }

Attractor AttractorRecorder::ClassifyRecord(bool check_decay) const {
  Attractor a;
  if (sections_.size() < 2) return a;
  const size_t n = sections_.size();
  const long long K = sections_.back().k;
  const double T = sys_.period(), w = sys_.frequency();
  const auto close = [&](const Section& x, const Section& y) {
    if (x.mode != y.mode) return false;
    const double scale = 1.0 + std::max(x.amax, y.amax);
    return (x.z - y.z).cwiseAbs().maxCoeff() <= tolerance_ * scale;
  };
  const auto in_window = [&](const Event& e, long long from, long long to) {
    // events with from·T < t ≤ to·T (period boundaries are section times)
    if (e.clock.period < from || e.clock.period > to) return false;
    if (e.clock.period == from && e.clock.offset == 0.0) return false;
    if (e.clock.period == to && e.clock.offset > 0.0) return false;
    return true;
  };
  // Calls f on the events in the window, in order. The events are in time order: the window's
  // first one is found by bisection (a chattering record holds thousands of events, and the
  // checks below look at windows of every period p up to max_period).
  const auto each_in = [&](long long from, long long to, const auto& f) {
    auto it = std::partition_point(events_.begin(), events_.end(),
                                   [&](const Event& e) { return e.clock.period < from; });
    for (; it != events_.end() && it->clock.period <= to; ++it)
      if (in_window(*it, from, to)) f(*it);
  };
  // Event counts by kind, per period of the record, as prefix sums: the period checks below
  // count events in windows of every p up to max_period, several kinds each, and a chattering
  // record holds thousands of events. An event at time t belongs to the period slot j with
  // jT < t ≤ (j + 1)T (so that a window (from·T, to·T] is the slots from … to − 1, as in_window);
  // built on the first count, as most calls during a transient never count.
  const long long lo = sections_.front().k - 2;  // no event kept lies in an earlier slot
  std::vector<std::array<long long, 6>> prefix;  // prefix[i][kind]: events in slots lo … lo + i − 1
  const auto count = [&](EventKind kind, long long from, long long to) {
    if (prefix.empty()) {
      prefix.assign(static_cast<size_t>(K - lo) + 1, {0, 0, 0, 0, 0, 0});
      for (const Event& e : events_) {
        const long long slot = e.clock.offset > 0.0 ? e.clock.period : e.clock.period - 1;
        if (slot < lo || slot >= K) continue;
        ++prefix[static_cast<size_t>(slot - lo) + 1][static_cast<size_t>(e.kind)];
      }
      for (size_t i = 1; i < prefix.size(); ++i)
        for (size_t k = 0; k < 6; ++k) prefix[i][k] += prefix[i - 1][k];
    }
    const auto at = [&](long long j) { return static_cast<size_t>(std::clamp(j, lo, K) - lo); };
    const auto k = static_cast<size_t>(kind);
    return prefix[at(to)][k] - prefix[at(from)][k];
  };

  // The stick and release times of two consecutive windows of p periods must repeat too: during
  // a sticking phase that erases the memory of the flight, the section points of a period-2
  // motion can coincide.
  const auto same_timing = [&](int p) {
    for (EventKind kind : {EventKind::kStick, EventKind::kRelease}) {
      std::vector<double> last, before;
      each_in(K - 2 * p, K, [&](const Event& e) {
        if (e.kind != kind) return;
        if (in_window(e, K - p, K))
          last.push_back(static_cast<double>(e.clock.period - (K - p)) * T + e.clock.offset);
        else if (in_window(e, K - 2 * p, K - p))
          before.push_back(static_cast<double>(e.clock.period - (K - 2 * p)) * T + e.clock.offset);
      });
      if (last.size() != before.size()) return false;
      for (size_t i = 0; i < last.size(); ++i)
        if (std::abs(last[i] - before[i]) > 10.0 * tolerance_ * T) return false;
    }
    return true;
  };
  // The event log of the last S = max(3p, max_period) periods recorded must be p-periodic: the
  // kinds and order of the events in (K − S, K − p] are those in (K − S + p, K] (impacts left out
  // when the span chatters). A motion that sticks every 7 periods is not period 1 because its
  // last two periods look alike. On a short record (a study cell stopped early, a sweep's run of
  // a few dozen periods) S is all of it but its first period (where the run's start, not the
  // orbit, set the events), and at least 3p: the same span for every p, so that a long period
  // wins nothing there.
  const auto log_repeats = [&](int p) {
    const long long recorded = static_cast<long long>(n) - 1;
    const long long span =
        std::max<long long>(3 * p, std::min<long long>(max_period_, recorded - 1));
    const bool chatters = count(EventKind::kAccumulation, K - span, K) > 0;
    // The two logs compared event by event (no copies: a chattering span is long).
    const auto first = [&](long long from) {
      return std::partition_point(events_.begin(), events_.end(),
                                  [&](const Event& e) { return e.clock.period < from; });
    };
    const auto next = [&](auto it, long long from, long long to) {
      for (; it != events_.end() && it->clock.period <= to; ++it)
        if (in_window(*it, from, to) && !(chatters && it->kind == EventKind::kImpact)) return it;
      return events_.end();
    };
    auto u = next(first(K - span), K - span, K - p);
    auto v = next(first(K - span + p), K - span + p, K);
    for (; u != events_.end() && v != events_.end();
         u = next(u + 1, K - span, K - p), v = next(v + 1, K - span + p, K))
      if (u->kind != v->kind) return false;
    return u == events_.end() && v == events_.end();
  };
  // Section points repeating within the tolerance are not enough: a decaying transient can
  // repeat within it by aliasing (a free oscillation whose phase returns after p periods while
  // it decays by 4 % a period). With the repeat distances δ1, δ2, δ3 of the last three windows
  // (Difference): when they fall geometrically (δ1 < δ2 < δ3 with δ1/δ2 and δ2/δ3 within 10 %),
  // a transient is still there, and the distance left to the orbit, about δ1·λ/(1 − λ) with
  // λ = δ1/δ2, must be within the tolerance too. Repeat distances that do not fall geometrically
  // are the rounding floor of a periodic orbit.
  // On a record of only two windows of differences (3p + 1 section points), δ1 < δ2 cannot tell
  // a geometric fall from rounding noise: the distance left, δ1·λ/(1 − λ), must then be within
  // the tolerance whenever δ1 is above the rounding floor (10⁻³ of the tolerance).
  const auto decayed = [&](int p) {
    const auto q = static_cast<size_t>(p);
    const size_t windows = std::min<size_t>(3, (n - 1) / q - 1);  // 2 or 3 (3p + 1 ≤ n)
    double d[3] = {0, 0, 0};
    for (size_t win = 0; win < windows; ++win)
      for (size_t j = 0; j < q; ++j)
        d[win] = std::max(d[win], Difference(n - 1 - j - win * q, n - 1 - j - (win + 1) * q));
    if (!(d[0] < d[1])) return true;
    const double l1 = d[0] / d[1];
    if (windows == 3) {
      if (!(d[1] < d[2])) return true;
      const double l2 = d[1] / d[2];
      if (std::abs(l1 - l2) > 0.1 * l2) return true;
    } else if (d[0] <= 1e-3 * tolerance_) {
      return true;
    }
    return d[0] * l1 / (1 - l1) <= tolerance_;
  };
  int period = 0;
  // A period p is accepted only on a record of at least three windows of it (3p + 1 section
  // points): two to see the points repeat and one more to see the transient has decayed.
  for (int p = 1; p <= max_period_ && static_cast<size_t>(3 * p) < n; ++p) {
    bool ok = true;
    for (int j = 0; j < p && ok; ++j) ok = close(sections_[n - 1 - j], sections_[n - 1 - j - p]);
    for (EventKind kind : {EventKind::kStick, EventKind::kRelease, EventKind::kAccumulation})
      ok = ok && count(kind, K - p, K) == count(kind, K - 2 * p, K - p);
    // Impacts are counted only without chattering: how many impacts of a sequence are followed
    // before its accumulation point is predicted is a numerical choice, not part of the orbit.
    if (count(EventKind::kAccumulation, K - p, K) == 0)
      ok = ok && count(EventKind::kImpact, K - p, K) == count(EventKind::kImpact, K - 2 * p, K - p);
    ok = ok && same_timing(p) && log_repeats(p);
    // A period whose points and events repeat while its transient has not decayed: the motion is
    // not periodic yet, and no multiple of p may be accepted instead (its repeat distances can
    // alias smaller than p's, as in the decaying free transient above). The decay is judged on
    // every record, however short (three windows of p at least, see above).
    if (ok && check_decay && !decayed(p)) break;
    if (ok) {
      period = p;
      break;
    }
  }
  // Settled asks only for a period: without one, the whole-record averages below (a pass over
  // every event with a phase each) would be most of a study's classification work.
  if (period == 0 && !check_decay) return a;

  const bool multi = sys_.contact_count() > 1;
  // Sticking phases: each release in the window closes one phase; its start is the last stick
  // before it. The window is p periods (the whole record without a period).
  const int p = period > 0 ? period : static_cast<int>(n) - 1;
  const long long from = K - p;
  // Each release closes the phase of its own contact (several contacts may stick in turn).
  std::vector<std::tuple<double, double, int>> phases;  // start, end, contact
  std::map<int, const Event*> last_stick;
  double per_orbit = 0.0;  // periodic: the durations of the phases released in the window
  for (const auto& e : events_) {
    if (e.kind == EventKind::kStick) last_stick[e.contact] = &e;
    const auto open = last_stick.find(e.contact);
    if (e.kind == EventKind::kRelease && in_window(e, from, K) && open != last_stick.end() && open->second) {
      const Event& stick = *open->second;
      const double duration = (static_cast<double>(e.clock.period - stick.clock.period) * T +
                               e.clock.offset - stick.clock.offset);
      const double start = Phase(stick.clock, p);
      phases.emplace_back(start, start + w * duration, e.contact);
      per_orbit += duration;
      open->second = nullptr;
    }
  }
  std::sort(phases.begin(), phases.end());
  // Without a period, the time on the stop is the measure of the sticking intervals inside the
  // window [K − p, K] (the whole record), an average over whole periods: a phase begun before the
  // window (the section point at its start is on the stop) or still running at its end (the last
  // one is) is cut at the window's edges. The intervals alternate stick → release, so the
  // fraction is in [0, 1] by construction. With a period p it is the same measure for an orbit
  // that repeats exactly; the durations of the phases released in the window are used (the
  // classification accepted p only when their stick and release times repeat), and a sum
  // outside [0, pT] would mean the period is wrong: the motion is then not periodic.
  const auto since_from = [&](const Clock& c) {
    return std::clamp(static_cast<double>(c.period - from) * T + c.offset, 0.0, p * T);
  };
  double stuck = 0.0, open_since = 0.0;
  const Section& first = sections_[n - 1 - static_cast<size_t>(p)];
  bool open = first.mode == Mode::kSticking;
  // Several contacts: the time with at least one contact held (docs/output.md), counted by how many
  // are held: the section point says how many at the window's start, each stick adds one and each
  // release (a liftoff too) takes one away; the phases of different contacts overlap, and a contact
  // held throughout has neither (issue 37's scene F: contact 0 held all along, fraction 1).
  int held = open ? std::max(first.held, 1) : 0;
  for (const auto& e : events_) {
    const bool at_start = e.clock.period == from && e.clock.offset == 0.0;  // after the section point
    if (!at_start && !in_window(e, from, K)) continue;
    if (multi) {
      if (e.kind == EventKind::kStick && held++ == 0) {
        open_since = since_from(e.clock);
      } else if (e.kind == EventKind::kRelease && held > 0 && --held == 0) {
        stuck += since_from(e.clock) - open_since;
      }
      continue;
    }
    if (e.kind == EventKind::kStick && !open) {
      open = true;
      open_since = since_from(e.clock);
    } else if (e.kind == EventKind::kRelease && open) {
      open = false;
      stuck += since_from(e.clock) - open_since;
    }
  }
  if (multi ? held > 0 : open) stuck += p * T - open_since;
  stuck = std::min(stuck, p * T);  // rounding of the sum
  if (period > 0 && !multi) {
    // Rounding (1e-12 of the window) aside, per_orbit is in [0, pT] for a true period.
    if (per_orbit < -1e-12 * p * T || per_orbit > (1 + 1e-12) * p * T) {
      Attractor none;
      none.sticking_fraction = stuck / (p * T);
      none.searched_period = std::min<int>(max_period_, static_cast<int>((n - 1) / 3));
      return none;  // not periodic: a period-p window cannot hold more than pT on the stop
    }
    stuck = std::clamp(per_orbit, 0.0, p * T);
  }
  const bool released = !phases.empty();
  const bool always_stuck = !released && sections_.back().mode == Mode::kSticking &&
                            count(EventKind::kImpact, from, K) == 0 &&
                            std::all_of(sections_.end() - p - 1, sections_.end(),
                                        [](const Section& s) { return s.mode == Mode::kSticking; });
  if (period == 0) {
    a.kind = "not-periodic";
    a.sticking_fraction = always_stuck ? 1.0 : stuck / (p * T);
    a.contact_fraction = sys_.contact_count() > 0 &&
                         std::all_of(sys_.contacts().begin(), sys_.contacts().end(),
                                     [](const auto& c) { return c.spec.compliance.compliant(); });
    // The periods tried: up to max_period, on a record long enough for three windows of each.
    a.searched_period = std::min<int>(max_period_, static_cast<int>((n - 1) / 3));
    FindRecurrence(a);
    return a;
  }
  a.period = period;
  const long long impacts = count(EventKind::kImpact, from, K);
  const long long accumulations = count(EventKind::kAccumulation, from, K);
  if (always_stuck) {
    a.kind = "permanent-contact";
    a.sticking_fraction = 1.0;
    a.impacts_per_period = 0;
    return a;
  }
  a.sticking_fraction = stuck / (period * T);
  for (const auto& [start, end, contact] : phases) {
    a.stick_phases.emplace_back(start, end);
    a.stick_contacts.push_back(contact);
  }
  if (accumulations == 0) a.impacts_per_period = impacts;
  // Every held phase a compliant stop's contact phase: no sticking (docs/compliant.md).
  const bool compliant_only = std::all_of(phases.begin(), phases.end(), [&](const auto& ph) {
    const int c = std::get<2>(ph);
    return c >= 0 && c < sys_.contact_count() && sys_.contacts()[static_cast<size_t>(c)].spec.compliance.compliant();
  });
  if (released)
    a.kind = compliant_only ? "contact-periodic" : "sticking-periodic";
  else if (impacts > 0)
    a.kind = "impact-periodic";
  else
    a.kind = "no-contact-periodic";
  if (a.kind == "impact-periodic") {
    for (const auto& e : events_) {
      if (e.kind != EventKind::kImpact || !in_window(e, from, K)) continue;
      a.impact_phases.push_back(Phase(e.clock, period));
      a.impact_velocities.push_back(e.v_before);
      a.impact_contacts.push_back(e.contact);
    }
  }
  return a;
}

}  // namespace vibro
