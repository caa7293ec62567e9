// The event signature and the non-smooth test quantities of a periodic orbit (orbit_probe.hpp).
#include "analysis/orbit_probe.hpp"

#include <algorithm>
#include <cmath>

#include "vibro/observer.hpp"
#include "vibro/simulator.hpp"

namespace vibro {
namespace {

struct Recorded {
  struct Ev {
    EventKind kind;
    double offset;  // time since t0
    double speed;   // |ẋ_B⁻|
  };
  struct Smp {
    double offset, gap, v_B, R;
    Mode mode;
    Eigen::VectorXd X, V;
  };
  std::vector<Ev> events;
  std::vector<Smp> samples;
  std::vector<double> entry_reactions;
};

class Recorder final : public Observer {
 public:
  Recorder(const System& sys, double T, Recorded& out) : sys_(sys), T_(T), out_(out) {}
  void OnEvent(const Event& e) override {
    out_.events.push_back({e.kind, Offset(e.clock), std::abs(e.v_before)});
  }
  void OnSample(const Sample& s) override {
    const double phase = sys_.frequency() * s.t;
    out_.samples.push_back({Offset(s.clock), s.x_B - sys_.stop(), sys_.ContactVelocity(s.V),
                            s.mode == Mode::kSticking ? sys_.Reaction(s.X, s.V, phase) : 0.0,
                            s.mode, s.X, s.V});
  }
  void OnReset(const Reset& r) override {
    if (r.kind == ResetKind::kPlasticStick)
      out_.entry_reactions.push_back(sys_.Reaction(r.X_after, r.V_after, r.phase));
    else if (r.kind == ResetKind::kAccumulation)
      out_.entry_reactions.push_back(
          sys_.Reaction(r.X_after, r.V_after, r.phase + sys_.frequency() * r.delta));
  }

