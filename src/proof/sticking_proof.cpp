// Proof of a one-DOF sticking orbit with plastic impacts, r = 0 (prove.hpp, docs/prove.md).
//
// On the stop the reaction is R(t) = (ω_1² x0 − κ sin ωt)/T_B, κ = T_A f (the paper's eq. (5) with n = 1).
// The body leaves where R falls through zero: sin φ1 = ω_1² x0/κ with κ cos φ1 > 0 (docs/model.md §4.4),
// t_r = φ1/ω, from rest at x0. Then, flight after flight:
//   1. the flight from rest at x0 keeps g > 0 until a landing s* that interval Newton encloses
//      (near its start g(s)/s³ ≥ g'''(0)/6 − M4 s/24 after the release, g(s)/s² ≥ g''(0)/2 − M3 s/6
//      after a departure, docs/model.md §2.1; subdivision after);
//   2. the landing is transversal (g' < 0); the plastic impact leaves the body at rest on the stop,
//      where R > 0 makes it stick (done) and R < 0 makes it depart at once with g'' = −T_B R > 0
//      (the next flight: Fig. 10 of the paper has two);
//   3. R > 0 from the last landing until t_r + kT, k = ⌈(t_landing − t_r)/T⌉, where the body is
//      released again from the same state: the orbit has period kT.
#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "proof/proof_common.hpp"

