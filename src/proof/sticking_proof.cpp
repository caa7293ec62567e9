// Proof of a one-DOF sticking orbit with plastic impacts, r = 0 (prove.hpp, docs/prove.md).
//
// On the stop the reaction is R(t) = (ω_1² x0 − κ sin ωt)/T_B, κ = T_A f (the paper's eq. (5) with n = 1).
// The body leaves where R falls through zero: sin φ1 = ω_1² x0/κ with κ cos φ1 > 0 (docs/model.md §4.4),
// t_r = φ1/ω, from rest at x0. Then:
//   1. the flight from (t_r, x0, 0) keeps g > 0 until a landing s* that interval Newton encloses
//      (g(s)/s³ ≥ g'''(0)/6 − M4 s/24 near the release, docs/model.md §2.1; subdivision after);
//   2. the landing is transversal (g' < 0) and R > 0 there: the plastic impact sticks;
//   3. R > 0 from the landing until t_r + kT, k = ⌈s*/T⌉, where the body is released again from the
//      same state: the orbit has period kT.
#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "proof/proof_common.hpp"

namespace vibro::proof {

Outcome ProveSticking1Dof(const IntervalModel& mdl, const ProofRequest& request, const Deadline& deadline) {
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

  // 1. The flight from rest at the release.
  const std::vector<Interval> X0{mdl.stop}, V0{Interval(0.0)};
  const auto gap = [&](const Interval& s) { return ContactSum(mdl, Flight(mdl, tr, X0, V0, s).X) - mdl.stop; };
  const auto slope = [&](const Interval& s) { return ContactSum(mdl, Flight(mdl, tr, X0, V0, s).V); };
  const Interval g3 = kappa * w * Cos(phi1);  // x_B''' at the release: −ω_1²·0 + κ ω cos φ1
  const Interval M4 = DerivativeBound(mdl, tr, X0, V0, 4);
  const std::string fl = "flight from the release";
  if (!ledger.Check(g3.Positive(), "third derivative of the gap", fl, g3, "> 0") ||
      !ledger.Check(M4.finite(), "fourth-derivative bound", fl, M4, "finite"))
    return finish("");
  // Lower bounds a little below the enclosures (a checker's wider enclosure still validates them).
  const double g3_low = g3.lo() * (1 - 1e-9);
  const double ws = 2 * g3_low / M4.hi();
  const Interval start_margin = Interval(g3_low) / Interval(6.0) - M4 * Interval(ws) / Interval(24.0);
  if (!ledger.Check(start_margin.Positive(), "start window g'''/6 - M4 ws/24", fl, start_margin, "> 0"))
    return finish("");
  // The landing, approximately: the first sign change of g after the window, then bisection.
  const double top = std::max(w.hi(), mdl.omega[0].hi()), step = 0.05 / top, T = mdl.period.mid();
  double a = ws, b = ws;
  bool found = false;
  while (b < 1000 * T) {
    a = b;
    b = a + step;
    if (gap(Interval(b)).mid() < 0) {
      found = true;
      break;
    }
    if (deadline.passed()) return finish("time limit reached looking for the landing");
  }
  if (!found) return finish("the body does not land within 1000 periods of the release");
  for (int it = 0; it < 200 && b - a > 4e-16 * b; ++it) {
    const double c = a + (b - a) / 2;
    (gap(Interval(c)).mid() > 0 ? a : b) = c;
  }
  const double s0 = a + (b - a) / 2;
  // Interval Newton: N(S) = s0 − g(s0)/g'(S) ⊂ int S and g' < 0 on S ⇒ exactly one root in S.
  Interval S, N, gp;
  bool newton = false;
  double radius = request.box_radius * (1 + s0);
  for (int attempt = 0; attempt < 4 && !newton; ++attempt, radius *= 4) {
    S = Interval::Hull(s0 - radius, s0 + radius);
    gp = slope(S);
    N = Interval(s0) - gap(Interval(s0)) / gp;
    newton = gp.Negative() && N.InsideOpen(S.lo(), S.hi());
  }
  const std::string land = "landing";
  if (!ledger.Check(gp.Negative(), "contact velocity at the landing", land, gp, "< 0") ||
      !ledger.Check(N.InsideOpen(S.lo(), S.hi()), "interval Newton", land, N,
                    "inside the box"))
    return finish("");
  const Interval after_window = Interval(S.lo()) - Interval(ws);
  if (!ledger.Check(after_window.Positive(), "landing after the start window", land, after_window, "> 0"))
    return finish("");
  const auto pos = ProvePositive(ws, S.lo(), 0.25 / top, request.max_depth, deadline,
                                 [&](double s) { return gap(Interval(s)); }, slope);
  if (!pos.proven) {
    ledger.Check(false, "gap", fmt::format("{} at s = {:.17g}", fl, pos.failed_at), pos.failed_value, "> 0");
    return finish(fmt::format("the gap is not proven positive on the {}: {}", fl, pos.reason));
  }
  Json gap_pieces = Json::array();
  for (const auto& [lo, hi] : pos.pieces) gap_pieces.push_back({lo, hi});
  const Interval tL = tr + N;
  const Interval R_land = (w1s * mdl.stop - kappa * Sin(w * tL)) / TB;
  if (!ledger.Check(R_land.Positive(), "reaction at the landing", land, R_land, "> 0"))
    return finish(ledger.failed() + " (the plastic impact does not stick)");
  out.certificate["flight"] = {{"third_derivative", Pair(g3)}, {"third_derivative_lower", g3_low}, {"fourth_derivative_bound", M4.hi()},
                               {"start_window", ws}, {"landing_center", s0}, {"landing_box", {S.lo(), S.hi()}}, {"landing", Pair(N)},
                               {"landing_slope", Pair(gp)}, {"pieces", gap_pieces}};

  // 3. Sticking until the next release t_r + kT.
  const Interval turns = N / mdl.period;
  const double k = std::floor(turns.lo()) + 1;
  if (!ledger.Check(turns.InsideOpen(k - 1, k), "landing time / T", land, turns, fmt::format("inside ({}, {})", k - 1, k)))
    return finish(ledger.failed() + " (the landing meets a release phase)");
  const int q = static_cast<int>(k);
  if (request.period > 0 && request.period != q)
    return finish(fmt::format("the sticking orbit through the release has period {}, not {}", q, request.period));
  const Interval kT = Interval(k) * mdl.period;
  const Interval M2R = Abs(kappa) * Sqr(w) / TB;  // |R''| ≤ |κ| ω²/T_B
  const double rate_low = -rate.hi() * (1 - 1e-9);
  const double we = rate_low / M2R.hi();
  const Interval end_margin = Interval(rate_low) - M2R * Interval(we) / Interval(2.0);
  const std::string st = "sticking phase";
  if (!ledger.Check(end_margin.Positive(), "end window b - M2 we/2", st, end_margin, "> 0")) return finish("");
  const auto reaction = [&](const Interval& tau) { return (w1s * mdl.stop - kappa * Sin(w * (tr + tau))) / TB; };
  const auto reaction_rate = [&](const Interval& tau) { return -(kappa * w * Cos(w * (tr + tau))) / TB; };
  Json stick_pieces = Json::array();
  // From the landing box's lower end (a certificate number, below the landing) to 0.1 we into the
  // end window (as for the flights of impact_proof.cpp).
  if (S.lo() < kT.hi() - 0.9 * we) {
    const auto rpos = ProvePositive(S.lo(), kT.hi() - 0.9 * we, 0.25 / top, request.max_depth, deadline,
                                    [&](double s) { return reaction(Interval(s)); }, reaction_rate);
    if (!rpos.proven) {
      ledger.Check(false, "reaction", fmt::format("{} at t - t_r = {:.17g}", st, rpos.failed_at), rpos.failed_value, "> 0");
      return finish(fmt::format("the reaction is not proven positive over the {}: {}", st, rpos.reason));
    }
    for (const auto& [lo, hi] : rpos.pieces) stick_pieces.push_back({lo, hi});
  }
  out.certificate["sticking"] = {{"periods", q}, {"rate_lower", rate_low}, {"second_derivative_bound", M2R.hi()}, {"end_window", we},
                                 {"pieces", stick_pieces}};
  out.certificate["inequalities"] = ledger.list();

  out.summary["period"] = q;
  out.summary["sequence"] = {"release", "impact", "stick"};
  out.summary["events"] = Json::array(
      {{{"kind", "release"}, {"time", Pair(tr)}, {"phase", Pair(Phase(mdl, tr))}, {"velocity_before", {0.0, 0.0}}},
       {{"kind", "impact"}, {"time", Pair(tL)}, {"phase", Pair(Phase(mdl, tL))}, {"velocity_before", Pair(gp)}},
       {{"kind", "stick"}, {"time", Pair(tL)}, {"phase", Pair(Phase(mdl, tL))}, {"velocity_before", Pair(gp)}}});
  out.summary["section"] = {{"time", Pair(tr)}, {"X", Json::array({Pair(mdl.stop)})}, {"V", Json::array({Json::array({0.0, 0.0})})},
                            {"at", "the release"}};
  out.summary["multipliers"] = Json::array();
  out.summary["stability"] = "stable";
  out.summary["stability_note"] =
      "superstable: a one-DOF trajectory that sticks is released from the same state at the same phase";
  out.summary["box_width"] = std::max(N.width(), tr.width());
  out.proven = true;
  out.reason = fmt::format("exactly one period-{} sticking orbit through the release: release, flight, plastic landing "
                           "with R > 0, sticking with R > 0 until the next release", q);
  return out;
}

}  // namespace vibro::proof
