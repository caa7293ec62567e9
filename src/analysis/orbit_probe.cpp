// The event signature and the non-smooth test quantities of a periodic orbit (orbit_probe.hpp).
#include "analysis/orbit_probe.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>

#include "vibro/observer.hpp"
#include "vibro/poincare.hpp"
#include "vibro/simulator.hpp"

namespace vibro {
namespace {

struct Recorded {
  struct Ev {
    EventKind kind;
    double offset;  // time since t0
    double speed;   // |ġ_j⁻|
    int contact;
  };
  struct Smp {
    double offset;
    std::vector<double> gap, v, R;  // per contact: g_j, ġ_j, and R_j while j is held alone (else 0)
    std::vector<char> held;         // per contact: held at this sample
    Mode mode;
    Eigen::VectorXd X, V;
  };
  std::vector<Ev> events;
  std::vector<Smp> samples;
  std::vector<std::pair<int, double>> entry_reactions;  // (contact, R) at the start of a sticking phase
};

class Recorder final : public Observer {
 public:
  Recorder(const System& sys, double T, Recorded& out)
      : sys_(sys), T_(T), out_(out), held_(static_cast<size_t>(sys.contact_count()), 0) {}
  void OnEvent(const Event& e) override {
    out_.events.push_back({e.kind, Offset(e.clock), std::abs(e.v_before), e.contact});
    if (e.kind == EventKind::kStick) held_[static_cast<size_t>(e.contact)] = 1;
    if (e.kind == EventKind::kRelease) held_[static_cast<size_t>(e.contact)] = 0;
  }
  void OnSample(const Sample& s) override {
    const double phase = sys_.frequency() * s.t;
    const int m = sys_.contact_count();
    Recorded::Smp smp{Offset(s.clock), {}, {}, {}, {}, s.mode, s.X, s.V};
    smp.gap.resize(static_cast<size_t>(m));
    smp.v.resize(static_cast<size_t>(m));
    smp.R.assign(static_cast<size_t>(m), 0.0);
    smp.held.assign(static_cast<size_t>(m), 0);
    const auto held = std::count(held_.begin(), held_.end(), 1);
    for (int j = 0; j < m; ++j) {
      const auto k = static_cast<size_t>(j);
      const ContactModel& c = sys_.contacts()[k];
      // One contact: exactly the single-stop quantities (x_B − x0, ẋ_B, R in sticking mode).
      smp.gap[k] = m == 1 ? s.x_B - sys_.stop() : c.shape.dot(s.X) - c.stop;
      smp.v[k] = m == 1 ? sys_.ContactVelocity(s.V) : c.shape.dot(s.V);
      smp.held[k] = static_cast<char>(m == 1 ? s.mode == Mode::kSticking : held_[k] == 1);
      if (smp.held[k] && (m == 1 || held == 1)) smp.R[k] = sys_.ContactReaction(j, s.X, s.V, phase);
    }
    out_.samples.push_back(std::move(smp));
  }
  void OnReset(const Reset& r) override {
    if (r.kind == ResetKind::kPlasticStick)
      out_.entry_reactions.emplace_back(r.contact, sys_.ContactReaction(r.contact, r.X_after, r.V_after, r.phase));
    else if (r.kind == ResetKind::kAccumulation)
      out_.entry_reactions.emplace_back(
          r.contact, sys_.ContactReaction(r.contact, r.X_after, r.V_after, r.phase + sys_.frequency() * r.delta));
  }