namespace vibro::proof {

namespace {
constexpr int kMaxFlights = 400;
// Chattering (r > 0): impacts are followed one by one until the speed after an impact is below
// this fraction of the first landing speed, or its enclosure is wider than kTailWidth of it (the
// enclosures widen along the sequence); the rest of the sequence is then bounded as a whole.
constexpr double kTailSwitch = 1e-7, kTailWidth = 1e-5;
// Damped, the tail's enclosure of the accumulation time is O(v) wide (below): the impacts are
// followed further.
constexpr double kTailSwitchDamped = 1e-12;
}

Outcome ProveSticking1Dof(const IntervalModel& mdl, const ProofRequest& request, const Budget& budget) {
  Outcome out;
  Ledger ledger;
  const auto finish = [&](std::string reason) {
    out.reason = reason.empty() ? ledger.failed() : std::move(reason);
    out.certificate["inequalities"] = ledger.list();
    return out;
  };
  const Interval& w = mdl.frequency;
  const Interval w1s = Sqr(mdl.omega[0]), kappa = mdl.forcing[0] * mdl.amplitude, TB = mdl.contact[0];
  const Interval ratio = w1s * mdl.stop / kappa;
  const std::string rel = "release";
  if (!ledger.Check(kappa.Positive() || kappa.Negative(), "forcing T_A f", rel, kappa, "!= 0") ||
      !ledger.Check((Interval(1.0) - Abs(ratio)).Positive(), "1 - |omega_1^2 x0/(T_A f)|", rel,
                    Interval(1.0) - Abs(ratio), "> 0"))
    return finish(ledger.failed() + " (the body never leaves the stop, or the reaction has no sign change)");
  const Interval phi1 = kappa.Positive() ? Asin(ratio) : Interval::Pi() - Asin(ratio);
  const Interval tr = phi1 / w;
  const Interval rate = -(kappa * w * Cos(phi1)) / TB;  // Ṙ at the release
  if (!ledger.Check(rate.Negative(), "reaction rate", rel, rate, "< 0")) return finish("");
  out.certificate["release"] = {{"phase", Pair(phi1)}, {"time", Pair(tr)}, {"reaction_rate", Pair(rate)}};
  const auto reaction = [&](const Interval& t) { return (w1s * mdl.stop - kappa * Sin(w * t)) / TB; };

  Json events = Json::array(), sequence = Json::array({"release"}), flights = Json::array();
  events.push_back({{"kind", "release"}, {"contact", 0}, {"time", Pair(tr)}, {"phase", Pair(Phase(mdl, tr))}, {"velocity_before", {0.0, 0.0}}});
  const double top = std::max(w.hi(), mdl.omega[0].hi()), T = mdl.period.mid();
  const std::vector<Interval> X0{mdl.stop};
  std::vector<Interval> V0{Interval(0.0)};
  const bool plastic = mdl.restitution.lo() == 0 && mdl.restitution.hi() == 0;
  Interval t = tr, tL, gp, t_end;  // t_end: where the sticking begins (a landing, or the accumulation point)
  double first_speed = 0;
  std::string start_kind = "release";
  double landing_low = 0;  // lower end of the last landing box, as t − t_r
  bool stuck = false;
  for (int k = 0; k < kMaxFlights && !stuck; ++k) {
    const bool from_release = start_kind == "release", from_impact = start_kind == "impact";
    const std::string fl = fmt::format("flight {}", k), land = fmt::format("landing {}", k);
    const auto gap = [&](const Interval& s) { return ContactSum(mdl, Flight(mdl, t, X0, V0, s).X) - mdl.stop; };
    const auto slope = [&](const Interval& s) { return ContactSum(mdl, Flight(mdl, t, X0, V0, s).V); };
    Json flight = {{"start", start_kind}};
    double ws = 0;
    if (from_release) {
      // g = g' = g'' = 0, g''' = κ ω cos ωt (x''' at rest: −ω_1²·0 + κ ω cos ωt).
      const Interval g3 = kappa * w * Cos(w * t);
      const Interval M4 = DerivativeBound(mdl, t, X0, V0, 4);
      if (!ledger.Check(g3.Positive(), "third derivative of the gap", fl, g3, "> 0") ||
          !ledger.Check(M4.finite(), "fourth-derivative bound", fl, M4, "finite"))
        return finish("");
      // Lower bounds a little below the enclosures (a checker's wider enclosure still validates them).
      const double g3_low = g3.lo() * (1 - 1e-9);
      ws = 2 * g3_low / M4.hi();
      const Interval margin = Interval(g3_low) / Interval(6.0) - M4 * Interval(ws) / Interval(24.0);
      if (!ledger.Check(margin.Positive(), "start window g'''/6 - M4 ws/24", fl, margin, "> 0")) return finish("");
      flight["third_derivative"] = Pair(g3);
      flight["third_derivative_lower"] = g3_low;
      flight["fourth_derivative_bound"] = M4.hi();
    } else if (from_impact) {
      // g = 0, g' = ẋ⁺ = a > 0: g(s) ≥ s(a − M2 s/2) (as after the impacts of impact_proof.cpp).
      const Interval M2 = DerivativeBound(mdl, t, X0, V0, 2);
      if (!ledger.Check(V0[0].Positive(), "contact velocity after impact", fl, V0[0], "> 0") ||
          !ledger.Check(M2.finite(), "second-derivative bound", fl, M2, "finite"))
        return finish("");
      const double a_low = V0[0].lo() * (1 - 1e-9);
      ws = a_low / M2.hi();
      const Interval margin = Interval(a_low) - M2 * Interval(ws) / Interval(2.0);
      if (!ledger.Check(margin.Positive(), "start window a - M2 ws/2", fl, margin, "> 0")) return finish("");
      flight["velocity_after"] = Pair(V0[0]);
      flight["velocity_after_lower"] = a_low;
      flight["second_derivative_bound"] = M2.hi();
    } else {
      // g = g' = 0, g'' = −ω_1² x0 + κ sin ωt = −T_B R > 0 (a departure, docs/model.md §4.4).
      const Interval g2 = kappa * Sin(w * t) - w1s * mdl.stop;
      const Interval M3 = DerivativeBound(mdl, t, X0, V0, 3);
      if (!ledger.Check(g2.Positive(), "second derivative of the gap", fl, g2, "> 0") ||
          !ledger.Check(M3.finite(), "third-derivative bound", fl, M3, "finite"))
        return finish("");
      const double g2_low = g2.lo() * (1 - 1e-9);
      ws = 1.5 * g2_low / M3.hi();
      const Interval margin = Interval(g2_low) / Interval(2.0) - M3 * Interval(ws) / Interval(6.0);
      if (!ledger.Check(margin.Positive(), "start window g''/2 - M3 ws/6", fl, margin, "> 0")) return finish("");
      flight["second_derivative"] = Pair(g2);
      flight["second_derivative_lower"] = g2_low;
      flight["third_derivative_bound"] = M3.hi();
    }
    // The landing, approximately: the first sign change of g after the window, then bisection.
    // A chattering flight lasts about 2v/(T_B R): scan it in quarters.
    const double step = from_impact ? std::min(0.05 / top, 0.5 * V0[0].hi() / std::max(1e-300, std::abs(reaction(t).mid() * TB.mid())))
                                    : 0.05 / top;
    double a = ws, b = ws;
    bool found = false;
    while (b < 1000 * T) {
      a = b;
      b = a + step;
      if (gap(Interval(b)).mid() < 0) {
        found = true;
        break;
      }
      if (budget.passed()) return finish("time limit reached looking for the landing");
    }
    if (!found) return finish(fmt::format("the body does not land within 1000 periods ({})", fl));
    for (int it = 0; it < 200 && b - a > 4e-16 * b; ++it) {
      const double c = a + (b - a) / 2;
      (gap(Interval(c)).mid() > 0 ? a : b) = c;
    }
    const double s0 = a + (b - a) / 2;
    // Interval Newton: N(S) = s0 − g(s0)/g'(S) ⊂ int S and g' < 0 on S ⇒ exactly one root in S.
    Interval S, N;
    // Short flights of a chattering sequence: a box of a fixed fraction of the flight.
    double radius = std::min(request.box_radius * (1 + s0), 1e-3 * s0) + 4 * t.width() + 4 * V0[0].width() * s0 / std::max(V0[0].lo(), 1e-300);
    for (int attempt = 0; attempt < 4; ++attempt, radius *= 4) {
      S = Interval::Hull(s0 - radius, s0 + radius);
      gp = slope(S);
      N = Interval(s0) - gap(Interval(s0)) / gp;
      if (gp.Negative() && N.InsideOpen(S.lo(), S.hi())) break;
    }
    if (!ledger.Check(gp.Negative(), "contact velocity at the landing", land, gp, "< 0") ||
        !ledger.Check(N.InsideOpen(S.lo(), S.hi()), "interval Newton", land, N, "inside the box"))
      return finish("");
    const Interval after_window = Interval(S.lo()) - Interval(ws);
    if (!ledger.Check(after_window.Positive(), "landing after the start window", land, after_window, "> 0"))
      return finish("");
    const auto pos = ProvePositive(ws, S.lo(), 0.25 / top, request.max_depth, budget,
                                   [&](double s) { return gap(Interval(s)); }, slope);
    if (!pos.proven) {
      ledger.Check(false, "gap", fmt::format("{} at s = {:.17g}", fl, pos.failed_at), pos.failed_value, "> 0");
      return finish(fmt::format("the gap is not proven positive on {}: {}", fl, pos.reason));
    }
    Json pieces = Json::array();
    for (const auto& [lo, hi] : pos.pieces) pieces.push_back({lo, hi});
    tL = t + N;
    const Interval R_land = reaction(tL);
    if (!plastic) {
      // r > 0: the body bounces with ẋ⁺ = −r ẋ⁻ (the speed from the tight enclosure N of the landing).
      Interval vminus = slope(N);
      if (from_impact) {
        // Centred form of the landing as a function of the start (t, v) of the flight: the value at
        // the centre plus the derivatives over the whole box times the offsets (mean-value theorem;
        // s(t, v) stays in N over the box). Plain interval evaluation would widen the enclosures of
        // the impact times and speeds ~2.5 times per impact; this keeps their true sensitivity.
        const double tc = t.mid(), vc = V0[0].mid();
        const std::vector<Interval> Vc{Interval(vc)};
        const auto gap_c = [&](const Interval& s1) { return ContactSum(mdl, Flight(mdl, Interval(tc), X0, Vc, s1).X) - mdl.stop; };
        const auto slope_c = [&](const Interval& s1) { return ContactSum(mdl, Flight(mdl, Interval(tc), X0, Vc, s1).V); };
        const Interval Nc = Interval(s0) - gap_c(Interval(s0)) / slope_c(S);
        const Dual dt = Dual::Variable(t, 0, 3), dv = Dual::Variable(V0[0], 1, 3), ds = Dual::Variable(N, 2, 3);
        const auto e = Flight(mdl, dt, std::vector<Dual>{Dual(mdl.stop)}, std::vector<Dual>{dv}, ds);
        const Dual g = ContactSum(mdl, e.X), vel = ContactSum(mdl, e.V);
        const Interval ds_dt = -(g.d[0] / g.d[2]), ds_dv = -(g.d[1] / g.d[2]);
        const Interval dvm_dt = vel.d[0] + vel.d[2] * ds_dt, dvm_dv = vel.d[1] + vel.d[2] * ds_dv;
        const Interval dT = t - Interval(tc), dV = V0[0] - Interval(vc);
        const Interval t_cent = Interval(tc) + Nc + (Interval(1.0) + ds_dt) * dT + ds_dv * dV;
        const Interval v_cent = slope_c(Nc) + dvm_dt * dT + dvm_dv * dV;
        if (Nc.InsideOpen(S.lo(), S.hi()) && t_cent.width() < tL.width()) tL = t_cent;
        if (Nc.InsideOpen(S.lo(), S.hi()) && v_cent.width() < vminus.width()) vminus = v_cent;
      }
      const Interval vplus = -(mdl.restitution * vminus);
      if (!ledger.Check(vminus.Negative(), "contact velocity before impact", land, vminus, "< 0")) return finish("");
      if (first_speed == 0) first_speed = -vminus.mid();
      flight["start_window"] = ws;
      flight["landing_center"] = s0;
      flight["landing_box"] = {S.lo(), S.hi()};
      flight["landing"] = Pair(N);
      flight["pieces"] = pieces;
      flights.push_back(flight);
      events.push_back({{"kind", "impact"}, {"contact", 0}, {"time", Pair(tL)}, {"phase", Pair(Phase(mdl, tL))}, {"velocity_before", Pair(vminus)}});
      sequence.push_back("impact");
      landing_low = (t - tr + Interval(S.lo())).lo();
      if (vplus.hi() < (mdl.damped() ? kTailSwitchDamped : kTailSwitch) * first_speed || vplus.width() > kTailWidth * vplus.mid()) {
        // The rest of the sequence, bounded (docs/prove.md "chattering"): with y = x − x0 ≥ 0,
        // ÿ = −ω_1² y − T_B R(t). On a window W where T_B R ∈ [a_lo, A_hi], a_lo > 0, every flight from
        // speed v lasts at most 2v/a_lo, rises at most Y = v²/(2 a_lo), and lands with speed at most
        // v √(a_hi/a_lo), a_hi = A_hi + ω_1² Y: the speeds shrink at least by ρ = r √(a_hi/a_lo) < 1
        // per impact and the impacts accumulate before t + 2v/(a_lo (1 − ρ)) ≤ t + L, inside W.
        const std::string tl = "chattering tail";
        // Bounds a little outside the enclosures (as a_low of the flights): a checker recomputes the
        // enclosures, checks that these bounds hold, and derives ρ and the time bound from them.
        const double v = vplus.hi() * (1 + 1e-9);
        double L = 4 * v / std::max(1e-300, (TB * R_land).lo());
        // Damped (σ = ζω_1 > 0), ÿ = −ω_1² y − 2σẏ − T_B R: the damping force opposes the rise (so
        // Y ≤ v²/(2 A_lo) still) and removes energy in the fall (so the landing speed is still at most
        // v √(a_hi/A_lo)), but it slows the fall: there ÿ ≤ −(A_lo − 2σ v √(a_hi/A_lo)) = −f_lo, and a
        // flight lasts at most v/A_lo + v/√(A_lo f_lo) ≤ 2v/f_lo. Undamped f_lo = A_lo.
        const bool damped = mdl.damped();
        const Interval sigma = damped ? mdl.sigma[0] : Interval(0.0);
        Interval A, a_lo, a_hi, rho, Tmax, f_lo;
        double A_low = 0, A_high = 0;
        bool closed = false;
        for (int it = 0; it < 6 && !closed; ++it, L *= 2) {
          A = TB * reaction(Interval::Hull(tL.lo(), tL.hi() + L));
          if (!(A.lo() > 0)) continue;
          A_low = A.lo() * (1 - 1e-9);
          A_high = A.hi() * (1 + 1e-9);
          a_lo = Interval(A_low);
          a_hi = Interval(A_high) + w1s * Sqr(Interval(v)) / (Interval(2.0) * a_lo);
          rho = mdl.restitution * Sqrt(a_hi / a_lo);
          f_lo = damped ? a_lo - Interval(2.0) * sigma * Interval(v) * Sqrt(a_hi / a_lo) : a_lo;
          if (!(rho.hi() < 1) || !(f_lo.lo() > 0)) continue;
          Tmax = Interval(2.0) * Interval(v) / (f_lo * (Interval(1.0) - rho));
          closed = Tmax.hi() <= L;
        }
        L /= 2;
        if (!ledger.Check(A.Positive(), "tail reaction T_B R over the window", tl, A, "> 0") ||
            !ledger.Check((Interval(1.0) - rho).Positive(), "tail contraction 1 - rho", tl, Interval(1.0) - rho, "> 0") ||
            (damped && !ledger.Check(f_lo.Positive(), "tail fall acceleration A_lo - 2 sigma v sqrt(a_hi/A_lo)", tl,
                                     f_lo, "> 0")) ||
            !ledger.Check((Interval(L) - Tmax).Positive(), "tail window L - Tmax", tl, Interval(L) - Tmax, "> 0"))
          return finish(ledger.failed() + " (the chattering sequence could not be bounded)");
        // And from below: a flight from v lasts at least 2v/a_hi and lands at least v √(A_lo/a_hi)
        // fast (the rise and the fall of the energy balance), so t∞ − t ≥ 2 v_lo/(a_hi (1 − ρ_lo)):
        // the enclosure of t∞ is O(v²) wide. Damped: at least the first rise, v_lo/(a_hi + 2σv) (the
        // deceleration in the rise is at most A_hi + ω_1² Y + 2σv): O(v) wide.
        const double v_low = vplus.lo() * (1 - 1e-9);
        const Interval rho_low = mdl.restitution * Sqrt(a_lo / a_hi);
        const Interval Tmin = damped ? Interval(v_low) / (a_hi + Interval(2.0) * sigma * Interval(v))
                                     : Interval(2.0) * Interval(v_low) / (a_hi * (Interval(1.0) - rho_low));
        t_end = Interval::Hull((tL + Tmin).lo(), (tL + Tmax).hi());
        out.certificate["tail"] = {{"after_flight", k},       {"speed_upper", v},        {"speed_lower", v_low},
                                   {"window", L},
                                   {"reaction_lower", A_low},   {"reaction_upper", A_high}, {"contraction", Pair(rho)},
                                   {"time_bound", Tmax.hi()},   {"accumulation", Pair(t_end)}};
        events.push_back({{"kind", "accumulation"}, {"contact", 0}, {"time", Pair(t_end)}, {"phase", Pair(Phase(mdl, t_end))},
                          {"velocity_before", {0.0, 0.0}}});
        events.push_back({{"kind", "stick"}, {"contact", 0}, {"time", Pair(t_end)}, {"phase", Pair(Phase(mdl, t_end))},
                          {"velocity_before", {0.0, 0.0}}});
        sequence.push_back("accumulation");
        sequence.push_back("stick");
        stuck = true;
        break;
      }
      V0 = {vplus};
      t = tL;
      start_kind = "impact";
      continue;
    }
    flight["start_window"] = ws;
    flight["landing_center"] = s0;
    flight["landing_box"] = {S.lo(), S.hi()};
    flight["landing"] = Pair(N);
    flight["landing_slope"] = Pair(gp);
    flight["reaction_at_landing"] = Pair(R_land);
    flight["pieces"] = pieces;
    flights.push_back(flight);
    events.push_back({{"kind", "impact"}, {"contact", 0}, {"time", Pair(tL)}, {"phase", Pair(Phase(mdl, tL))}, {"velocity_before", Pair(gp)}});
    sequence.push_back("impact");
    if (R_land.Positive()) {
      ledger.Check(true, "reaction at the landing", land, R_land, "> 0");
      events.push_back({{"kind", "stick"}, {"contact", 0}, {"time", Pair(tL)}, {"phase", Pair(Phase(mdl, tL))}, {"velocity_before", Pair(gp)}});
      sequence.push_back("stick");
      landing_low = (t - tr + Interval(S.lo())).lo();
      t_end = tL;
      stuck = true;
    } else if (R_land.Negative()) {
      ledger.Check(true, "reaction at the landing", land, R_land, "< 0");  // the body departs at once
      events.push_back({{"kind", "departure"}, {"contact", 0}, {"time", Pair(tL)}, {"phase", Pair(Phase(mdl, tL))}, {"velocity_before", {0.0, 0.0}}});
      sequence.push_back("departure");
      t = tL;
      start_kind = "departure";
    } else {
      ledger.Check(false, "reaction at the landing", land, R_land, "!= 0");
      return finish(ledger.failed() + " (the landing meets R = 0: stick or depart is undecided)");
    }
  }
  out.certificate["flights"] = flights;
  if (!stuck) return finish(fmt::format("no landing with R > 0 after {} flights", kMaxFlights));

  // Sticking until the next release t_r + kT.
  const std::string st = "sticking phase";
  const Interval turns = (t_end - tr) / mdl.period;
  const double k = std::floor(turns.lo()) + 1;
  if (!ledger.Check(turns.InsideOpen(k - 1, k), "landing time / T", st, turns, fmt::format("inside ({}, {})", k - 1, k)))
    return finish(ledger.failed() + " (the landing meets a release phase)");
  const int q = static_cast<int>(k);
  if (request.period > 0 && request.period % q != 0)
    return finish(fmt::format("the sticking orbit through the release has period {}, which does not divide {}", q,
                              request.period));
  const Interval kT = Interval(k) * mdl.period;
  const Interval M2R = Abs(kappa) * Sqr(w) / TB;  // |R''| ≤ |κ| ω²/T_B
  const double rate_low = -rate.hi() * (1 - 1e-9);
  const double we = rate_low / M2R.hi();
  const Interval end_margin = Interval(rate_low) - M2R * Interval(we) / Interval(2.0);
  if (!ledger.Check(end_margin.Positive(), "end window b - M2 we/2", st, end_margin, "> 0")) return finish("");
  // R > 0 from a little before the landing (1e-9 relative: a checker's wider enclosure of the
  // landing still lies inside) to 0.1 we into the end window (as for the flights of impact_proof.cpp).
  const double from = landing_low - 1e-9 * (1 + std::abs(landing_low)), to = kT.hi() - 0.9 * we;
  Json stick_pieces = Json::array();
  if (from < to) {
    const auto rpos = ProvePositive(from, to, 0.25 / top, request.max_depth, budget,
                                    [&](double s) { return reaction(tr + Interval(s)); },
                                    [&](const Interval& tau) { return -(kappa * w * Cos(w * (tr + tau))) / TB; });
    if (!rpos.proven) {
      ledger.Check(false, "reaction", fmt::format("{} at t - t_r = {:.17g}", st, rpos.failed_at), rpos.failed_value, "> 0");
      return finish(fmt::format("the reaction is not proven positive over the {}: {}", st, rpos.reason));
    }
    for (const auto& [lo, hi] : rpos.pieces) stick_pieces.push_back({lo, hi});
  }
  out.certificate["sticking"] = {{"periods", q}, {"rate_lower", rate_low}, {"second_derivative_bound", M2R.hi()},
                                 {"end_window", we}, {"pieces", stick_pieces}};
  out.certificate["inequalities"] = ledger.list();

  out.summary["period"] = q;
  out.summary["sequence"] = sequence;
  out.summary["events"] = events;
  out.summary["section"] = {{"time", Pair(tr)}, {"X", Json::array({Pair(mdl.stop)})}, {"V", Json::array({Json::array({0.0, 0.0})})},
                            {"at", "the release"}};
  out.summary["multipliers"] = Json::array();
  out.summary["stability"] = "stable";
  out.summary["stability_note"] =
      "superstable: a one-DOF trajectory that sticks is released from the same state at the same phase";
  out.summary["box_width"] = std::max(t_end.width(), tr.width());
  out.proven = true;
  out.reason = out.certificate.contains("tail")
                   ? fmt::format("exactly one period-{} sticking orbit through the release: release, {} impacts followed, "
                                 "a chattering tail accumulating within {:.1e}, sticking with R > 0 until the next release",
                                 q, flights.size(), t_end.width())
                   : fmt::format("exactly one period-{} sticking orbit through the release: release, {} flight(s) with "
                                 "plastic landings, sticking with R > 0 until the next release", q, flights.size());
  if (request.period > q) StateLeastPeriod(out, request.period);
  return out;
}

}  // namespace vibro::proof
