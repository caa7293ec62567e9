// Pseudo-arclength continuation of periodic orbits (see include/vibro/continuation.hpp).
#include "vibro/continuation.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include <fmt/format.h>

#include "analysis/orbit_probe.hpp"
#include "vibro/observer.hpp"
#include "vibro/orbit_from_state.hpp"

namespace vibro {
namespace {

struct Evaluation {
  Eigen::VectorXd G;   // F(z; λ) − z
  Eigen::MatrixXd Jz;  // DF − I
  Eigen::VectorXd Jl;  // ∂F/∂λ
  bool ok = false;
};

// A corrected point of the branch with what is known about its orbit.
struct Point {
  Eigen::VectorXd y;  // (z, λ)
  Evaluation eval;    // G, DF − I and ∂F/∂λ at y
  OrbitResult orbit;
  OrbitProbe probe;
};

// A corrected point and the evaluation of the map there.
struct Corrected {
  Eigen::VectorXd y;
  Evaluation eval;
};

// The map F(z; λ) on the section ωt0 = phase (so a change of ω keeps the section's forcing phase).
class Problem {
 public:
  Problem(const ContinuationRequest& req, double phase, int q) : req_(req), phase_(phase), q_(q) {}

  std::optional<Scene> SceneAt(double lambda) const {
    try {
      return req_.scene_at(lambda);
    } catch (const std::exception&) {
      return std::nullopt;  // λ left the valid range of the key
    }
  }
  double SectionTime(const Scene& s) const { return phase_ / s.frequency; }
  double phase() const { return phase_; }
  int period() const { return q_; }
  void MoveSection(double phase) { phase_ = phase; }

  // The scene at λ in the precision that decides its chattering sequences: double, or quad at the
  // values of λ where double left one undetermined (a map evaluation there switched).
  std::optional<Scene> DecidingSceneAt(double lambda) const {
    auto scene = SceneAt(lambda);
    if (scene && std::find(quad_at_.begin(), quad_at_.end(), lambda) != quad_at_.end())
      scene->run.precision = Precision::kQuad;
    return scene;
  }

  std::optional<Eigen::VectorXd> Map(const Eigen::VectorXd& z, double lambda,
                                     Eigen::MatrixXd* jac) const {
    auto scene = SceneAt(lambda);
    if (!scene) return std::nullopt;
    const System sys(*scene);
    const auto n = sys.dof();
    MapValue m = StroboscopicMap(sys, *scene, SectionTime(*scene), z.head(n), z.tail(n), q_);
    // Near the end of a sticking branch the double engine's chattering tails can reach the
    // rounding floor of ẋ_B before their accumulation point is predicted within the tolerance
    // (docs/chattering.md): the map is then evaluated with the quad engine instead, so that the
    // boundary is located where the motion changes, not where double precision gives out.
    if (m.status == RunStatus::kUndetermined && scene->run.precision == Precision::kDouble &&
        scene->run.engine == Engine::kExact) {
      scene->run.precision = Precision::kQuad;
      m = StroboscopicMap(sys, *scene, SectionTime(*scene), z.head(n), z.tail(n), q_);
      ++quad_evaluations_;
      if (m.status == RunStatus::kOk &&
          std::find(quad_at_.begin(), quad_at_.end(), lambda) == quad_at_.end())
        quad_at_.push_back(lambda);
    }
    if (m.status == RunStatus::kUndetermined) undetermined_ = true;
    if (m.status != RunStatus::kOk || m.singular) return std::nullopt;
    // An event the tangent map does not cover (a simultaneous impact of coupled contacts, a set
    // of contacts held at once; docs/contacts.md): no derivative, so no Newton step and no
    // multipliers there.
    if (jac && !m.undefined.empty()) {
      no_jacobian_ = m.undefined;
      return std::nullopt;
    }
    if (jac) *jac = m.jacobian;
    Eigen::VectorXd out(2 * n);
    out << m.X, m.V;
    return out;
  }

  Evaluation Evaluate(const Eigen::VectorXd& z, double lambda) const {
    Evaluation e;
    Eigen::MatrixXd DF;
    const auto F = Map(z, lambda, &DF);
    const double h = 1e-6 * std::max(1.0, std::abs(lambda));
    const auto Fp = Map(z, lambda + h, nullptr), Fm = Map(z, lambda - h, nullptr);
    // At an end of the key's valid range (a damping ratio of 0): a one-sided difference.
    if (!F || (!Fp && !Fm)) return e;
    e.G = *F - z;
    e.Jz = DF - Eigen::MatrixXd::Identity(z.size(), z.size());
    e.Jl = Fp && Fm ? Eigen::VectorXd((*Fp - *Fm) / (2 * h)) : Fp ? Eigen::VectorXd((*Fp - *F) / h)
                                                                  : Eigen::VectorXd((*F - *Fm) / h);
    // Within h of a non-smooth point of the map in λ (a grazing: F has a square-root term past
    // it), one of the two one-sided differences spans it and the central difference is wrong by
    // O(1/√h): the tangent and the corrector would then leave the branch (a false fold, a
    // boundary located h away). Each side is checked against the difference over h/2; a side
    // whose two differences disagree beyond the O(h) of a smooth map is not used.
    if (Fp && Fm) {
      const Eigen::VectorXd dp = (*Fp - *F) / h, dm = (*F - *Fm) / h;
      const double scale = 1.0 + dp.cwiseAbs().maxCoeff() + dm.cwiseAbs().maxCoeff();
      if ((dp - dm).cwiseAbs().maxCoeff() > 1e-3 * scale) {
        const auto smooth_side = [&](double sign, const Eigen::VectorXd& d) {
          const auto Fh = Map(z, lambda + sign * 0.5 * h, nullptr);
          if (!Fh) return false;
          const Eigen::VectorXd d_half = sign * (*Fh - *F) / (0.5 * h);
          return (d - d_half).cwiseAbs().maxCoeff() < 1e-4 * scale;
        };
        const bool plus = smooth_side(1.0, dp), minus = smooth_side(-1.0, dm);
        if (plus != minus) e.Jl = plus ? dp : dm;
      }
    }
    e.ok = true;
    return e;
  }

  // The orbit at y = (z, λ): summary, multipliers and event probe.
  std::optional<Point> Examine(const Corrected& c) const {
    const Eigen::VectorXd& y = c.y;
    const auto N = y.size() - 1;
    const double lambda = y[N];
    const auto scene = DecidingSceneAt(lambda);
    if (!scene) return std::nullopt;
    const System sys(*scene);
    const auto n = sys.dof();
    Point pt;
    pt.y = y;
    pt.eval = c.eval;
    OrbitResult& o = pt.orbit;
    o.status = "converged";
    o.period = q_;
    o.section_time = SectionTime(*scene);
    o.X = y.head(n);
    o.V = y.segment(n, n);
    o.monodromy = c.eval.Jz + Eigen::MatrixXd::Identity(2 * n, 2 * n);
    Characterize(sys, *scene, o);
    pt.probe = ProbeOrbit(sys, *scene, o.section_time, o.X, o.V, q_, 256);
    if (!pt.probe.ok) return std::nullopt;
    return pt;
  }