 private:
  double Offset(const Clock& c) const { return static_cast<double>(c.period) * T_ + c.offset; }
  const System& sys_;
  double T_;
  Recorded& out_;
  std::vector<char> held_;  // contacts held now (from the events)
};

// The tokens of a signature: a letter and, with several contacts, its contact's digits.
std::vector<std::string> Tokens(const std::string& s) {
  std::vector<std::string> out;
  for (char ch : s) {
    if (std::isdigit(static_cast<unsigned char>(ch)) && !out.empty()) out.back() += ch;
    else out.emplace_back(1, ch);
  }
  return out;
}

std::string Join(const std::vector<std::string>& t, size_t from = 0) {
  std::string out;
  for (size_t i = 0; i < t.size(); ++i) out += t[(from + i) % t.size()];
  return out;
}

// The lexicographically smallest rotation (by whole tokens): signatures do not depend on where
// the section is.
std::string Canonical(const std::string& s) {
  const auto t = Tokens(s);
  std::string best = s;
  for (size_t i = 1; i < t.size(); ++i) best = std::min(best, Join(t, i));
  return best;
}

// The signature with the isolated impacts just before a chattering sequence (on the same contact)
// merged into it.
std::string Coarse(const std::string& s) {
  auto t = Tokens(s);
  for (bool merged = true; merged && t.size() > 1;) {
    merged = false;
    for (size_t i = 0; i < t.size(); ++i) {
      const std::string& next = t[(i + 1) % t.size()];
      if (t[i][0] == 'I' && next[0] == 'C' && t[i].substr(1) == next.substr(1)) {
        t.erase(t.begin() + static_cast<long>(i));
        merged = true;
        break;
      }
    }
  }
  return Canonical(Join(t));
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
  const int m = sys.contact_count();
  const auto M = static_cast<size_t>(m);
  Scene sc = scene;
  sc.run.periods = q;
  sc.run.samples_per_period = samples;
  Recorded rec;
  Recorder observer(sys, T, rec);
  const InitialOverride init{t0, X, V};
  SimulationOptions opt;
  opt.initial = &init;
  opt.observers = {&observer};
  opt.max_segments = kMapSegmentsPerPeriod * q;
  if (Simulate(sys, sc, opt).status != RunStatus::kOk) return p;
  p.ok = true;
  const auto& ev = rec.events;
  // Keeps the smaller value and the contact where it is.
  const auto keep = [](double& value, int& where, double candidate, int contact) {
    if (candidate < value) {
      value = candidate;
      where = contact;
    }
  };
  const auto label = [&](char kind, int contact) {
    return m == 1 ? std::string(1, kind) : kind + std::to_string(contact);
  };

  // 1. Tokens (docs/model.md §5.4: a chattering tail is the run of impacts of decreasing speed on
  //    one contact that ends in its accumulation point; impacts before it are isolated).
  std::string tokens;
  std::vector<size_t> pending;  // impacts of the current free flight not yet tokenised
  std::vector<char> stick_in_token(M, 0);  // the contact's next stick event belongs to its last C
  std::vector<size_t> isolated;  // the isolated impacts
  const auto flush = [&](size_t upto) {
    for (size_t i = 0; i < upto; ++i) {
      tokens += label('I', ev[pending[i]].contact);
      isolated.push_back(pending[i]);
    }
    pending.erase(pending.begin(), pending.begin() + static_cast<long>(upto));
  };
  for (size_t i = 0; i < ev.size(); ++i) {
    const int c = ev[i].contact;
    switch (ev[i].kind) {
      case EventKind::kImpact:
        pending.push_back(i);
        break;
      case EventKind::kAccumulation: {
        // The tail: the last impacts on this contact, of decreasing speed, and the one before them.
        size_t s = pending.size();
        while (s > 0 && ev[pending[s - 1]].contact != c) --s;  // impacts elsewhere after the tail
        size_t tail = s;
        while (tail > 1 && ev[pending[tail - 2]].contact == c && ev[pending[tail - 2]].speed > ev[pending[tail - 1]].speed)
          --tail;
        if (tail > 0) --tail;
        flush(tail);
        // Impacts on other contacts between the tail's last impact and the accumulation point:
        // isolated, before the C.
        for (size_t j = s - tail; j < pending.size(); ++j) {
          tokens += label('I', ev[pending[j]].contact);
          isolated.push_back(pending[j]);
        }
        pending.clear();
        tokens += label('C', c);
        stick_in_token[static_cast<size_t>(c)] = 1;
        break;
      }
      case EventKind::kStick:
        ++p.sticking_phases;
        if (stick_in_token[static_cast<size_t>(c)]) {
          stick_in_token[static_cast<size_t>(c)] = 0;
        } else if (!pending.empty() && ev[pending.back()].contact == c &&
                   std::abs(ev[pending.back()].offset - ev[i].offset) <= 1e-12 * span) {
          flush(pending.size() - 1);
          pending.clear();
          tokens += label('P', c);
        } else {
          flush(pending.size());
          tokens += label('S', c);
        }
        break;
      case EventKind::kRelease:
        flush(pending.size());
        tokens += label('R', c);
        break;
      case EventKind::kGrazing:
        flush(pending.size());
        tokens += label('G', c);
        break;
    }
  }
  flush(pending.size());
  p.signature = Canonical(tokens);
  p.coarse_signature = Coarse(p.signature);

  // 2. Sticking phases (per contact) and free flights (no contact held; the orbit starts free at
  //    the section).
  struct Interval {
    double from, to;
  };
  std::vector<Interval> flights;  // flights end at every contact event
  std::vector<double> stuck_since(M, -1.0);
  int held = 0;
  double since = 0;
  for (const auto& e : ev) {
    const auto k = static_cast<size_t>(e.contact);
    if (held == 0) {
      if (e.offset > since) flights.push_back({since, e.offset});
      since = e.offset;
    }
    if (e.kind == EventKind::kStick && stuck_since[k] < 0) {
      stuck_since[k] = e.offset;
      ++held;
    } else if (e.kind == EventKind::kRelease && stuck_since[k] >= 0) {
      keep(p.shortest_stick, p.at.shortest_stick, (e.offset - stuck_since[k]) / span, e.contact);
      stuck_since[k] = -1;
      if (--held == 0) since = e.offset;
    }
  }
  for (int j = 0; j < m; ++j)
    if (stuck_since[static_cast<size_t>(j)] >= 0)
      keep(p.shortest_stick, p.at.shortest_stick, (span - stuck_since[static_cast<size_t>(j)]) / span, j);
  if (held == 0) {
    flights.push_back({since, span});
    // The flight cut by the end of the window continues at its start (the orbit is periodic).
    if (flights.size() > 1 && flights.front().from == 0.0) {
      flights.front().from = flights.back().from - span;
      flights.pop_back();
    }
  }
  std::vector<double> released(M, -1.0);
  for (const auto& e : ev) {
    const auto k = static_cast<size_t>(e.contact);
    if (e.kind == EventKind::kRelease) released[k] = e.offset;
    if (e.kind == EventKind::kStick && released[k] >= 0) {
      keep(p.release_to_stick, p.at.release_to_stick, (e.offset - released[k]) / span, e.contact);
      released[k] = -1;
    }
  }
  // Two consecutive events on different contacts close in time (an impact on one at the moment
  // another releases, or two impacts: simultaneous impacts are the limit). Only adjacent events
  // can swap their order.
  for (size_t i = 1; m > 1 && i < ev.size(); ++i) {
    const size_t k = i - 1;
    if (ev[k].contact == ev[i].contact || (ev[i].offset - ev[k].offset) / span >= p.simultaneous) continue;
    p.simultaneous = (ev[i].offset - ev[k].offset) / span;
    p.at.simultaneous = ev[i].contact;
    p.at.simultaneous_other = ev[k].contact;
    p.at.simultaneous_kind = static_cast<int>(ev[i].kind);
    p.at.simultaneous_other_kind = static_cast<int>(ev[k].kind);
  }

  // 3. Interior minima of R (sticking) and of the gaps between consecutive events, per contact.
  const auto& S = rec.samples;
  std::vector<double> R_max(M, 0.0), gap_min(M, OrbitProbe::kNone), gap_max(M, -OrbitProbe::kNone),
      speed_max(M, 0.0);
  for (const auto& smp : S)
    for (size_t k = 0; k < M; ++k) {
      R_max[k] = std::max(R_max[k], smp.R[k]);
      gap_min[k] = std::min(gap_min[k], smp.gap[k]);
      gap_max[k] = std::max(gap_max[k], smp.gap[k]);
      speed_max[k] = std::max(speed_max[k], std::abs(smp.v[k]));
    }
  const auto segment = [&](double offset) {
    return std::upper_bound(ev.begin(), ev.end(), offset,
                            [](double o, const Recorded::Ev& e) { return o < e.offset; }) -
           ev.begin();
  };
  const auto R_scale = [&](size_t k) { return R_max[k] > 0 ? R_max[k] : 1.0; };
  const auto gap_scale = [&](size_t k) { return gap_max[k] > gap_min[k] ? gap_max[k] - gap_min[k] : 1.0; };
  for (size_t j = 1; j + 1 < S.size(); ++j) {
    const auto seg = segment(S[j].offset);
    if (segment(S[j - 1].offset) != seg || segment(S[j + 1].offset) != seg) continue;
    if (S[j - 1].mode != S[j].mode || S[j + 1].mode != S[j].mode) continue;
    const int holding = static_cast<int>(std::find(S[j].held.begin(), S[j].held.end(), 1) - S[j].held.begin());
    for (size_t k = 0; k < M; ++k) {
      const int c = static_cast<int>(k);
      if (S[j].held[k]) {
        const double R0 = S[j - 1].R[k], R1 = S[j].R[k], R2 = S[j + 1].R[k];
        if ((m == 1 || R1 != 0.0) && R1 < R0 && R1 <= R2)  // (R 0: held with others)
          keep(p.interior_reaction, p.at.interior_reaction, std::max(ParabolaMin(R0, R1, R2), 0.0) / R_scale(k), c);
        continue;
      }
      const double g0 = S[j - 1].gap[k], g1 = S[j].gap[k], g2 = S[j + 1].gap[k];
      if (!(g1 < g0 && g1 <= g2)) continue;
      const double value = std::max(ParabolaMin(g0, g1, g2), 0.0) / gap_scale(k);
      if (S[j].mode == Mode::kFree) {
        keep(p.flight_gap, p.at.flight_gap, value, c);
      } else if (m > 1 && value < p.closing_gap) {
        p.closing_gap = value;
        p.at.closing_gap = c;
        p.at.closing_held = holding;
      }
    }
  }
  for (size_t i : isolated) {
    const auto k = static_cast<size_t>(ev[i].contact);
    keep(p.impact_speed, p.at.impact_speed, ev[i].speed / (speed_max[k] > 0 ? speed_max[k] : 1.0), ev[i].contact);
  }
  for (const auto& [c, R] : rec.entry_reactions) {
    keep(p.entry_reaction, p.at.entry_reaction, std::max(R, 0.0) / R_scale(static_cast<size_t>(c)), c);
    p.entry_reaction_raw = std::min(p.entry_reaction_raw, R);
  }
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
