// Two-parameter curves of codimension-one points (see include/vibro/two_parameter.hpp).
#include "vibro/two_parameter.hpp"

#include <algorithm>
#include <cmath>
#include <optional>

#include <fmt/format.h>

#include "vibro/orbit_from_state.hpp"
#include "vibro/system.hpp"

namespace vibro {

const std::vector<std::string>& CurveKinds() {
  static const std::vector<std::string> kinds = {"fold",    "flip",          "neimark-sacker", "branch-point",
                                                 "grazing", "sticking-lost", "sticking-entry", "rising",
                                                 "simultaneous"};
  return kinds;
}

namespace {

using Vec2 = Eigen::Vector2d;

// What the corrector needs to start Newton next to a curve point: the orbit there.
struct Seed {
  Vec2 u;  // where the orbit is (scaled)
  int period = 1;
  double section_time = 0, frequency = 1;
  Eigen::VectorXd X, V;
  std::string signature, sequence;
  std::vector<std::complex<double>> multipliers;
  bool stable = false;
};

struct Found {
  Vec2 u;          // the curve point (scaled)
  double bracket;  // along the line, scaled
  Bifurcation bif;
  Seed seed;    // Newton's start for the next corrector (the line's first orbit) and the
                // multipliers of the orbit next to the point (codimension-two tests)
  Vec2 near_u;  // where that orbit next to the point is (scaled)
};

// Test quantities of the smooth bifurcations, from the multipliers of an orbit next to the curve:
// Π(μ − 1) (a real multiplier through +1), Π(μ + 1) (through −1), and the modulus of the largest
// complex pair minus 1 (NaN without a complex pair).
double FoldTest(const std::vector<std::complex<double>>& mu) {
  std::complex<double> p = 1;
  for (const auto& m : mu) p *= m - 1.0;
  return mu.empty() ? std::nan("") : p.real();
}
double FlipTest(const std::vector<std::complex<double>>& mu) {
  std::complex<double> p = 1;
  for (const auto& m : mu) p *= m + 1.0;
  return mu.empty() ? std::nan("") : p.real();
}
double TorusTest(const std::vector<std::complex<double>>& mu) {
  double best = -1;
  for (const auto& m : mu)
    if (std::abs(m.imag()) > 1e-9) best = std::max(best, std::abs(m));
  return best < 0 ? std::nan("") : best - 1.0;
}

class Tracer {
 public:
  explicit Tracer(const CurveRequest& req) : req_(req) {
    lo_ << req.lo1, req.lo2;
    width_ << req.hi1 - req.lo1, req.hi2 - req.lo2;
  }

  Vec2 Param(const Vec2& u) const { return lo_ + u.cwiseProduct(width_); }
  Vec2 Scaled(double v1, double v2) const { return (Vec2(v1, v2) - lo_).cwiseQuotient(width_); }
  bool stopped() const { return req_.stop_requested && req_.stop_requested->load(); }
  int corrections() const { return corrections_; }

