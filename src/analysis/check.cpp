// Cross-check of the two engines and the Poincaré solver.
#include "vibro/check.hpp"

#include <algorithm>
#include <cmath>
#include <optional>

#include <fmt/format.h>

#include "vibro/contact_sequence.hpp"

namespace vibro {
namespace {

struct SectionLog final : Observer {
  std::vector<Eigen::VectorXd> z;
  void OnSection(const Sample& s) override {
    Eigen::VectorXd v(2 * s.X.size());
    v << s.X, s.V;
    z.push_back(std::move(v));
  }
};

// The events of the last `keep` forcing periods of a run of `periods` (the contact sequence of
// its attractor, several contacts).
struct FinalEvents final : Observer {
  long long from = 0;
  std::vector<Event> events;
  void OnEvent(const Event& e) override {
    if (e.clock.period >= from) events.push_back(e);
  }
};

// A compliant stop's first contact phase (docs/compliant.md): its entry and its exit, which carries
// the phase's loads.
struct FirstPhase final : Observer {
  std::optional<Event> entry, exit;
  void OnEvent(const Event& e) override {
    if (e.kind == EventKind::kStick && !entry) entry = e;
    if (e.kind == EventKind::kRelease && entry && !exit && std::isfinite(e.peak_time)) exit = e;
  }
};

struct Run {
  Attractor attractor;
  RunResult result;
  std::vector<Eigen::VectorXd> sections;
  std::vector<Event> final_events;  // the last run.max_period periods (several contacts, compliant stops)
  FirstPhase first;                 // a compliant stop's first contact phase
  long long periods = 0;
};

Run SimulateWith(const System& sys, Scene scene, Engine engine,
                 Precision precision = Precision::kDouble) {
  scene.run.engine = engine;
  scene.run.precision = precision;
  scene.run.samples_per_period = 0;
  AttractorRecorder rec(sys, scene);
  SectionLog log;
  FinalEvents last;
  last.from = sys.contact_count() > 1 || HasCompliantContact(scene) ? scene.run.periods - scene.run.max_period
                                                                     : scene.run.periods;
  Run r;
  SimulationOptions opt;
  opt.observers = {&rec, &log, &last, &r.first};
  r.result = Simulate(sys, scene, opt);
  r.attractor = rec.Classify();
  r.sections = std::move(log.z);
  r.final_events = std::move(last.events);
  r.periods = scene.run.periods;
  return r;
}

// The contact sequence of a run's periodic attractor: its events over the last p periods (p its
// period, else `fallback`), as a cyclic word.
std::vector<std::string> FinalSequence(const Run& r, int fallback) {
  const long long p = r.attractor.period.value_or(fallback);
  std::vector<Event> last;
  for (const Event& e : r.final_events)
    if (e.clock.period >= r.periods - p) last.push_back(e);
  return ContactSequenceOf(last);
}

// Decay rate of the transient: slope of log |z_{k+1} − z_k| where it is between rounding and
// the nonlinear regime. Returns 0 when the differences vanish (superstable), nullopt when too
// few points are usable.
std::optional<double> ObservedDecay(const std::vector<Eigen::VectorXd>& z) {
  if (z.size() < 4) return std::nullopt;
  double scale = 1.0;
  for (const auto& v : z) scale = std::max(scale, v.cwiseAbs().maxCoeff());
  std::vector<double> d;
  for (size_t k = 0; k + 1 < z.size(); ++k) d.push_back((z[k + 1] - z[k]).cwiseAbs().maxCoeff());
  std::vector<std::pair<double, double>> pts;
  for (size_t k = 0; k < d.size(); ++k)
    if (d[k] > 1e-11 * scale && d[k] < 1e-3 * scale) pts.emplace_back(static_cast<double>(k), std::log(d[k]));
  // Differences that end at exactly 0 after a geometric decay through the band (a long run that
  // reaches its orbit to the last bit: a sticking orbit of several DOFs) still have that decay's
  // rate; without such a decay they mean a superstable orbit.
  if (pts.size() < 6) {
    if (d.back() == 0.0 && d[d.size() - 2] == 0.0) return 0.0;
    return std::nullopt;
  }
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (const auto& [x, y] : pts) {
    sx += x;
    sy += y;
    sxx += x * x;
    sxy += x * y;
  }
  const double m = static_cast<double>(pts.size());
  return std::exp((m * sxy - sx * sy) / (m * sxx - sx * sx));
}

std::vector<CyclicEvent> ImpactsOf(const Attractor& x) {
  std::vector<CyclicEvent> out;
  for (size_t i = 0; i < x.impact_phases.size(); ++i)
    out.push_back({i < x.impact_contacts.size() ? x.impact_contacts[i] : 0, x.impact_phases[i],
                   i < x.impact_velocities.size() ? x.impact_velocities[i] : std::nan("")});
  return out;
}

std::vector<CyclicEvent> StickPhasesOf(const Attractor& x) {
  std::vector<CyclicEvent> out;
  for (size_t i = 0; i < x.stick_phases.size(); ++i)
    out.push_back({i < x.stick_contacts.size() ? x.stick_contacts[i] : 0, x.stick_phases[i].first,
                   x.stick_phases[i].second});
  return out;
}

// A phase difference modulo 2π (each record counts phases from the forcing period it starts in).
double PhaseDistance(double x, double y) {
  const double d = x - y;
  return std::abs(d - 2.0 * M_PI * std::round(d / (2.0 * M_PI)));
}

std::vector<CyclicEvent> Rotated(const std::vector<CyclicEvent>& v, size_t r) {
  std::vector<CyclicEvent> out(v.begin() + static_cast<std::ptrdiff_t>(r), v.end());
  out.insert(out.end(), v.begin(), v.begin() + static_cast<std::ptrdiff_t>(r));
  return out;
}

}  // namespace

std::vector<CyclicEvent> CanonicalCyclic(const std::vector<CyclicEvent>& v) {
  if (v.size() < 2) return v;
  std::vector<std::string> word;
  for (const auto& e : v) word.push_back(std::to_string(e.contact) + ":impact");
  const std::vector<std::string> canon = CanonicalRotation(word);
  std::optional<size_t> best;
  for (size_t r = 0; r < v.size(); ++r) {
    bool same = true;
    for (size_t i = 0; i < v.size() && same; ++i) same = word[(r + i) % v.size()] == canon[i];
    if (same && (!best || std::fmod(v[r].a, 2.0 * M_PI) < std::fmod(v[*best].a, 2.0 * M_PI))) best = r;
  }
  return Rotated(v, best.value_or(0));
}

std::vector<CyclicEvent> AlignedCyclic(const std::vector<CyclicEvent>& ref, const std::vector<CyclicEvent>& v,
                                       bool b_is_phase) {
  if (v.size() != ref.size() || v.empty()) return v;
  std::optional<size_t> best;
  double best_d = 0;
  for (size_t r = 0; r < v.size(); ++r) {
    double d = 0;
    bool same = true;
    for (size_t i = 0; i < v.size() && same; ++i) {
      const CyclicEvent& x = v[(r + i) % v.size()];
      same = x.contact == ref[i].contact;
      d = std::max({d, PhaseDistance(x.a, ref[i].a),
                    b_is_phase ? PhaseDistance(x.b, ref[i].b) : std::abs(x.b - ref[i].b)});
    }
    if (same && (!best || d < best_d)) {
      best = r;
      best_d = d;
    }
  }
  return Rotated(v, best.value_or(0));
}

CheckReport CrossCheck(const System& sys, const Scene& scene, bool with_quad) {
  CheckReport rep;
  const Run ex = SimulateWith(sys, scene, Engine::kExact);
  const Run cv = SimulateWith(sys, scene, Engine::kCvode);
  std::optional<Run> qd;
  if (with_quad) qd = SimulateWith(sys, scene, Engine::kExact, Precision::kQuad);
  rep.exact_kind = ex.attractor.kind;
  rep.cvode_kind = cv.attractor.kind;
  if (qd) rep.quad_kind = qd->attractor.kind;
  const double tol_cvode = std::max(1e-6, 100.0 * std::pow(scene.run.rtol, 2.0 / 3.0));
  constexpr double kTolOrbit = 1e-9;
  constexpr double kTolQuad = 1e-9;

  const auto add = [&](CheckRow row) {
    rep.ok = rep.ok && row.ok;
    rep.rows.push_back(std::move(row));
  };
  add({"attractor kind", {}, {}, {}, 0, 0,
       ex.attractor.kind == cv.attractor.kind && (!qd || qd->attractor.kind == ex.attractor.kind),
       fmt::format("exact {}, cvode {}{}", ex.attractor.kind, cv.attractor.kind,
                   qd ? ", quad " + qd->attractor.kind : ""),
       {}});
  const auto status_note = [](const char* name, const RunResult& r) {
    return fmt::format("{} {}{}", name, ToString(r.status),
                       r.message.empty() ? "" : " (" + r.message + ")");
  };
  add({"status", {}, {}, {}, 0, 0,
       ex.result.status == RunStatus::kOk && cv.result.status == RunStatus::kOk &&
           (!qd || qd->result.status == RunStatus::kOk),
       fmt::format("{}, {}{}", status_note("exact", ex.result), status_note("cvode", cv.result),
                   qd ? ", " + status_note("quad", qd->result) : ""),
       {}});

  const bool periodic = HoldsContact(ex.attractor.kind) || ex.attractor.kind == "impact-periodic";
  // A compliant stop (docs/compliant.md): the engines are compared, and the Poincaré solver with the
  // compliant saltations ("Periodic orbits") finds the orbit as for a rigid stop.
  const bool compliant = HasCompliantContact(scene);
  OrbitResult orbit;
  if (periodic) {
    OrbitRequest req;
    req.kind = HoldsContact(ex.attractor.kind) ? OrbitKind::kSticking : OrbitKind::kImpact;
    req.period = *ex.attractor.period;
    orbit = FindOrbit(sys, scene, req);
  } else {
    orbit.status = "not attempted";
    orbit.message = "the motion is " + ex.attractor.kind + ": no periodic orbit to solve for";
  }
  rep.orbit_status = orbit.status;
  const bool have_orbit = orbit.status == "converged";
  add({"poincare solver", {}, {}, {}, orbit.residual, 0, !periodic || have_orbit,
       have_orbit ? fmt::format("converged in {} Newton iterations, residual {:.1e}",
                                orbit.newton_iterations, orbit.residual)
                  : orbit.status + ": " + orbit.message,
       {}});
  // A compliant stop (docs/compliant.md): its first contact phase in both engines, whatever the
  // attractor, and below each contact phase of a periodic attractor's last period: the loads its
  // exit carries, as relative differences; instants in periods.
  const auto relative = [&](const std::string& name, double e, double c, bool in_periods) {
    const double scale = in_periods ? sys.period() : std::max(std::abs(e), 1e-300);
    CheckRow row{name, e, c, {}, std::abs(c - e) / scale, tol_cvode, true, in_periods ? "in periods" : "relative", {}};
    row.ok = row.difference <= tol_cvode;
    add(row);
  };
  const auto phase_rows = [&](const std::string& what, const Event& e, const Event& c) {
    relative(what + " duration", e.stick_duration, c.stick_duration, false);
    relative(what + " peak force", e.reaction_max, c.reaction_max, false);
    relative(what + " largest penetration", e.penetration_max, c.penetration_max, false);
    relative(what + " impulse", e.reaction_integral, c.reaction_integral, false);
  };
  if (compliant) {
    const FirstPhase &a = ex.first, &b = cv.first;
    if (!a.exit || !b.exit) {
      add({"first contact phase", {}, {}, {}, 0, 0, a.exit.has_value() == b.exit.has_value(),
           fmt::format("exact {}, cvode {}", a.exit ? "one" : "none", b.exit ? "one" : "none"), {}});
    } else {
      relative("first contact phase entry t", a.entry->t, b.entry->t, true);
      relative("first contact phase exit t", a.exit->t, b.exit->t, true);
      phase_rows("first contact phase", *a.exit, *b.exit);
      relative("first contact phase exit velocity", a.exit->v_after, b.exit->v_after, false);
    }
  }
  if (!periodic) return rep;
  // Several contacts: the attractor's contact sequence, the same cyclic word (wherever each
  // record starts, a chattering sequence's count of impacts aside: contact_sequence.hpp) in each
  // engine and on the orbit Newton finds.
  if (sys.contact_count() > 1) {
    const int p = *ex.attractor.period;
    const auto e = FinalSequence(ex, p), c = FinalSequence(cv, p);
    std::string unused;
    const auto o = have_orbit ? ParseContactSequence(orbit.sequence, -1, unused) : std::nullopt;
    const auto q = qd ? std::optional(FinalSequence(*qd, p)) : std::nullopt;
    const bool same_c = SameContactSequence(e, c), same_o = !o || SameContactSequence(e, *o),
               same_q = !q || SameContactSequence(e, *q);
    std::string note = "exact " + ContactSequenceText(e);
    if (!same_c) note += "; cvode " + ContactSequenceText(c);
    if (!same_o) note += "; orbit " + orbit.sequence;
    if (!same_q) note += "; quad " + ContactSequenceText(*q);
    if (same_c && same_o && same_q) note += fmt::format(" (the same in cvode{}{})", o ? ", the orbit" : "", q ? ", quad" : "");
    add({"contact sequence", {}, {}, {}, 0, 0, same_c && same_o && same_q, note, {}});
  }

  // Each quantity of the exact run against CVODE (tol_cvode), the Poincaré solver and the quad
  // engine (kTolOrbit, kTolQuad); q is the quad value when the quad engine ran.
  const auto compare = [&](const std::string& name, std::optional<double> e, std::optional<double> c,
                           std::optional<double> o, std::optional<double> q) {
    CheckRow row{name, e, c, have_orbit ? o : std::nullopt, 0, tol_cvode, true, "", q};
    if (!e || !c || (qd && !q)) {
      row.ok = e.has_value() == c.has_value() && (!qd || e.has_value() == q.has_value());
      row.note = "missing in one engine";
      add(row);
      return;
    }
    // Phases (ωt) of a period-p orbit are counted from whichever forcing period each method's
    // record starts in: the same orbit may show a phase shifted by 2π. Phases are compared modulo 2π.
    const bool phase = name.find("phase") != std::string::npos;
    const auto diff = [phase](double a, double b) {
      const double d = a - b;
      return std::abs(phase ? d - 2.0 * M_PI * std::round(d / (2.0 * M_PI)) : d);
    };
    const double dc = diff(*c, *e);
    const double dorb = row.orbit ? diff(*row.orbit, *e) : 0.0;
    const double dq = q ? diff(*q, *e) : 0.0;
    row.difference = std::max({dc, dorb, dq});
    row.ok = dc <= tol_cvode && dorb <= kTolOrbit && dq <= kTolQuad;
    if (dorb > kTolOrbit) row.note = fmt::format("orbit differs by {:.1e} > {:.0e}", dorb, kTolOrbit);
    if (dq > kTolQuad)
      row.note += fmt::format("{}quad differs by {:.1e} > {:.0e}", row.note.empty() ? "" : "; ", dq,
                              kTolQuad);
    add(row);
  };
  const Attractor none;
  const Attractor& qa = qd ? qd->attractor : none;
  const auto per = [](const Attractor& a) {
    return a.period ? std::optional<double>(*a.period) : std::nullopt;
  };
  compare("period", per(ex.attractor), per(cv.attractor), per(orbit.summary), per(qa));
  compare("sticking fraction", ex.attractor.sticking_fraction, cv.attractor.sticking_fraction,
          orbit.summary.sticking_fraction, qa.sticking_fraction);
  const auto ipp = [](const Attractor& a) {
    return a.impacts_per_period ? std::optional<double>(static_cast<double>(*a.impacts_per_period))
                                : std::nullopt;
  };
  // Impacts and sticking phases are cyclic lists (a periodic orbit has no first event): the exact
  // run's in the canonical rotation of its contact sequence, each other record rotated to match
  // it, contact by contact. Scenes with [[contact]] tables name each event's contact.
  const bool named = sys.contact_count() > 1 || !scene.contacts.empty();
  const auto label = [named](const char* what, size_t i, int contact) {
    return named ? fmt::format("{} {} (contact {})", what, i + 1, contact) : fmt::format("{} {}", what, i + 1);
  };
  const auto nth_a = [](const std::vector<CyclicEvent>& v, size_t i) -> std::optional<double> {
    return i < v.size() ? std::optional<double>(v[i].a) : std::nullopt;
  };
  const auto nth_b = [](const std::vector<CyclicEvent>& v, size_t i) -> std::optional<double> {
    return i < v.size() ? std::optional<double>(v[i].b) : std::nullopt;
  };
  // A row per value, and one per event whose contact differs from the exact run's.
  const auto compare_events = [&](const char* what, const char* a_name, const char* b_name, bool b_is_phase,
                                  const auto& of) {
    const std::vector<CyclicEvent> e = CanonicalCyclic(of(ex.attractor)), c = AlignedCyclic(e, of(cv.attractor), b_is_phase),
                                   o = AlignedCyclic(e, of(orbit.summary), b_is_phase),
                                   q = qd ? AlignedCyclic(e, of(qa), b_is_phase) : std::vector<CyclicEvent>{};
    for (size_t i = 0; i < e.size(); ++i) {
      const auto differs = [&](const std::vector<CyclicEvent>& v) { return i < v.size() && v[i].contact != e[i].contact; };
      if (differs(c) || (have_orbit && differs(o)) || (qd && differs(q))) {
        std::string note;
        const auto at = [&](const char* who, const std::vector<CyclicEvent>& v) {
          if (differs(v)) note += fmt::format("{}{} at contact {}", note.empty() ? "" : "; ", who, v[i].contact);
        };
        at("cvode", c);
        if (have_orbit) at("orbit", o);
        if (qd) at("quad", q);
        add({label(what, i, e[i].contact) + " contact", {}, {}, {}, 0, 0, false, note, {}});
      }
      compare(label(what, i, e[i].contact) + " " + a_name, nth_a(e, i), nth_a(c, i), nth_a(o, i),
              qd ? nth_a(q, i) : std::nullopt);
      compare(label(what, i, e[i].contact) + " " + b_name, nth_b(e, i), nth_b(c, i), nth_b(o, i),
              qd ? nth_b(q, i) : std::nullopt);
    }
  };
  if (ex.attractor.kind == "impact-periodic") {
    compare("impacts per period", ipp(ex.attractor), ipp(cv.attractor), ipp(orbit.summary),
            ipp(qa));
    // Each impact of the orbit: its phase and the contact velocity just before it.
    compare_events("impact", "phase", "velocity before", false, ImpactsOf);
  }
  compare_events("stick phase", "start", "end (release)", true, StickPhasesOf);
  if (have_orbit) {
    double lead = 0;
    for (const auto& m : orbit.multipliers) lead = std::max(lead, std::abs(m));
    const auto decay = ObservedDecay(ex.sections);
    CheckRow row{"leading |multiplier| vs transient decay", decay, {}, lead, 0, 0, true, "", {}};
    if (!decay) {
      row.note = "the transient converged too fast to measure its decay";
    } else {
      row.difference = std::abs(lead - *decay);
      row.tolerance = 0.1 * lead + 0.02;
      row.ok = row.difference <= row.tolerance;
      row.note = orbit.multipliers.empty() ? "superstable (one DOF): the transient stops at once"
                                           : (orbit.stable ? "stable" : "unstable");
    }
    add(row);
  }
  // Each contact phase of the compliant attractor's last period (above).
  if (compliant) {
    const long long p = *ex.attractor.period;
    const auto exits = [p](const Run& r) {
      std::vector<Event> out;
      for (const Event& e : r.final_events)
        if (e.kind == EventKind::kRelease && e.clock.period >= r.periods - p && std::isfinite(e.peak_time))
          out.push_back(e);
      return out;
    };
    const std::vector<Event> e = exits(ex), c = exits(cv);
    if (e.size() != c.size())
      add({"contact phases per period", static_cast<double>(e.size()) / static_cast<double>(p),
           static_cast<double>(c.size()) / static_cast<double>(p), {}, 0, 0, false, "", {}});
    else
      for (size_t i = 0; i < e.size(); ++i)
        phase_rows(fmt::format("contact phase {} (contact {})", i + 1, e[i].contact), e[i], c[i]);
  }

  return rep;
}

}  // namespace vibro