  // Map evaluations done in quad precision, and whether one stayed undetermined even so (or
  // could not switch: CVODE, or a scene quad does not cover).
  int quad_evaluations() const { return quad_evaluations_; }
  bool undetermined() const { return undetermined_; }
  void ClearUndetermined() {
    undetermined_ = false;
    no_jacobian_.clear();
  }
  // Why the last map evaluation that failed for lack of a derivative had none (empty: none failed so).
  const std::string& no_jacobian() const { return no_jacobian_; }

 private:
  const ContinuationRequest& req_;
  double phase_;
  int q_;
  mutable std::vector<double> quad_at_;  // the λ values at which the map switched to quad
  mutable int quad_evaluations_ = 0;
  mutable bool undetermined_ = false;
  mutable std::string no_jacobian_;
};

// Every impact of q periods of the orbit from the free state (X, V) at t0.
std::vector<BranchPoint::Impact> ImpactsOf(const System& sys, const Scene& scene, double t0,
                                           const Eigen::VectorXd& X, const Eigen::VectorXd& V, int q) {
  struct Log final : Observer {
    std::vector<Event> impacts;
    void OnEvent(const Event& e) override {
      if (e.kind == EventKind::kImpact) impacts.push_back(e);
    }
  } log;
  Scene sc = scene;
  sc.initial_time = t0;
  sc.run.periods = q;
  sc.run.samples_per_period = 0;
  const InitialOverride here{t0, X, V};
  SimulationOptions opt;
  opt.initial = &here;
  opt.observers = {&log};
  Simulate(sys, sc, opt);
  const double cycle = 2.0 * M_PI * q, w = sys.frequency();
  std::vector<BranchPoint::Impact> out;
  for (const auto& e : log.impacts) {
    const double phase = std::fmod(std::fmod(w * t0, cycle) + 2.0 * M_PI * static_cast<double>(e.clock.period) +
                                       w * e.clock.offset,
                                   cycle);
    out.push_back({phase, e.v_before, e.v_after, e.contact});
  }
  return out;
}

// The stroboscopic state (docs/output.md, `strobe`): every contact's coordinate w_jᵀq = σ_j c_jᵀX
// at the time t ≡ t_s (mod qT), t_s the scene's start time (initial.time), the last such time up
// to the section t0 (the orbit is qT-periodic: any one gives the same state). The same forcing
// phase as a sweep's section points t_s + kT (src/studies/studies.cpp), wherever the section sits.
// NaN per contact when the period could not be simulated.
std::vector<double> StrobeOf(const System& sys, const Scene& scene, double t0, const Eigen::VectorXd& X,
                             const Eigen::VectorXd& V, int q) {
  struct Last final : Observer {
    std::optional<Eigen::VectorXd> X;
    void OnSection(const Sample& s) override { X = s.X; }
  } last;
  const double cycle = q * 2.0 * M_PI / sys.frequency();
  const double origin = scene.initial_time + std::floor((t0 - scene.initial_time) / cycle) * cycle;
  std::vector<double> out(static_cast<size_t>(sys.contact_count()), std::numeric_limits<double>::quiet_NaN());
  Eigen::VectorXd at = X;
  if (t0 - origin > 0) {  // otherwise the section is a strobe time itself
    // The simulator takes an origin within one forcing period before the start: the start of
    // the start's own period, j periods after `origin`, and q − j periods from there to the
    // strobe time origin + qT (a section of a q-periodic orbit may lie in any of its q periods).
    const double T = 2.0 * M_PI / sys.frequency();
    const int j = std::clamp(static_cast<int>(std::floor((t0 - origin) / T)), 0, q - 1);
    Scene sc = scene;
    sc.run.periods = q - j;
    sc.run.samples_per_period = 0;
    const InitialOverride here{t0, X, V};
    SimulationOptions opt;
    opt.initial = &here;
    opt.section_origin = origin + j * T;
    opt.observers = {&last};
    opt.loads = false;
    if (Simulate(sys, sc, opt).status != RunStatus::kOk || !last.X) return out;
    at = *last.X;
  }
  for (int j = 0; j < sys.contact_count(); ++j) {
    const ContactModel& c = sys.contacts()[static_cast<size_t>(j)];
    out[static_cast<size_t>(j)] = (c.spec.side == Side::kAbove ? -1.0 : 1.0) * c.shape.dot(at);
  }
  return out;
}

// Unit null vector of the 2n × (2n+1) matrix [Jz Jλ], oriented like `previous`.
Eigen::VectorXd Tangent(const Evaluation& e, const Eigen::VectorXd& previous) {
  Eigen::MatrixXd A(e.Jz.rows(), e.Jz.cols() + 1);
  A << e.Jz, e.Jl;
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(A, Eigen::ComputeFullV);
  Eigen::VectorXd t = svd.matrixV().col(A.cols() - 1);
  if (previous.size() == t.size() && t.dot(previous) < 0) t = -t;
  return t;
}

// Newton on {G(y) = 0, tᵀ(y − y_pred) = 0}. `polish`: once converged, Newton goes on while the
// residual still decreases (to the rounding floor of the map: the samples of a test function
// near a branch point, where the system is ill-conditioned, so that 1e-13 in G is not 1e-13 in y).
// `start`: Newton's first iterate when it is not the predictor y (the hyperplane still passes
// through y).
std::optional<Corrected> Correct(const Problem& p, Eigen::VectorXd y, const Eigen::VectorXd& t,
                                 int& iterations, bool polish = false, const Eigen::VectorXd* start = nullptr) {
  const auto N = y.size();
  const Eigen::VectorXd pred = y;
  if (start) y = *start;
  double last = 0;
  std::optional<Corrected> best;
  double best_res = 0;
  for (iterations = 0; iterations < 16; ++iterations) {
    const Evaluation e = p.Evaluate(y.head(N - 1), y[N - 1]);
    if (!e.ok) return best;
    const double res = e.G.cwiseAbs().maxCoeff() / (1.0 + y.head(N - 1).cwiseAbs().maxCoeff());
    if (best) {  // polishing: stop when Newton no longer gains
      if (res >= 0.5 * best_res || iterations > 15) return best;
      best = Corrected{y, e};
      best_res = res;
    } else if (res < 1e-13 || (res < 1e-11 && iterations > 0 && res > 0.1 * last)) {
      // Converged at 1e-13, or at 1e-11 once Newton stops gaining (rounding of the map).
      if (!polish || res == 0) return Corrected{y, e};
      best = Corrected{y, e};
      best_res = res;
    }
    if (iterations >= 11 && !best) return std::nullopt;  // 12 evaluations without converging
    last = res;
    Eigen::MatrixXd J(N, N);
    J.topLeftCorner(N - 1, N - 1) = e.Jz;
    J.topRightCorner(N - 1, 1) = e.Jl;
    J.bottomRows(1) = t.transpose();
    Eigen::VectorXd r(N);
    r << e.G, t.dot(y - pred);
    y -= J.fullPivLu().solve(r);
  }
  return best;
}

// The most negative real multiplier (the flip test), or 0 when there is none.
double MostNegativeReal(const std::vector<std::complex<double>>& mu) {
  double best = 0;
  for (const auto& m : mu)
    if (std::abs(m.imag()) < 1e-9 && m.real() < best) best = m.real();
  return best;
}

double LeadingComplex(const std::vector<std::complex<double>>& mu) {
  double best = 0;
  for (const auto& m : mu)
    if (std::abs(m.imag()) >= 1e-9) best = std::max(best, std::abs(m));
  return best;
}

// The argument θ ∈ (0, π) of the complex multiplier of largest modulus (0 when none).
double LeadingComplexAngle(const std::vector<std::complex<double>>& mu) {
  double best = 0, angle = 0;
  for (const auto& m : mu)
    if (std::abs(m.imag()) >= 1e-9 && std::abs(m) > best) {
      best = std::abs(m);
      angle = std::abs(std::arg(m));
    }
  return angle;
}

// Whether the orbit has a sticking phase (from its events: the attractor summary of an orbit
// next to a non-smooth point may fail to see its period within tolerance).
bool Sticks(const Point& a) { return a.probe.signature.find_first_of("CPS") != std::string::npos; }

bool SameFamily(const Point& a, const Point& b) { return a.probe.signature == b.probe.signature; }

long Count(const std::string& s, char c) { return std::count(s.begin(), s.end(), c); }

// The non-smooth bifurcation between `lo` (on the branch) and `hi` (past it, if the orbit goes
// on): named by the probe quantity that vanishes there (docs/model.md §5.7, orbit_probe.hpp), or
// "relabel" when only the grouping of a chattering sequence changed (no bifurcation). With several
// contacts (`m` > 1) the detail names the contact, and `contact` is set.
struct NonSmooth {
  std::string kind, detail;
  int contact = -1;
};
NonSmooth NameNonSmooth(const Point& lo, const Point* hi, int m) {
  // The smaller of lo's and hi's value of a probe quantity, with the contact where it is.
  struct Value {
    double value;
    int contact;
  };
  const auto both = [&](double OrbitProbe::*q, int OrbitProbe::Where::*w) {
    Value v{lo.probe.*q, lo.probe.at.*w};
    if (hi && hi->probe.*q < v.value) v = {hi->probe.*q, hi->probe.at.*w};
    return v;
  };
  const auto on = [&](int c) { return m > 1 ? fmt::format(" on contact {}", c) : std::string(); };
  // Both sequences: the events per period and, with several contacts, the contact sequences.
  const std::string change =
      hi ? fmt::format("events per period {} → {}{}", lo.probe.signature, hi->probe.signature,
                       m > 1 ? fmt::format("; contact sequence {} → {}", lo.orbit.sequence, hi->orbit.sequence) : "")
         : fmt::format("events per period {}{}; the orbit does not go on", lo.probe.signature,
                       m > 1 ? fmt::format("; contact sequence {}", lo.orbit.sequence) : "");
  if (lo.probe.shortest_stick < 1e-6)
    return {"sticking-lost",
            fmt::format("a sticking phase{} shrinks to zero ({:.1e} of the period); {}", on(lo.probe.at.shortest_stick),
                        lo.probe.shortest_stick, change),
            m > 1 ? lo.probe.at.shortest_stick : -1};
  // A sticking phase that splits in two (or two that merge) across the point, by a release
  // followed, after a vanishing time, by a landing: the rising bifurcation seen from either side.
  if (hi && std::abs(hi->probe.sticking_phases - lo.probe.sticking_phases) == 1) {
    const Point& more = hi->probe.sticking_phases > lo.probe.sticking_phases ? *hi : lo;
    const Point& fewer = &more == &lo ? *hi : lo;
    if (std::min(more.probe.release_to_stick, fewer.probe.interior_reaction) < 1e-3 &&
        fewer.probe.sticking_phases > 0) {
      const int c = more.probe.release_to_stick <= fewer.probe.interior_reaction ? more.probe.at.release_to_stick
                                                                                 : fewer.probe.at.interior_reaction;
      return {"rising",
              fmt::format("R touches zero inside a sticking phase{}, which splits in two "
                          "(flight {:.1e} of the period); {}",
                          on(c), more.probe.release_to_stick, change),
              m > 1 ? c : -1};
    }
  }
  struct Candidate {
    const char* kind;
    Value v;
    std::string what;
  };
  const auto entry = both(&OrbitProbe::entry_reaction, &OrbitProbe::Where::entry_reaction);
  const auto gap = both(&OrbitProbe::flight_gap, &OrbitProbe::Where::flight_gap);
  const auto speed = both(&OrbitProbe::impact_speed, &OrbitProbe::Where::impact_speed);
  const auto grazing = gap.value <= speed.value ? gap : speed;
  if (entry.value < 1e-3)  // also a degenerate grazing at f_sticking (§6.3)
    return {"sticking-entry",
            fmt::format("R vanishes at the landing{} (test quantity {:.1e}; grazing quantity {:.1e}); {}",
                        on(entry.contact), entry.value, grazing.value, change),
            m > 1 ? entry.contact : -1};
  const auto interior = both(&OrbitProbe::interior_reaction, &OrbitProbe::Where::interior_reaction);
  const auto release = both(&OrbitProbe::release_to_stick, &OrbitProbe::Where::release_to_stick);
  const auto closing = both(&OrbitProbe::closing_gap, &OrbitProbe::Where::closing_gap);
  const int closing_held = closing.value == lo.probe.closing_gap ? lo.probe.at.closing_held
                           : hi                                   ? hi->probe.at.closing_held
                                                                  : 0;
  const auto simultaneous = both(&OrbitProbe::simultaneous, &OrbitProbe::Where::simultaneous);
  const OrbitProbe::Where& sim_at = simultaneous.value == lo.probe.simultaneous || !hi ? lo.probe.at : hi->probe.at;
  const auto kind_name = [](int k) { return ToString(static_cast<EventKind>(k)); };
  const std::string simultaneous_what =
      sim_at.simultaneous_kind == 1 && sim_at.simultaneous_other_kind == 1
          ? fmt::format("impacts on contacts {} and {} become simultaneous", sim_at.simultaneous_other,
                        sim_at.simultaneous)
          : fmt::format("the {} of contact {} and the {} of contact {} become simultaneous",
                        kind_name(sim_at.simultaneous_other_kind), sim_at.simultaneous_other,
                        kind_name(sim_at.simultaneous_kind), sim_at.simultaneous);
  const Candidate c[] = {
      {"rising", interior.value <= release.value ? interior : release,
       "R touches zero inside a sticking phase" + on(interior.value <= release.value ? interior.contact : release.contact)},
      {"sticking-entry", entry, "R vanishes at the landing" + on(entry.contact)},
      {"grazing", grazing, "a free flight touches the stop tangentially" + on(grazing.contact)},
      {"rising", closing,
       fmt::format("contact {} closes tangentially while contact {} sticks", closing.contact, closing_held)},
      {"simultaneous", simultaneous, simultaneous_what},
  };
  const auto best = std::min_element(std::begin(c), std::end(c),
                                     [](const auto& a, const auto& b) { return a.v.value < b.v.value; });
  const int where = m > 1 ? best->v.contact : -1;
  if (best->v.value < 1e-3)
    return {best->kind, fmt::format("{} (test quantity {:.1e}); {}", best->what, best->v.value, change), where};
  // The same events grouped differently (orbit_probe.hpp, coarse_signature): the impact that
  // starts a chattering sequence's tail of decreasing speeds moved by one, as two of its impacts
  // swapped which is faster. Nothing of the orbit changes there: not a bifurcation.
  if (hi && lo.probe.coarse_signature == hi->probe.coarse_signature)
    return {"relabel",
            fmt::format("a chattering sequence is regrouped: its tail of decreasing impact "
                        "speeds now starts one impact {} (no event appears or vanishes; "
                        "smallest test quantity: {} {:.1e}); {}",
                        Count(hi->probe.signature, 'I') > Count(lo.probe.signature, 'I') ? "later" : "earlier",
                        best->kind, best->v.value, change),
            where};
  return {"non-smooth",
          fmt::format("the event sequence changes and no test quantity vanishes "
                      "(smallest: {} {:.1e}); {}", best->kind, best->v.value, change),
          where};
}

// The branch as returned, with how many map evaluations needed the quad engine.
Branch& Finish(Branch& br, const Problem& p) {
  br.quad_evaluations = p.quad_evaluations();
  return br;
}

}  // namespace

Branch Continue(const ContinuationRequest& req) {
  Branch br;
  const auto first_scene = req.scene_at(req.from);
  const System first_sys(first_scene);
  const OrbitResult start = SolveOrbit(first_sys, first_scene, req.orbit);
  // Every run polls the process's stop request (vibro/stop_request.hpp): an orbit solve cut
  // short by it is an interruption, not the absence of an orbit.
  const auto stopped = [&] { return req.stop_requested && req.stop_requested->load(); };
  if (stopped()) {
    br.status = "interrupted";
    br.end = "interrupted";
    return br;
  }
  if (start.status != "converged") {
    br.status = "no-orbit";
    br.end = "no orbit at the start: " + start.message;
    return br;
  }
  br.period = start.period;
  const double cycle = 2.0 * M_PI * start.period;
  Problem p(req, std::fmod(first_scene.frequency * start.section_time, cycle), start.period);
  const auto n2 = start.X.size() * 2;
  const auto n = n2 / 2;
  const int m = first_sys.contact_count();
  const double span = req.to - req.from;
  double ds = req.step > 0 ? req.step : std::abs(span) / 50.0;
  const double ds_max = req.max_step > 0 ? req.max_step : std::abs(span) / 10.0;
  const double ds_retry = 1e-4 * std::abs(span);  // below this a failed step means a boundary

  const auto record = [&](const Point& pt) {
    // A point computed while a stop request came may rest on runs it cut short: not kept (the
    // branch kept is the start of the uninterrupted branch; the loop reports the interruption).
    if (stopped()) return;
    const auto scene = p.SceneAt(pt.y[n2]);
    const System sys(*scene);
    BranchPoint b;
    b.value = pt.y[n2];
    b.summary = pt.orbit.summary;
    b.multipliers = pt.orbit.multipliers;
    b.stable = pt.orbit.stable;
    b.signature = pt.probe.signature;
    b.x_B = sys.ContactDisplacement(pt.y.head(n));
    b.section_phase = p.phase();
    b.section_time = p.SectionTime(*scene);
    b.X = pt.y.head(n);
    b.V = pt.y.segment(n, n);
    if (sys.physical()) {
      b.q = sys.mode_shapes() * b.X;
      b.q_dot = sys.mode_shapes() * b.V;
    }
    b.impacts = ImpactsOf(sys, *scene, b.section_time, b.X, b.V, p.period());
    b.strobe = StrobeOf(sys, *scene, b.section_time, b.X, b.V, p.period());
    b.sequence = pt.orbit.sequence;
    auto loads = OrbitLoads(sys, *scene, pt.orbit);  // docs/loads.md, per contact
    b.loads = std::move(loads.contacts);
    b.loads_note = std::move(loads.note);
    b.contact_phases = pt.orbit.contact_phases;  // compliant stops: each phase's loads (docs/compliant.md)
    br.points.push_back(std::move(b));
    if (req.progress) req.progress(br.points.size(), pt.y[n2]);
  };
  Eigen::VectorXd y0(n2 + 1);
  y0 << start.X, start.V, req.from;
  Evaluation e = p.Evaluate(y0.head(n2), y0[n2]);
  auto first = e.ok ? p.Examine({y0, e}) : std::nullopt;
  if (stopped()) {
    br.status = "interrupted";
    br.end = "interrupted";
    return br;
  }
  if (!first) {
    br.end = "the map could not be evaluated at the start";
    return Finish(br, p);
  }
  Point cur = *first;
  record(cur);
  Eigen::VectorXd t = Tangent(cur.eval, Eigen::VectorXd());
  if (t[n2] * span < 0) t = -t;

  // A stop request (SIGINT/SIGTERM), also polled inside the bisections below.
  const auto stop_requested = [&] { return req.stop_requested && req.stop_requested->load(); };
  // Corrects the predictor at arclength s from `cur` along `t`.
  const auto trial = [&](double s) -> std::optional<Point> {
    int iters = 0;
    const auto yc = Correct(p, cur.y + s * t, t, iters);
    if (!yc) return std::nullopt;
    return p.Examine(*yc);
  };
  // Bisection of the arclength on a sign change of `test` between cur (s = 0) and s = hi.
  const auto locate = [&](const std::function<double(const Point&, const Eigen::VectorXd&)>& test,
                          double hi, double fallback, double& bracket) {
    double lo = 0.0, value = fallback;
    const double sign_lo = test(cur, t);
    double l_lo = cur.y[n2], l_hi = fallback;
    for (int it = 0; it < 80; ++it) {
      if (stop_requested()) break;  // the bracket reached so far is reported with the point
      const double mid = 0.5 * (lo + hi);
      int iters = 0;
      const auto yc = Correct(p, cur.y + mid * t, t, iters);
      if (!yc) break;
      const auto pc = p.Examine(*yc);
      if (!pc) break;
      const double v = test(*pc, Tangent(pc->eval, t));
      value = pc->y[n2];
      if ((v > 0) == (sign_lo > 0)) {
        lo = mid;
        l_lo = value;
      } else {
        hi = mid;
        l_hi = value;
      }
      if (std::abs(l_hi - l_lo) < 1e-13 * std::max(1.0, std::abs(value)) && it > 10) break;
    }
    bracket = std::abs(l_hi - l_lo);
    return value;
  };

  // The root of a test function that is smooth along this branch (det(DF − I) at a branch point),
  // between cur (s = 0, value f0) and s = hi (value f1). Near a branch point the arclength
  // hyperplanes also cut the branch that crosses this one, and the system the corrector solves
  // is singular there: every sample is corrected onto this branch (near its predictor, the same
  // events) and polished to the map's rounding floor, and none is taken closer to the root than
  // 1e-4 of the step. (1) Regula falsi (Illinois) on the arclength brackets the root to 1e-6 of
  // the step. (2) Eight samples at 1 to 4 times 1e-4 of the step on both sides of it; the root
  // of the least-squares cubic in λ through them is the location. `bracket`: its distance to the
  // root of the quartic fit, plus the rounding noise of the samples over the slope. Falls back
  // to the regula-falsi bracket (or `fallback`) when samples leave the branch.
  const auto locate_root = [&](const std::function<double(const Point&)>& test, double f0, double f1,
                               const Eigen::VectorXd& y1, double hi, double fallback, double& bracket) {
    struct TestSample {
      double s, lambda, f;
    };
    // Corrected points of this branch so far, by arclength: Newton starts from the interpolation
    // between the two nearest (close to the root the predictor alone lies outside the corrector's
    // basin, which shrinks with the distance to the branch point, and it lands on the other branch).
    std::vector<std::pair<double, Eigen::VectorXd>> known = {{0.0, cur.y}, {hi, y1}};
    // |df/ds| near the root: the secant of the bracket (from the unmodified end values). A sample
    // closer to the root than 3e-5 of the step, |f| < 3e-5·hi·slope, is too close (below); where
    // it fell says where the root is.
    double root_slope = std::abs(f1 - f0) / hi;
    std::optional<std::pair<double, double>> too_close;  // (s, λ) of the last such sample
    const auto sample = [&](double s) -> std::optional<TestSample> {
      auto above = std::lower_bound(known.begin(), known.end(), s,
                                    [](const auto& k, double v) { return k.first < v; });
      if (above == known.begin()) ++above;
      if (above == known.end()) --above;
      const auto below = above - 1;
      const double w = (s - below->first) / (above->first - below->first);
      const Eigen::VectorXd guess = below->second + w * (above->second - below->second);
      const double reach = std::min(s - below->first, above->first - s);
      int iters = 0;
      const auto yc = Correct(p, cur.y + s * t, t, iters, true, &guess);
      const auto pc = yc ? p.Examine(*yc) : std::nullopt;
      if (!pc || !SameFamily(cur, *pc) || (pc->y - guess).norm() > 0.2 * std::abs(reach) + 1e-12 * (1.0 + cur.y.norm()))
        return std::nullopt;
      const double v = test(*pc);
      // A sample this close to the root is within the corrector's ill-conditioned zone (it may
      // sit on the crossing branch): not trusted, neither as a value nor as a start for others.
      // The zone's width is a fraction of the step (the corrector's error grows as the distance
      // to the crossing shrinks), not of |f|, which may be far larger at one end of the step
      // (e.g. next to a Neimark-Sacker point, where the multipliers are large).
      if (!std::isfinite(v)) return std::nullopt;
      if (std::abs(v) < 3e-5 * hi * root_slope) {
        too_close = std::make_pair(s, pc->y[n2]);
        return std::nullopt;
      }
      known.insert(above, {s, pc->y});
      return TestSample{s, pc->y[n2], v};
    };
    // (1) Illinois regula falsi on s in [a, b], with a bisection whenever two steps did not halve
    // the bracket.
    double a = 0, fa = f0, b = hi, fb = f1, l_a = cur.y[n2], l_b = fallback;
    double fa_true = f0, fb_true = f1;
    int side = 0;
    bool bracketed = false, near = false;
    std::vector<double> widths = {hi, hi};
    for (int it = 0; it < 100 && b - a > 1e-3 * hi; ++it) {
      if (stop_requested()) break;
      const double w = b - a;
      const bool bisect = w > 0.5 * widths[widths.size() - 2];
      double s = bisect ? 0.5 * (a + b) : std::clamp(b - fb * w / (fb - fa), a + 1e-3 * w, b - 1e-3 * w);
      too_close.reset();
      auto x = sample(s);
      if (!x && too_close) {  // the root is within 3e-5 of the step of s: fitted around s below
        near = true;
        break;
      }
      if (!x && !bisect) x = sample(s = 0.5 * (a + b));
      if (!x && too_close) {
        near = true;
        break;
      }
      if (!x) break;
      widths.push_back(w);
      if ((x->f > 0) == (fa > 0)) {
        a = s;
        fa = fa_true = x->f;
        l_a = x->lambda;
        if (side == -1) fb *= 0.5;
        side = -1;
      } else {
        b = s;
        fb = fb_true = x->f;
        l_b = x->lambda;
        bracketed = true;
        if (side == 1) fa *= 0.5;
        side = 1;
      }
      root_slope = std::abs(fb_true - fa_true) / (b - a);
    }
    double s_star = near ? too_close->first : 0.5 * (a + b);
    double at = near ? too_close->second : bracketed ? 0.5 * (l_a + l_b) : fallback;
    bracket = bracketed ? std::abs(l_b - l_a) : bracket;
    if ((!near && b - a > 1e-3 * hi) || stop_requested()) return at;
    // (2) The least-squares fit through samples on both sides: first at 2e-3 to 8e-3 of the step
    // from the bracket's middle, then at 1e-4 to 4e-4 of it from the first fit's root.
    for (const double h : {2e-3 * hi, 1e-4 * hi}) {
      std::vector<TestSample> xs;
      int below = 0, above = 0;
      for (double k : {-4.0, -3.0, -2.0, -1.0, 1.0, 2.0, 3.0, 4.0}) {
        if (stop_requested()) return at;
        // Past either end of the step when the root is close to it (the branch goes on smoothly
        // there; a sample that leaves it is refused by `sample`): without them a root within 8e-3
        // of the step's end had samples on one side only and kept the regula falsi's location.
        const double s = s_star + k * h;
        if (s <= -0.25 * hi || s >= 1.25 * hi) continue;
        if (const auto x = sample(s)) {
          xs.push_back(*x);
          (k < 0 ? below : above) += 1;
        }
      }
      if (below < 2 || above < 2 || xs.size() < 6) return at;
      double centre = 0, width = 0;
      for (const auto& x : xs) centre += x.lambda / static_cast<double>(xs.size());
      for (const auto& x : xs) width = std::max(width, std::abs(x.lambda - centre));
      if (!(width > 0)) return at;
      const auto fit_root = [&](int degree, double* noise) {
        Eigen::MatrixXd A(xs.size(), degree + 1);
        Eigen::VectorXd f(xs.size());
        for (size_t i = 0; i < xs.size(); ++i) {
          const double u = (xs[i].lambda - centre) / width;
          for (int d = 0; d <= degree; ++d) A(static_cast<long>(i), d) = std::pow(u, d);
          f[static_cast<long>(i)] = xs[i].f;
        }
        const Eigen::VectorXd c = A.colPivHouseholderQr().solve(f);
        const auto poly = [&](double u, double* slope) {
          double v = 0, dv = 0;
          for (int d = degree; d >= 0; --d) {
            dv = dv * u + v;
            v = v * u + c[d];
          }
          if (slope) *slope = dv;
          return v;
        };
        double u = -c[0] / c[1];  // Newton from the linear root
        for (int it = 0; it < 50; ++it) {
          double slope = 0;
          const double v = poly(u, &slope);
          const double du = v / slope;
          u -= du;
          if (std::abs(du) < 1e-17) break;
        }
        if (noise) {
          double slope = 0;
          poly(u, &slope);
          const double rms = std::sqrt((A * c - f).squaredNorm() / static_cast<double>(xs.size()));
          *noise = rms / std::abs(slope) * width;
        }
        return centre + u * width;
      };
      double noise = 0;
      const double root3 = fit_root(3, &noise), root4 = fit_root(4, nullptr);
      if (!std::isfinite(root3) || std::abs(root3 - at) > std::max(bracket, 2.0 * width)) return at;
      // plus the rounding of λ itself (each sample's λ is a double): a bracket below an ulp of the
      // location could not contain the truth.
      bracket = std::abs(root4 - root3) + noise + 2 * std::numeric_limits<double>::epsilon() * std::abs(root3);
      at = root3;
      // The arclength of the root, for the next pass: interpolated between the samples.
      for (size_t i = 1; i < xs.size(); ++i)
        if ((xs[i - 1].lambda - root3) * (xs[i].lambda - root3) <= 0 && xs[i].lambda != xs[i - 1].lambda)
          s_star = xs[i - 1].s + (root3 - xs[i - 1].lambda) / (xs[i].lambda - xs[i - 1].lambda) * (xs[i].s - xs[i - 1].s);
    }
    return at;
  };

  // Moves the section to the middle of the longest free flight of `cur` (when an event comes near
  // it, the map loses its smoothness there and the corrector fails for no reason of the orbit's).
  const auto move_section = [&]() {
    if (cur.probe.best_X.size() != static_cast<long>(n)) return false;
    const auto scene = p.SceneAt(cur.y[n2]);
    const double old_phase = p.phase(), t_lambda = t[n2];
    p.MoveSection(std::fmod(old_phase + scene->frequency * cur.probe.best_offset, cycle));
    Eigen::VectorXd y(n2 + 1);
    y << cur.probe.best_X, cur.probe.best_V, cur.y[n2];
    int iters = 0;
    const Evaluation es = p.Evaluate(y.head(n2), y[n2]);
    const auto moved = es.ok ? Correct(p, y, Tangent(es, Eigen::VectorXd()), iters) : std::nullopt;
    const auto pm = moved ? p.Examine(*moved) : std::nullopt;
    if (!pm || !SameFamily(cur, *pm)) {
      p.MoveSection(old_phase);
      return false;
    }
    cur = *pm;
    t = Tangent(cur.eval, Eigen::VectorXd());
    if (t[n2] * t_lambda < 0) t = -t;
    return true;
  };
  bool section_fresh = false;  // the section was just moved to the middle of a flight of cur
  // The last non-smooth transition while no smooth step has followed it: its bifurcation's index,
  // the number of points before the orbit past it, the orbit before it, and the intermediate
  // event sequences met since (docs/orbits.md: one transition, one bifurcation).
  struct Transition {
    size_t index, points;
    Point before;
    Eigen::VectorXd tangent;  // at `before`
    double phase;             // of the section `before` is at
    std::vector<std::string> via;
  };
  std::optional<Transition> transition;

  // A sticking entry (R at a landing reaches 0) located by the landing reaction itself: R is
  // smooth along the branch up to the transition, where the bisection on the events stops short
  // (the orbit degenerates: a flight of vanishing length before the landing, whose speed is below
  // what decides an impact from a grazing). Six points behind `base` (arclength k·h, k = 1..6, h
  // 1e-6 of the span), R at their landings, and the root of the least-squares cubic in λ through
  // them, which must lie within `bracket` of `at` or 10 sample spans of it; `bracket` becomes its distance to the
  // quadratic fit's root plus the samples' rounding noise over the slope. Unchanged otherwise.
  const auto refine_entry = [&](const Point& base, const Eigen::VectorXd& tb, double section_phase, double& at,
                                double& bracket) {
    if (section_phase != p.phase() || !std::isfinite(base.probe.entry_reaction_raw)) return;
    std::vector<double> ls, rs;
    const double h = 1e-6 * std::abs(span);
    for (int k = 1; k <= 6; ++k) {
      if (stop_requested()) return;
      int iters = 0;
      const auto yc = Correct(p, base.y - (k * h) * tb, tb, iters, true);
      const auto pc = yc ? p.Examine(*yc) : std::nullopt;
      if (!pc || !SameFamily(base, *pc) || !std::isfinite(pc->probe.entry_reaction_raw)) return;
      ls.push_back(pc->y[n2]);
      rs.push_back(pc->probe.entry_reaction_raw);
    }
    const double centre = ls.front(), width = std::abs(ls.back() - ls.front());
    if (!(width > 0)) return;
    const auto fit_root = [&](int degree, double* noise) {
      Eigen::MatrixXd A(static_cast<long>(ls.size()), degree + 1);
      Eigen::VectorXd f(static_cast<long>(ls.size()));
      for (size_t i = 0; i < ls.size(); ++i) {
        for (int d = 0; d <= degree; ++d) A(static_cast<long>(i), d) = std::pow((ls[i] - centre) / width, d);
        f[static_cast<long>(i)] = rs[i];
      }
      const Eigen::VectorXd c = A.colPivHouseholderQr().solve(f);
      double u = -c[0] / c[1], dv = 0;
      for (int it = 0; it < 50; ++it) {
        double v = 0;
        dv = 0;
        for (int d = degree; d >= 0; --d) {
          dv = dv * u + v;
          v = v * u + c[d];
        }
        const double du = v / dv;
        u -= du;
        if (std::abs(du) < 1e-17) break;
      }
      if (noise) *noise = std::sqrt((A * c - f).squaredNorm() / static_cast<double>(ls.size())) / std::abs(dv) * width;
      return centre + u * width;
    };
    double noise = 0;
    const double root3 = fit_root(3, &noise), root2 = fit_root(2, nullptr);
    // The events' bisection may stop short of the root by much more than its bracket.
    if (!std::isfinite(root3) || std::abs(root3 - at) > std::max(bracket, 10.0 * width)) return;
    // R is smooth only where the fits of degree 2 and 3 agree: where it is not (a 1-DOF column's
    // f_st, where SP ~ |f − f_st|^(1/3), docs/model.md §6.3) their roots part by more than the
    // events' bracket, and the bisection's location stands.
    const double fit_bracket = std::abs(root3 - root2) + noise;
    if (!(fit_bracket < bracket)) return;
    at = root3;
    bracket = fit_bracket;
  };

  while (static_cast<int>(br.points.size()) < req.max_points) {
    if (stop_requested()) {
      br.status = "interrupted";
      br.end = "interrupted";
      return Finish(br, p);
    }
    const auto next = trial(ds);
    // Step control (Allgower & Georg): a step whose corrected point strays far from the predictor
    // or changes the sticking fraction a lot may have jumped over part of the branch.
    const auto sp = [](const Point& x) { return x.orbit.summary.sticking_fraction.value_or(0.0); };
    const bool too_far = next && ds > ds_retry &&
                         ((next->y - (cur.y + ds * t)).norm() > 0.2 * ds || std::abs(sp(*next) - sp(cur)) > 0.02);
    if (too_far) {
      ds *= 0.5;
      continue;
    }
    // A step that ends within about 1e-3 of itself of a branch point (det(DF − I) there nearly
    // zero against its change over the step) ends where the corrector's system is nearly singular
    // and the crossing branch is as close as this one: the point may lie on the other branch (its
    // λ-tangent then turns there, read as a fold), and the root would be located from one side
    // only. The step is shortened by a tenth, whatever --step asked for.
    if (next && ds > ds_retry && SameFamily(cur, *next) &&
        std::abs(next->eval.Jz.determinant()) < 1e-3 * std::abs(cur.eval.Jz.determinant() - next->eval.Jz.determinant())) {
      ds *= 0.9;
      continue;
    }
    // A fold between cur and next: the λ-tangent changes sign AND a real multiplier is at +1
    // where it does (DF − I singular). A sign change without it comes from a non-smooth point
    // between them (the map's smoothness is lost there, e.g. the square-root of a grazing): the
    // step is refused, and the point is located as such below.
    std::optional<Bifurcation> fold;
    bool false_turn = false;
    if (next && SameFamily(cur, *next) && t[n2] * Tangent(next->eval, t)[n2] < 0) {
      double bracket = 0, nearest_one = std::numeric_limits<double>::infinity();
      const double at = locate(
          [&](const Point& pc, const Eigen::VectorXd& tc) {
            nearest_one = std::numeric_limits<double>::infinity();
            for (const auto& mu : pc.orbit.multipliers) nearest_one = std::min(nearest_one, std::abs(mu - 1.0));
            return tc[n2];
          },
          ds, 0.5 * (cur.y[n2] + next->y[n2]), bracket);
      if (nearest_one < 1e-3 && !stop_requested())
        fold = Bifurcation{"fold", at,
                           fmt::format("the branch turns back (λ-tangent changes sign; the nearest multiplier "
                                       "is {:.1e} from +1)", nearest_one),
                           bracket};
      else
        false_turn = !stop_requested();
    }
    if (false_turn && ds > ds_retry) {
      ds *= 0.5;
      continue;
    }
    if (next && SameFamily(cur, *next) && !false_turn) {
      // Smooth bifurcations between cur and next.
      const Eigen::VectorXd t_new = Tangent(next->eval, t);
      const double l_old = cur.y[n2], l_new = next->y[n2];
      double bracket = 0;
      if (fold) br.bifurcations.push_back(*fold);
      const auto by_multipliers = [](auto score) {
        return [score](const Point& pc, const Eigen::VectorXd&) { return score(pc.orbit.multipliers); };
      };
      // A real multiplier through +1 where the branch goes on in the same direction: a branch
      // point (a pitchfork where a symmetric orbit loses its symmetry, or a transcritical point).
      // Test function det(DF − I) = Π(μ_i − 1): analytic along the branch, unlike the multiplier
      // itself (a real pair is often born from a complex one just before).
      const auto det = [](const Point& pc) { return pc.eval.Jz.determinant(); };
      const double one_old = det(cur), one_new = det(*next);
      if (t[n2] * t_new[n2] > 0 && one_old * one_new < 0) {
        const double w = one_old / (one_old - one_new);
        bracket = std::abs(l_new - l_old);
        const double at = locate_root(det, one_old, one_new, next->y, ds, l_old + w * (l_new - l_old), bracket);
        br.bifurcations.push_back({"branch-point", at,
                                   "a real multiplier crosses +1 and the branch does not turn back (a "
                                   "pitchfork: another branch of orbits crosses this one, e.g. where a "
                                   "symmetric orbit loses its symmetry)",
                                   bracket});
      }
      const double flip_old = MostNegativeReal(cur.orbit.multipliers);
      const double flip_new = MostNegativeReal(next->orbit.multipliers);
      if ((flip_old + 1) * (flip_new + 1) < 0 && (flip_old < 0 || flip_new < 0)) {
        const double w = (flip_old + 1) / (flip_old - flip_new);
        const double at = locate(by_multipliers([](const auto& mu) { return MostNegativeReal(mu) + 1; }),
                                 ds, l_old + w * (l_new - l_old), bracket);
        br.bifurcations.push_back({"flip", at, "a real multiplier crosses −1", bracket});
      }
      const double ns_old = LeadingComplex(cur.orbit.multipliers);
      const double ns_new = LeadingComplex(next->orbit.multipliers);
      if (ns_old > 0 && ns_new > 0 && (ns_old - 1) * (ns_new - 1) < 0) {
        const double w = (ns_old - 1) / (ns_old - ns_new);
        // The rotation number θ/2π of the pair e^{±iθ} there: from the tested point nearest to |μ| = 1.
        double theta = 0, nearest = std::numeric_limits<double>::infinity();
        const auto ns_test = [&](const Point& pc, const Eigen::VectorXd&) {
          const double f = LeadingComplex(pc.orbit.multipliers) - 1;
          if (std::abs(f) < nearest) {
            nearest = std::abs(f);
            theta = LeadingComplexAngle(pc.orbit.multipliers);
          }
          return f;
        };
        ns_test(cur, t);
        ns_test(*next, t);
        const double at = locate(ns_test, ds, l_old + w * (l_new - l_old), bracket);
        br.bifurcations.push_back({"neimark-sacker", at,
                                   fmt::format("a complex pair of multipliers crosses the unit circle at e^(±iθ), "
                                               "rotation number θ/2π = {:.10f} per period of the orbit",
                                               theta / (2 * M_PI)),
                                   bracket});
        br.bifurcations.back().rotation_number = theta / (2 * M_PI);
      }
      for (double level : req.levels) {
        const double a = sp(cur) - level, b2 = sp(*next) - level;
        if (a * b2 < 0) {
          const double w = a / (a - b2);
          const double at = locate([&](const Point& pc, const Eigen::VectorXd&) { return sp(pc) - level; }, ds,
                                   l_old + w * (l_new - l_old), bracket);
          br.crossings.push_back({level, at, bracket});
        }
      }
      if ((l_new - req.to) * span >= 0) {
        // Past the end value: the point at λ = to exactly, corrected with λ held fixed (the
        // hyperplane λ = to instead of the arclength one), from the secant between cur and next.
        const double w = (req.to - l_old) / (l_new - l_old);
        Eigen::VectorXd y = cur.y + w * (next->y - cur.y);
        y[n2] = req.to;
        Eigen::VectorXd e_lambda = Eigen::VectorXd::Zero(n2 + 1);
        e_lambda[n2] = 1.0;
        int iters = 0;
        const auto yc = Correct(p, y, e_lambda, iters);
        const auto at_end = yc ? p.Examine(*yc) : std::nullopt;
        record(at_end && SameFamily(cur, *at_end) ? *at_end : *next);
        br.end = "reached the end value";
        return Finish(br, p);
      }
      cur = *next;
      t = t_new;
      section_fresh = false;
      record(cur);
      transition.reset();
      ds = std::min(ds * 1.5, ds_max);
    } else if (ds > ds_retry) {
      ds *= 0.5;  // the corrector may just need a shorter step, or jumped to another orbit
      continue;
    } else if (!section_fresh && cur.probe.section_margin < 0.45 && move_section()) {
      section_fresh = true;  // retry from a section in the middle of a flight
      continue;
    } else {
      // A non-smooth point lies in (0, ds], or the orbit ends there: bisection of the arclength
      // on "corrected, same kind and same events" (docs/model.md §5.7).
      double lo = 0.0, hi = ds;
      bool moved = false;
      std::optional<Point> past = next;
      p.ClearUndetermined();
      for (int it = 0; it < 100; ++it) {
        if (stop_requested()) break;
        const double mid = 0.5 * (lo + hi);
        auto pm = trial(mid);
        if (pm && SameFamily(cur, *pm)) {
          cur = *pm;  // the branch point nearest to the boundary so far
          moved = true;
          hi -= mid;
          lo = 0.0;
        } else {
          hi = mid;
          if (pm) past = pm;
          else if (past && (past->y - cur.y).norm() > 2.0 * hi) past.reset();
        }
        const double l_hi = past ? past->y[n2] : cur.y[n2] + hi * t[n2];
        if (std::abs(l_hi - cur.y[n2]) < 1e-13 * std::max(1.0, std::abs(cur.y[n2])) && it > 5) break;
        if (hi < 1e-15 * std::max(1.0, cur.y.norm())) break;
      }
      if (stop_requested()) {  // the boundary is not located: keep what the branch has
        if (moved) record(cur);
        br.status = "interrupted";
        br.end = "interrupted";
        return Finish(br, p);
      }
      // A point of another orbit met on the same corrector hyperplane is not "past" anything:
      // along one branch, corrected points an arclength h apart are O(h) apart.
      if (past && (past->y - cur.y).norm() > 1e3 * hi + 1e-7) {
        past.reset();
        if (moved) {
          record(cur);
          ds = ds_retry;
          continue;
        }
      }
      // Just past a non-smooth point the new orbit may be too degenerate to correct (a flight of
      // zero length, a grazing landing): try to step over it.
      for (int k = 0; !past && k < 12; ++k) {
        const double s_over = hi + ds_retry * std::pow(2.0, k - 4);
        if (s_over > std::max(ds, 16.0 * ds_retry)) break;
        auto po = trial(s_over);
        if (po && !SameFamily(cur, *po) && (po->y - cur.y).norm() < 1e3 * s_over) past = po;
      }
      auto [kind, detail, contact] = NameNonSmooth(cur, past ? &*past : nullptr, m);
      // The boundary lies between cur and its predictor at arclength hi.
      const double at = cur.y[n2] + 0.5 * hi * t[n2], bracket = hi * std::abs(t[n2]);
      if (moved) record(cur);
      if (kind == "relabel") {  // bookkeeping: recorded as such, and the branch goes on
        br.relabels.push_back({at, cur.probe.signature, past->probe.signature, detail, bracket});
        t = Tangent(past->eval, t);
        cur = *past;
        section_fresh = false;
        record(cur);
        ds = std::max(ds, 1e-3 * std::abs(span));
        if (cur.probe.section_margin < 0.3 && !move_section()) {
          br.end = "could not move the section away from an event";
          return Finish(br, p);
        }
        continue;
      }
      // Past cur the map could not be evaluated because a chattering sequence stayed undetermined
      // (CVODE, or beyond quad too): the bisection found where this precision gives out, which
      // need not be where the motion changes. Say so rather than name a bifurcation there.
      const bool undecided = p.undetermined() && !past;
      if (undecided) {
        detail = fmt::format("past λ = {:.17g} a chattering sequence of the orbit is undetermined at this "
                             "precision (the computation gives out before the motion is seen to change; "
                             "{} suspected: {}). The exact engine evaluates such points in quad precision",
                             cur.y[n2], kind, detail);
        kind = "undetermined";
      }
      if (!past && !p.no_jacobian().empty()) {
        detail = fmt::format("past λ = {:.17g} the orbit runs through {}: the map has no derivative there, "
                             "so the branch cannot be corrected beyond ({} suspected: {})",
                             cur.y[n2], p.no_jacobian(), kind, detail);
        kind = "no-jacobian";
      }
      // No test quantity vanishes and no orbit is found past the point: nothing says that the
      // motion changes there (the corrector may just fail, e.g. on a strongly unstable orbit). Not a
      // bifurcation: the branch ends with what is known.
      if (kind == "non-smooth" && !past) {
        double lead = 0;
        for (const auto& mu : cur.orbit.multipliers) lead = std::max(lead, std::abs(mu));
        br.end = fmt::format("no orbit found past λ = {:.17g} (bracket {:.1e}) and no test quantity vanishes "
                             "there ({}; largest |multiplier| {:.3g}): not a bifurcation",
                             at, bracket, detail.substr(detail.find('(') + 1, detail.find(')') - detail.find('(') - 1),
                             lead);
        return Finish(br, p);
      }
      // One transition, one bifurcation: a transition found again within 1e-6 (relative) of the
      // last one with no smooth step between them (the orbits met between are of no extent, e.g.
      // the two contacts of a symmetric orbit changing at one value, seen one after the other) is
      // merged into it; the points recorded between them are dropped.
      if (transition && transition->index + 1 == br.bifurcations.size() &&
          std::abs(at - br.bifurcations.back().value) <= 1e-6 * std::max(1.0, std::abs(at))) {
        Bifurcation& merged = br.bifurcations.back();
        const double lo_v = std::min(merged.value - 0.5 * merged.bracket, at - 0.5 * bracket);
        const double hi_v = std::max(merged.value + 0.5 * merged.bracket, at + 0.5 * bracket);
        transition->via.push_back(m > 1 ? cur.orbit.sequence : cur.probe.signature);
        const Point& before = transition->before;
        const auto cut = merged.detail.find("; events per period");
        std::string via;
        for (const auto& v : transition->via) via += (via.empty() ? "" : ", ") + v;
        merged.detail = fmt::format(
            "{}; events per period {} → {}{} (one transition: met {} times within {:.1e}, through {})",
            merged.detail.substr(0, cut), before.probe.signature, past ? past->probe.signature : "none",
            m > 1 ? fmt::format("; contact sequence {} → {}", before.orbit.sequence, past ? past->orbit.sequence : "none")
                  : "",
            transition->via.size() + 1, hi_v - lo_v, via);
        if (merged.kind == "non-smooth") merged.kind = kind;
        if (merged.contact != contact && merged.contact >= 0 && contact >= 0) {
          const std::string one = fmt::format(" on contact {}", merged.contact);
          if (const auto k = merged.detail.find(one); k != std::string::npos)
            merged.detail.replace(k, one.size(), fmt::format(" on contacts {} and {}", std::min(merged.contact, contact),
                                                             std::max(merged.contact, contact)));
          merged.contact = -1;
        }
        merged.value = 0.5 * (lo_v + hi_v);
        merged.bracket = hi_v - lo_v;
        if (merged.kind == "sticking-entry")
          refine_entry(before, transition->tangent, transition->phase, merged.value, merged.bracket);
        br.points.resize(transition->points);
        kind = merged.kind;
      } else {
        double value = at, width = bracket;
        if (kind == "sticking-entry") refine_entry(cur, t, p.phase(), value, width);
        br.bifurcations.push_back({kind, value, detail, width, contact});
        transition = Transition{br.bifurcations.size() - 1, br.points.size(), cur, t, p.phase(), {}};
      }
      // The branch goes on when the orbit past the point is of the same kind (a sticking orbit
      // that lost one of its sticking phases still sticks).
      // (Not when the orbit past it is itself at a sticking-lost boundary: e.g. a symmetric orbit
      // whose sticking phases on two contacts vanish together.)
      const bool goes_on = past && Sticks(*past) == Sticks(cur) &&
                           past->probe.signature.find_first_of("RI") != std::string::npos &&
                           !(kind == "sticking-lost" && past->probe.shortest_stick < 1e-6);
      if (!goes_on) {
        br.end = kind == "sticking-lost" || kind == "undetermined" || kind == "no-jacobian" ? kind
                 : past && past->probe.signature.find_first_of("RI") == std::string::npos
                     ? kind + " (permanent contact beyond)"
                     : kind + " (the orbit does not go on)";
        return Finish(br, p);
      }
      t = Tangent(past->eval, t);
      cur = *past;
      section_fresh = false;
      record(cur);
      ds = std::max(ds, 1e-3 * std::abs(span));
    }
    if (cur.probe.section_margin < 0.3 && !move_section()) {
      br.end = section_fresh || br.bifurcations.empty()
                   ? "could not move the section away from an event"
                   : br.bifurcations.back().kind + " (the orbit past it is too degenerate to continue)";
      return Finish(br, p);
    }
  }
  br.end = "max points";
  return Finish(br, p);
}

}  // namespace vibro