  // Continues the orbit `seed` (moved to S by Newton) along the line u = S + s ν, s ∈ [0, L], and
  // returns the first bifurcation of the requested kind on it, with the orbit next to it.
  // `inside`: the next corrector's seed is the recorded orbit nearest to the point that lies at least
  // this far inside the family (along the line).
  std::optional<Found> Locate(const Vec2& S, const Vec2& nu, double L, const Seed& seed, double inside,
                              std::string& why) {
    ++corrections_;
    ContinuationRequest cr;
    try {
      cr = LineRequest(S, nu, L, seed);
    } catch (const std::exception& e) {
      why = fmt::format("the scene is not valid at the corrector's start: {}", e.what());
      return std::nullopt;
    }
    const Branch br = Continue(cr);
    if (br.points.empty()) {
      why = "no orbit at the corrector's start (" + br.end + ")";
      return std::nullopt;
    }
    const auto& first = br.points.front();
    if (!seed.signature.empty() && (first.signature != seed.signature || first.sequence != seed.sequence)) {
      why = fmt::format("the orbit at the corrector's start is of another family (events {} → {})", seed.signature,
                        first.signature);
      return std::nullopt;
    }
    const Bifurcation* hit = nullptr;
    for (const auto& b : br.bifurcations) {
      const int c = b.contact < 0 ? 0 : b.contact;
      if (b.kind == req_.kind && (req_.contact < 0 || c == req_.contact)) {
        hit = &b;
        break;
      }
    }
    if (!hit) {
      std::string met;
      for (const auto& b : br.bifurcations) met += (met.empty() ? "" : ", ") + b.kind;
      why = fmt::format("no {} on the corrector line (met: {}; {})", req_.kind, met.empty() ? "nothing" : met, br.end);
      return std::nullopt;
    }
    // The orbit next to it: the last recorded point before it, while the line parameter grows
    // (after a fold the branch comes back on its other sheet).
    const BranchPoint* near = &first;
    for (size_t i = 1; i < br.points.size(); ++i) {
      const auto& p = br.points[i];
      if (p.value < br.points[i - 1].value || p.value > hit->value) break;
      near = &p;
    }
    Found f;
    f.u = S + hit->value * nu;
    f.bracket = hit->bracket;
    f.bif = *hit;
    // The next corrector starts Newton from the line's first orbit, a step inside the family: the
    // orbit next to the bifurcation is degenerate there (a sticking phase of zero length, a grazing
    // flight), and Newton from it a step away may land on another family.
    const BranchPoint* base = &first;
    for (size_t i = 1; i < br.points.size(); ++i) {
      const auto& p = br.points[i];
      if (p.value < br.points[i - 1].value || p.value > hit->value - inside) break;
      base = &p;
    }
    f.seed = SeedOf(*base, S + base->value * nu, cr.scene_at(base->value).frequency);
    f.seed.multipliers = near->multipliers;
    f.seed.stable = near->stable;
    f.near_u = S + near->value * nu;
    // A closer orbit for the codimension-two tests (multipliers at the curve, not a step away):
    // Newton at 1e-6 of the line before the point, from the recorded one.
    const double s_close = hit->value - std::max(1e-6 * L, 4.0 * hit->bracket);
    if (s_close > near->value) {
      try {
        const Scene sc = cr.scene_at(s_close);
        const System sys(sc);
        OrbitRequest oreq;
        oreq.kind = OrbitKind::kAuto;
        oreq.period = seed.period;
        oreq.transient_periods = 0;
        oreq.start = InitialOverride{near->section_time * cr.scene_at(near->value).frequency / sc.frequency, near->X,
                                     near->V};
        const OrbitResult o = SolveOrbit(sys, sc, oreq);
        if (o.status == "converged" && o.no_jacobian.empty() && o.distance_from_start && *o.distance_from_start < 1e-2) {
          f.seed.multipliers = o.multipliers;
          f.seed.stable = o.stable;
        }
      } catch (const std::exception&) {
      }
    }
    return f;
  }

  // The first bifurcation met by continuing the orbit `seed` along u = seed.u + s·dir, s ∈ [0, L]
  // (none: nothing met), with where it is (scaled).
  std::optional<std::pair<Bifurcation, Vec2>> FirstAlong(const Seed& seed, const Vec2& dir, double L) {
    const Vec2 S = seed.u;
    try {
      const Branch br = Continue(LineRequest(S, dir, L, seed));
      if (br.bifurcations.empty()) return std::nullopt;
      const auto& b = br.bifurcations.front();
      return std::make_pair(b, Vec2(S + b.value * dir));
    } catch (const std::exception&) {
      return std::nullopt;
    }
  }

  // The continuation of the orbit `seed` along the line u = S + s·dir, s ∈ [0, L], in the line
  // parameter s. Throws when the scene is not valid at the line's start.
  ContinuationRequest LineRequest(const Vec2& S, const Vec2& dir, double L, const Seed& seed) const {
    ContinuationRequest cr;
    cr.scene_at = [this, S, dir](double s) {
      const Vec2 p = Param(S + s * dir);
      return req_.scene_at(p[0], p[1]);
    };
    const Scene at = cr.scene_at(0.0);
    cr.from = 0.0;
    cr.to = L;
    cr.step = L / 8;
    cr.max_step = 4 * L;  // arclength in (z, λ): the state may change far faster than λ
    cr.max_points = 400;
    cr.orbit.kind = OrbitKind::kAuto;
    cr.orbit.period = seed.period;
    cr.orbit.transient_periods = 0;
    // The same forcing phase at the section as the seed's (the frequency may change along the line).
    cr.orbit.start = InitialOverride{seed.section_time * seed.frequency / at.frequency, seed.X, seed.V};
    cr.stop_requested = req_.stop_requested;
    return cr;
  }