 private:
  double Offset(const Clock& c) const { return static_cast<double>(c.period) * T_ + c.offset; }
  const System& sys_;
  double T_;
  Recorded& out_;
};

// The lexicographically smallest rotation: signatures do not depend on where the section is.
std::string Canonical(const std::string& s) {
  std::string best = s;
  for (size_t i = 1; i < s.size(); ++i) best = std::min(best, s.substr(i) + s.substr(0, i));
  return best;
}

// The signature with the isolated impacts just before a chattering sequence merged into it.
std::string Coarse(std::string s) {
  for (bool merged = true; merged && s.size() > 1;) {
    merged = false;
    for (size_t i = 0; i < s.size(); ++i)
      if (s[i] == 'I' && s[(i + 1) % s.size()] == 'C') {
        s.erase(i, 1);
        merged = true;
        break;
      }
  }
  return Canonical(s);
}

// Minimum of the parabola through three equally spaced values with y1 the smallest.
double ParabolaMin(double y0, double y1, double y2) {
  const double curvature = y2 - 2.0 * y1 + y0;
  return curvature > 0 ? y1 - (y2 - y0) * (y2 - y0) / (8.0 * curvature) : y1;
}

}  // namespace

OrbitProbe ProbeOrbit(const System& sys, const Scene& scene, double t0, const Eigen::VectorXd& X,
                      const Eigen::VectorXd& V, int q, int samples) {
  OrbitProbe p;
  const double T = sys.period(), span = q * T;
  Scene sc = scene;
  sc.run.periods = q;
  sc.run.samples_per_period = samples;
  Recorded rec;
  Recorder observer(sys, T, rec);
  const InitialOverride init{t0, X, V};
  SimulationOptions opt;
  opt.initial = &init;
  opt.observers = {&observer};
  if (Simulate(sys, sc, opt).status != RunStatus::kOk) return p;
  p.ok = true;
  const auto& ev = rec.events;

  // 1. Tokens (docs/model.md §5.4: a chattering tail is the run of impacts of decreasing speed that ends
  //    in the accumulation point; impacts before it are isolated).
  std::string tokens;
  std::vector<size_t> pending;  // impacts of the current free flight not yet tokenised
  bool stick_in_token = false;  // the next stick event belongs to the last token (C)
  const auto flush = [&](size_t upto) {
    for (size_t i = 0; i < upto; ++i) {
      tokens += 'I';
      p.impact_speed = std::min(p.impact_speed, ev[pending[i]].speed);
    }
    pending.erase(pending.begin(), pending.begin() + static_cast<long>(upto));
  };
  for (size_t i = 0; i < ev.size(); ++i) {
    switch (ev[i].kind) {
      case EventKind::kImpact:
        pending.push_back(i);
        break;
      case EventKind::kAccumulation: {
        size_t s = pending.size();
        while (s > 1 && ev[pending[s - 2]].speed > ev[pending[s - 1]].speed) --s;
        if (s > 0) --s;
        flush(s);
        pending.clear();
        tokens += 'C';
        stick_in_token = true;
        break;
      }
      case EventKind::kStick:
        ++p.sticking_phases;
        if (stick_in_token) {
          stick_in_token = false;
        } else if (!pending.empty() && std::abs(ev[pending.back()].offset - ev[i].offset) <= 1e-12 * span) {
          flush(pending.size() - 1);
          pending.clear();
          tokens += 'P';
        } else {
          flush(pending.size());
          tokens += 'S';
        }
        break;
      case EventKind::kRelease:
        flush(pending.size());
        tokens += 'R';
        break;
      case EventKind::kGrazing:
        flush(pending.size());
        tokens += 'G';
        break;
    }
  }
  flush(pending.size());
  p.signature = Canonical(tokens);
  p.coarse_signature = Coarse(p.signature);

  // 2. Sticking phases and free flights (the orbit starts free at the section).
  struct Interval {
    double from, to;
  };
  std::vector<Interval> flights, sticks;  // flights end at every contact event
  bool free = true;
  double since = 0;
  for (const auto& e : ev) {
    if (free) {
      if (e.offset > since) flights.push_back({since, e.offset});
      since = e.offset;
      if (e.kind == EventKind::kStick) free = false;
    } else if (e.kind == EventKind::kRelease) {
      sticks.push_back({since, e.offset});
      free = true;
      since = e.offset;
    }
  }
  if (free) {
    flights.push_back({since, span});
    // The flight cut by the end of the window continues at its start (the orbit is periodic).
    if (flights.size() > 1 && flights.front().from == 0.0) {
      flights.front().from = flights.back().from - span;
      flights.pop_back();
    }
  } else {
    sticks.push_back({since, span});
  }
  double released = -1;
  for (const auto& e : ev) {
    if (e.kind == EventKind::kRelease) released = e.offset;
    if (e.kind == EventKind::kStick && released >= 0) {
      p.release_to_stick = std::min(p.release_to_stick, (e.offset - released) / span);
      released = -1;
    }
  }
  for (const auto& s : sticks) p.shortest_stick = std::min(p.shortest_stick, (s.to - s.from) / span);

  // 3. Interior minima of R (sticking) and of the gap (free flight) between consecutive events.
  double R_max = 0, gap_min = OrbitProbe::kNone, gap_max = -OrbitProbe::kNone, speed_max = 0;
  for (const auto& s : rec.samples) {
    R_max = std::max(R_max, s.R);
    gap_min = std::min(gap_min, s.gap);
    gap_max = std::max(gap_max, s.gap);
    speed_max = std::max(speed_max, std::abs(s.v_B));
  }
  const auto segment = [&](double offset) {
    return std::upper_bound(ev.begin(), ev.end(), offset,
                            [](double o, const Recorded::Ev& e) { return o < e.offset; }) -
           ev.begin();
  };
  const auto& S = rec.samples;
  double interior_R = OrbitProbe::kNone, interior_gap = OrbitProbe::kNone;
  for (size_t j = 1; j + 1 < S.size(); ++j) {
    const auto seg = segment(S[j].offset);
    if (segment(S[j - 1].offset) != seg || segment(S[j + 1].offset) != seg) continue;
    if (S[j - 1].mode != S[j].mode || S[j + 1].mode != S[j].mode) continue;
    if (S[j].mode == Mode::kSticking) {
      if (S[j].R < S[j - 1].R && S[j].R <= S[j + 1].R)
        interior_R = std::min(interior_R, ParabolaMin(S[j - 1].R, S[j].R, S[j + 1].R));
    } else if (S[j].gap < S[j - 1].gap && S[j].gap <= S[j + 1].gap) {
      interior_gap = std::min(interior_gap, ParabolaMin(S[j - 1].gap, S[j].gap, S[j + 1].gap));
    }
  }
  const double R_scale = R_max > 0 ? R_max : 1.0;
  const double gap_scale = gap_max > gap_min ? gap_max - gap_min : 1.0;
  const double speed_scale = speed_max > 0 ? speed_max : 1.0;
  if (std::isfinite(interior_R)) p.interior_reaction = std::max(interior_R, 0.0) / R_scale;
  if (std::isfinite(interior_gap)) p.flight_gap = std::max(interior_gap, 0.0) / gap_scale;
  if (std::isfinite(p.impact_speed)) p.impact_speed /= speed_scale;
  for (double R : rec.entry_reactions)
    p.entry_reaction = std::min(p.entry_reaction, std::max(R, 0.0) / R_scale);

  // 4. The section: its margin in the flight it lies in, and the middle of the longest flight.
  if (!flights.empty() && flights.front().from <= 0.0) {
    const auto& f = flights.front();
    p.section_margin = std::min(-f.from, f.to) / (f.to - f.from);
  }
  const auto longest = std::max_element(flights.begin(), flights.end(), [](const auto& a, const auto& b) {
    return a.to - a.from < b.to - b.from;
  });
  if (longest != flights.end()) {
    double mid = 0.5 * (longest->from + longest->to);
    if (mid < 0) mid += span;
    const Recorded::Smp* best = nullptr;
    for (const auto& s : S)
      if (s.mode == Mode::kFree && (!best || std::abs(s.offset - mid) < std::abs(best->offset - mid)))
        best = &s;
    if (best) {
      p.best_offset = best->offset;
      p.best_X = best->X;
      p.best_V = best->V;
    }
  }
  return p;
}

}  // namespace vibro