  Seed SeedOf(const BranchPoint& p, const Vec2& u, double frequency) const {
    Seed s;
    s.u = u;
    s.period = seed_period_;
    s.section_time = p.section_time;
    s.frequency = frequency;
    s.X = p.X;
    s.V = p.V;
    s.signature = p.signature;
    s.sequence = p.sequence;
    s.multipliers = p.multipliers;
    s.stable = p.stable;
    return s;
  }
  void SetPeriod(int q) { seed_period_ = q; }

  CurvePoint PointOf(const Found& f) const {
    CurvePoint c;
    const Vec2 p = Param(f.u), o = Param(f.near_u);
    c.value1 = p[0];
    c.value2 = p[1];
    c.bracket = f.bracket;
    c.detail = f.bif.detail;
    c.contact = f.bif.contact;
    c.rotation_number = f.bif.rotation_number;
    c.orbit1 = o[0];
    c.orbit2 = o[1];
    c.section_time = f.seed.section_time;
    c.X = f.seed.X;
    c.V = f.seed.V;
    c.multipliers = f.seed.multipliers;
    c.stable = f.seed.stable;
    c.signature = f.seed.signature;
    c.sequence = f.seed.sequence;
    return c;
  }

 private:
  const CurveRequest& req_;
  Vec2 lo_, width_;
  int corrections_ = 0;
  int seed_period_ = 1;
};

Vec2 Perp(const Vec2& v) { return Vec2(-v[1], v[0]); }

bool InBox(const Vec2& u) { return u[0] >= -1e-12 && u[0] <= 1 + 1e-12 && u[1] >= -1e-12 && u[1] <= 1 + 1e-12; }

// The codimension-two tests that apply on a curve of `kind`: (name, test).
struct Test {
  std::string name;
  double (*f)(const std::vector<std::complex<double>>&);
};
std::vector<Test> TestsFor(const std::string& kind) {
  std::vector<Test> t;
  const bool smooth_fold = kind == "fold" || kind == "branch-point";
  const auto name = [&](const char* other) {
    // Smooth pairs by their usual names, ordered fold < flip < neimark-sacker; non-smooth
    // curves as "KIND-OTHER" (e.g. grazing-flip: a grazing curve meets a flip curve).
    return kind + "-" + other;
  };
  if (!smooth_fold) t.push_back({kind == "flip" ? std::string("fold-flip") : kind == "neimark-sacker" ? "fold-neimark-sacker" : name("fold"), FoldTest});
  if (kind != "flip") t.push_back({kind == "fold" ? std::string("fold-flip") : name("flip"), FlipTest});
  if (kind != "neimark-sacker")
    t.push_back({kind == "fold" ? std::string("fold-neimark-sacker") : kind == "flip" ? "flip-neimark-sacker" : name("neimark-sacker"),
                 TorusTest});
  return t;
}

}  // namespace

Curve TraceCurve(const CurveRequest& req) {
  Curve curve;
  curve.kind = req.kind;
  curve.contact = req.contact;
  curve.period = req.period;
  Tracer tr(req);
  tr.SetPeriod(req.period);
  const Scene first_scene = req.scene_at(req.start1, req.start2);
  Seed seed0;
  seed0.u = tr.Scaled(req.start1, req.start2);
  seed0.period = req.period;
  seed0.section_time = req.section_time;
  seed0.frequency = first_scene.frequency;
  seed0.X = req.X;
  seed0.V = req.V;  // signature empty: the first line takes the family Newton finds at the start
  Vec2 d = Vec2(req.dir1, req.dir2).cwiseQuotient(Vec2(req.hi1 - req.lo1, req.hi2 - req.lo2));
  const double reach = req.reach * d.norm();
  d.normalize();
  std::string why;
  const auto start = tr.Locate(seed0.u, d, reach * 1.05 + 1e-9, seed0, 0.5 * req.step, why);
  if (!start) {
    curve.status = tr.stopped() ? "interrupted" : "no-start";
    curve.end_start = curve.end_finish = "the " + req.kind + " was not found from the start: " + why;
    curve.corrections = tr.corrections();
    return curve;
  }
  const double h_min = 1e-7;
  const auto tests = TestsFor(req.kind);

  // One half of the curve from the start point, in the direction σ·perp(ν0).
  struct Half {
    std::vector<CurvePoint> points;
    std::vector<CodimTwoPoint> special;  // `after` counts from the start point (0: start → first)
    std::string end;
    bool closed = false;
  };
  const auto trace = [&](double sigma) {
    Half half;
    Found cur = *start;
    Vec2 nu = d, tau = sigma * Perp(d);
    double h = std::min(req.step, req.max_step), h_end = h;
    std::string last_failure;
    for (int k = 0; k < req.max_points; ++k) {
      if (tr.stopped()) {
        half.end = "interrupted";
        return half;
      }
      std::optional<Found> next;
      Vec2 t_new, nu_new;
      // Corrector from cur with step h along τ (the line τ·(u − P) = 0, from the family's side).
      // The line reaches `wide` steps to either side of P: more than one while the tangent is not
      // known from a secant (the first step of each half: the start's line need not be normal to
      // the curve) or when the line missed the curve.
      const auto correct = [&](double step, std::string& w, double wide = 1.0) -> std::optional<Found> {
        const Vec2 P = cur.u + step * tau;
        if (!InBox(P)) {
          w = "the predictor leaves the box";
          return std::nullopt;
        }
        const double dd = std::max(step, 1e-9) * wide;
        auto f = tr.Locate(P - dd * nu, nu, 2.0 * dd, cur.seed, 0.5 * std::max(step, 1e-9), w);
        if (!f && wide < 8 && w.rfind("no " + req.kind + " on the corrector line (met: nothing", 0) == 0)
          f = tr.Locate(P - 4 * dd * nu, nu, 8.0 * dd, cur.seed, 0.5 * std::max(step, 1e-9), w);
        return f;
      };
      // A predictor past the box's edge is cut to the edge (a little inside it).
      for (int side = 0; side < 2; ++side)
        for (const double edge : {0.0, 1.0}) {
          const double to_edge = (edge - cur.u[side]) / tau[side];
          if (tau[side] != 0 && to_edge > 0 && to_edge < h) h = std::max(to_edge * (1 - 1e-9), 0.0);
        }
      if (h < h_min) {
        half.end = "reached the edge of the box";
        return half;
      }
      while (true) {
        if (tr.stopped()) {
          half.end = "interrupted";
          return half;
        }
        next = correct(h, last_failure, half.points.empty() ? 8.0 : 1.0);
        if (next) {
          t_new = (next->u - cur.u).normalized();
          if (t_new.dot(tau) > std::cos(M_PI / 6) || h <= 4 * h_min) break;
          last_failure = fmt::format("the curve turns by {:.0f}° over one step", std::acos(std::clamp(t_new.dot(tau), -1.0, 1.0)) * 180 / M_PI);
          next.reset();
        }
        if (h <= h_min) break;
        h = std::max(0.5 * h, h_min);
      }
      if (!next) {
        const double margin = std::min({cur.u[0], 1 - cur.u[0], cur.u[1], 1 - cur.u[1]});
        if (margin < 1e-6) {
          half.end = "reached the edge of the box";
          return half;
        }
        half.end = fmt::format("the curve could not be continued past ({:.12g}, {:.12g}): {}",
                               tr.Param(cur.u)[0], tr.Param(cur.u)[1], last_failure);
        // What ends it: the family, continued from its orbit next to the end along the curve's
        // tangent, meets another boundary within a few steps (a corner of the family's region:
        // a codimension-two point where the two curves meet).
        if (!tr.stopped())
          if (const auto other = tr.FirstAlong(cur.seed, tau, std::max(4.0 * h_end, 1e-4));
              other && other->first.kind != req.kind) {
            const Vec2 at = tr.Param(other->second);
            CodimTwoPoint c;
            c.kind = req.kind + "-" + other->first.kind;
            c.value1 = at[0];
            c.value2 = at[1];
            c.bracket = (other->second - cur.u).norm();
            c.after = half.points.size();
            c.detail = fmt::format("the {} curve ends where the family meets a {} boundary ({}): a corner of the "
                                   "region where the orbit exists",
                                   req.kind, other->first.kind, other->first.detail);
            half.special.push_back(c);
            half.end = fmt::format("the curve ends at ({:.12g}, {:.12g}), where it meets a {} curve (codimension two)",
                                   at[0], at[1], other->first.kind);
          }
        return half;
      }
      if (!InBox(next->u)) {  // kept when just past the edge (the predictor stopped at it)
        if ((next->u - next->u.cwiseMax(0.0).cwiseMin(1.0)).norm() < 0.5 * h) half.points.push_back(tr.PointOf(*next));
        half.end = "left the box";
        return half;
      }
      nu_new = Perp(t_new);
      if (nu_new.dot(nu) < 0) nu_new = -nu_new;
      // Codimension-two points: another test quantity changes sign between cur and next.
      for (const auto& test : tests) {
        const double a = test.f(cur.seed.multipliers), b = test.f(next->seed.multipliers);
        if (!(std::isfinite(a) && std::isfinite(b)) || a * b >= 0) continue;
        // Bisection of the step from cur.
        double lo = 0, hi = h, fa = a;
        Vec2 u_lo = cur.u, u_hi = next->u;
        for (int it = 0; it < 18 && !tr.stopped(); ++it) {
          const double mid = 0.5 * (lo + hi);
          std::string w;
          const auto m = correct(mid, w);
          if (!m) break;
          const double fm = test.f(m->seed.multipliers);
          if (!std::isfinite(fm)) break;
          if ((fm > 0) == (fa > 0)) {
            lo = mid;
            u_lo = m->u;
          } else {
            hi = mid;
            u_hi = m->u;
          }
        }
        const Vec2 at = tr.Param(0.5 * (u_lo + u_hi));
        CodimTwoPoint c;
        c.kind = test.name;
        c.value1 = at[0];
        c.value2 = at[1];
        c.bracket = (u_hi - u_lo).norm();
        c.after = half.points.size();
        c.detail = test.f == FlipTest   ? "a real multiplier of the orbit crosses −1 on the curve"
                   : test.f == FoldTest ? "a real multiplier of the orbit crosses +1 on the curve"
                                        : "a complex pair of multipliers of the orbit crosses the unit circle on the curve";
        half.special.push_back(c);
      }
      half.points.push_back(tr.PointOf(*next));
      if (req.progress) req.progress(half.points.size(), half.points.back().value1, half.points.back().value2);
      // A closed curve: back at the start, heading the same way.
      if (half.points.size() > 3 && (next->u - start->u).norm() < 0.75 * h && t_new.dot(sigma * Perp(d)) > 0) {
        half.end = "the curve closes";
        half.closed = true;
        return half;
      }
      tau = t_new;
      nu = nu_new;
      cur = *next;
      h_end = h;
      h = std::min(1.5 * h, req.max_step);
    }
    half.end = "max points";
    return half;
  };
  Half forward = trace(1.0);
  Half backward;
  if (req.both_ways && !forward.closed && forward.end != "interrupted") backward = trace(-1.0);
  // The curve in order: the backward half reversed, the start, the forward half.
  for (auto it = backward.points.rbegin(); it != backward.points.rend(); ++it) curve.points.push_back(*it);
  const size_t s = curve.points.size();
  curve.points.push_back(tr.PointOf(*start));
  for (auto& p : forward.points) curve.points.push_back(std::move(p));
  for (auto c : backward.special) {  // between backward points after−1 and after (after = 0: the start)
    c.after = s - 1 - c.after;
    curve.special.push_back(c);
  }
  for (auto c : forward.special) {
    c.after = s + c.after;
    curve.special.push_back(c);
  }
  std::sort(curve.special.begin(), curve.special.end(), [](const auto& a, const auto& b) { return a.after < b.after; });
  curve.end_start = req.both_ways ? (forward.closed ? "the curve closes" : backward.end) : "one way only";
  curve.end_finish = forward.end;
  if (forward.end == "interrupted" || backward.end == "interrupted") curve.status = "interrupted";
  curve.corrections = tr.corrections();
  return curve;
}

}  // namespace vibro
