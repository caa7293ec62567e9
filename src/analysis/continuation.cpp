// Pseudo-arclength continuation of periodic orbits (see include/vibro/continuation.hpp).
#include "vibro/continuation.hpp"

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
#include <optional>

#include <fmt/format.h>

#include "analysis/mirror_symmetry.hpp"
#include "analysis/orbit_probe.hpp"
#include "vibro/contact_sequence.hpp"
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
  // The relative step of the central differences in λ (1e-6; smaller next to a grazing the branch
  // went through, where F varies on the scale of the distance to it).
  void SetLambdaStep(double h) { lambda_step_ = h; }

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
    // A corner of the map: the derivative is the first order's piece's (the tracker's default).
    if (jac && !m.corner.empty() && corner_.empty()) corner_ = fmt::format("{} at λ = {:.17g}", m.corner, lambda);
    if (jac) *jac = m.jacobian;
    Eigen::VectorXd out(2 * n);
    out << m.X, m.V;
    return out;
  }

  // The half map H(z; λ) = −Φ_{qT/2}(z) of a mirror-symmetric model (q odd), with its derivative:
  // F = H∘H, and a symmetric orbit is a fixed point of H (docs/orbits.md, "Through a grazing").
  // Double precision only (no switch to quad).
  std::optional<Eigen::VectorXd> HalfMap(const Eigen::VectorXd& z, double lambda, Eigen::MatrixXd* jac) const {
    const auto scene = SceneAt(lambda);
    if (!scene) return std::nullopt;
    const System sys(*scene);
    const auto n = sys.dof();
    const MapValue m = HalfPeriodFlow(sys, *scene, SectionTime(*scene), z.head(n), z.tail(n), q_);
    if (m.status != RunStatus::kOk || m.singular || (jac && !m.undefined.empty())) return std::nullopt;
    if (jac) *jac = -m.jacobian;
    Eigen::VectorXd out(2 * n);
    out << -m.X, -m.V;
    return out;
  }

  Evaluation Evaluate(const Eigen::VectorXd& z, double lambda) const {
    Evaluation e;
    Eigen::MatrixXd DF;
    const auto F = Map(z, lambda, &DF);
    const double h = lambda_step_ * std::max(1.0, std::abs(lambda));
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
  // The first corner of the map a derivative was taken at (empty: none), with its λ.
  const std::string& corner() const { return corner_; }

 private:
  const ContinuationRequest& req_;
  double phase_;
  int q_;
  mutable std::vector<double> quad_at_;  // the λ values at which the map switched to quad
  mutable int quad_evaluations_ = 0;
  mutable bool undetermined_ = false;
  mutable std::string no_jacobian_;
  mutable std::string corner_;
  double lambda_step_ = 1e-6;
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
  opt.max_segments = kMapSegmentsPerPeriod * q;
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
    opt.max_segments = kMapSegmentsPerPeriod * sc.run.periods;
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
// contacts (`m` > 1) the detail names the contact, and `contact` is set. `compliant[j]`: contact j
// is a compliant stop (docs/compliant.md), whose grazing is a contact phase that just touches.
struct NonSmooth {
  std::string kind, detail;
  int contact = -1;
};
NonSmooth NameNonSmooth(const Point& lo, const Point* hi, int m, const std::vector<bool>& compliant) {
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
      {"grazing", grazing,
       (grazing.contact >= 0 && static_cast<size_t>(grazing.contact) < compliant.size() &&
                compliant[static_cast<size_t>(grazing.contact)]
            ? std::string("a contact phase on the compliant stop just touches (zero penetration, tangential)")
            : std::string("a free flight touches the stop tangentially")) +
           on(grazing.contact)},
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

// ---- Through a grazing (docs/orbits.md, "Through a grazing") ----

// The impacts of one period of the orbit from z at λ (section of `p`), or nothing when it cannot
// be simulated.
std::optional<std::vector<BranchPoint::Impact>> ImpactsAt(const Problem& p, const Eigen::VectorXd& z, double lambda) {
  const auto scene = p.DecidingSceneAt(lambda);
  if (!scene) return std::nullopt;
  const System sys(*scene);
  const auto n = sys.dof();
  return ImpactsOf(sys, *scene, p.SectionTime(*scene), z.head(n), z.tail(n), p.period());
}

// The closest approach of the orbit's free flights to a stop over its range (OrbitProbe::flight_gap)
// from 16384 samples per period instead of the 256 of Examine: the parabola through three samples
// is off by O(Δt³) (about 1e-6 of the range with 256), far above the gaps next to a grazing.
double PreciseGap(const Problem& p, const Eigen::VectorXd& y) {
  const auto n2 = y.size() - 1;
  const auto scene = p.DecidingSceneAt(y[n2]);
  if (!scene) return std::numeric_limits<double>::quiet_NaN();
  const System sys(*scene);
  const auto n = sys.dof();
  const auto pr = ProbeOrbit(sys, *scene, p.SectionTime(*scene), y.head(n), y.segment(n, n), p.period(), 16384);
  return pr.ok ? pr.flight_gap : std::numeric_limits<double>::quiet_NaN();
}

// The slowest impact speed |ẋ⁻| of a list (∞ when it is empty).
double Slowest(const std::vector<BranchPoint::Impact>& impacts) {
  double v = std::numeric_limits<double>::infinity();
  for (const auto& i : impacts) v = std::min(v, std::abs(i.v_before));
  return v;
}

// Newton for the orbit with the new low-velocity impact(s) next to a grazing, on the bordered
// system {F(z; λ) − z = 0, v(z, λ)² − v_t² = 0}, v the slowest impact speed of the period from
// (z, λ): λ is an unknown and the new impact's speed is held at v_t. The map has a square-root
// term in the depth x to which the flight would cross the stop (v = √(2a·x), Nordmark), so Newton
// with λ held overshoots into the orbits without the impact from any seed deeper than the orbit;
// v², linear in x, is smooth, and holding it fixes the depth, where the square root is smooth on
// the scale of the corrections. The solution's λ falls on whichever side of the grazing the orbit
// exists. A step that loses the new impact is halved until it keeps it. ∂/∂λ and ∇v² by central
// differences with steps far below the depth's scale.
//
// `half`: a symmetric orbit of a mirror-symmetric model, solved as a fixed point of the half map
// H = −Φ_{qT/2} (Problem::HalfMap) instead of F = H∘H. Its new impacts come in mirror pairs, one
// in each half period, equally slow: F has the square-root term of both, and holding one speed
// leaves the other's, on which Newton stalls (the tube's four-impact orbit next to ω = 0.569366,
// at speeds near 1e-4). H has one slow impact, the one held: the impact is the slowest of the
// seed's first half period.
std::optional<Point> NewtonOnNewImpact(const Problem& p, Eigen::VectorXd z, double lambda, double v_t, size_t more,
                                       const std::function<bool()>& stop, bool half = false) {
  const auto N = z.size();
  const auto map = [&](const Eigen::VectorXd& zz, double l, Eigen::MatrixXd* jac) {
    return half ? p.HalfMap(zz, l, jac) : p.Map(zz, l, jac);
  };
  // The new impact: the slowest of the seed's period (half period), followed by its contact and
  // phase (another new impact, e.g. the mirror one of a symmetric orbit, may be as slow: v as the
  // slowest of both would have a kink).
  const auto first = ImpactsAt(p, z, lambda);
  if (!first || (!half && first->size() < more)) return std::nullopt;
  const double cycle = 2.0 * M_PI * p.period();
  const auto in_first_half = [&](const BranchPoint::Impact& i) {
    const double offset = std::fmod(std::fmod(i.phase - p.phase(), cycle) + cycle, cycle);
    return offset < 0.5 * cycle;
  };
  auto slowest = first->end();
  for (auto it = first->begin(); it != first->end(); ++it)
    if ((!half || in_first_half(*it)) &&
        (slowest == first->end() || std::abs(it->v_before) < std::abs(slowest->v_before)))
      slowest = it;
  if (slowest == first->end()) return std::nullopt;
  const int contact = slowest->contact;
  const double phase = slowest->phase;
  const auto speed2 = [&](const Eigen::VectorXd& zz, double l) -> std::optional<double> {
    const auto imp = ImpactsAt(p, zz, l);
    if (!imp) return std::nullopt;
    // On the half map only the first half period is solved for: its impacts (half of the orbit's)
    // must all be there; the second half's follow once the iterate is symmetric.
    if (half ? static_cast<size_t>(std::count_if(imp->begin(), imp->end(), in_first_half)) < (more + 1) / 2
             : imp->size() < more)
      return std::nullopt;
    double best = std::numeric_limits<double>::infinity(), v = 0;
    for (const auto& i : *imp) {
      if (i.contact != contact || (half && !in_first_half(i))) continue;
      const double d = std::abs(std::remainder(i.phase - phase, cycle));
      if (d < best) {
        best = d;
        v = i.v_before;
      }
    }
    if (!std::isfinite(best)) return std::nullopt;
    return v * v;
  };
  double last = std::numeric_limits<double>::infinity();
  for (int it = 0; it < 40; ++it) {
    if (stop()) return std::nullopt;
    Eigen::MatrixXd DF;
    const auto F = map(z, lambda, &DF);
    const auto v2 = speed2(z, lambda);
    if (!F || !v2) return std::nullopt;
    const Eigen::VectorXd G = *F - z;
    const double res = G.cwiseAbs().maxCoeff() / (1.0 + z.cwiseAbs().maxCoeff());
    const double res_v = std::abs(std::sqrt(*v2) - v_t) / v_t;
    // The map's rounding floor grows with |DF| (each slow impact contributes a factor 1/v): once
    // Newton stops gaining, a residual within 1e-14·|DF| of it is converged (10⁻¹¹ otherwise).
    const double floor = 1e-11 * std::max(1.0, 1e-3 * DF.cwiseAbs().maxCoeff());
    // The speed itself is known to the rounding of the depth over v (1e-16/v): once Newton stalls
    // it is held within 1e-3 of v_t (the caller measures the speed it got).
    if ((res < 1e-13 && res_v < 1e-6) || (res < floor && res > 0.1 * last && res_v < 1e-3)) {
      const Evaluation e = p.Evaluate(z, lambda);
      if (!e.ok) return std::nullopt;
      Eigen::VectorXd y(N + 1);
      y << z, lambda;
      return p.Examine({y, e});
    }
    last = res;
    Eigen::MatrixXd J(N + 1, N + 1);
    J.topLeftCorner(N, N) = DF - Eigen::MatrixXd::Identity(N, N);
    // At a fixed state, λ moves the depth of the slow impact at a rate of order one, and F has a
    // square-root term in that depth (∝ v): its difference in λ is a derivative only over steps
    // that change v² by a small fraction of itself. The step is cut to 1e-3 of v_t² over the
    // rate at which v² changes (v² being linear in the depth, its own difference is exact).
    double hl = 1e-9 * std::max(1.0, std::abs(lambda));
    auto vp = speed2(z, lambda + hl), vm = speed2(z, lambda - hl);
    for (int k = 0; k < 4 && !(vp && vm); ++k) {  // the slow impact lost within hl: shorter
      hl *= 1e-2;
      vp = speed2(z, lambda + hl);
      vm = speed2(z, lambda - hl);
    }
    if (vp && vm) {
      const double rate = std::abs(*vp - *vm) / (2 * hl);
      if (rate * hl > 1e-3 * v_t * v_t)
        hl = std::max(1e-3 * v_t * v_t / rate, 1e-15 * std::max(1.0, std::abs(lambda)));
      vp = speed2(z, lambda + hl);
      vm = speed2(z, lambda - hl);
    }
    const auto Fp = map(z, lambda + hl, nullptr), Fm = map(z, lambda - hl, nullptr);
    if (!Fp || !Fm || !vp || !vm) return std::nullopt;
    J.topRightCorner(N, 1) = (*Fp - *Fm) / (2 * hl);
    J(N, N) = (*vp - *vm) / (2 * hl);
    for (long k = 0; k < N; ++k) {
      double h = 1e-9 * (1.0 + std::abs(z[k]));
      std::optional<double> a, b;
      for (int j = 0; j < 5 && !(a && b); ++j, h *= 1e-2) {  // shorter where the impact is lost within h
        Eigen::VectorXd zp = z, zm = z;
        zp[k] += h;
        zm[k] -= h;
        a = speed2(zp, lambda);
        b = speed2(zm, lambda);
        if (a && b) break;
      }
      if (!a || !b) return std::nullopt;
      J(N, k) = (*a - *b) / (2 * h);
    }
    Eigen::VectorXd r(N + 1);
    r << G, *v2 - v_t * v_t;
    const Eigen::VectorXd dy = -J.fullPivLu().solve(r);
    if (!dy.allFinite()) return std::nullopt;
    // Backtracking on the residual (the speed's in speed units: (v² − v_t²)/2v_t): a full step
    // leaves the depth's scale when the seed is not yet close.
    const auto merit = [&](const Eigen::VectorXd& zz, double l) -> std::optional<double> {
      const auto FF = map(zz, l, nullptr);
      const auto vv = speed2(zz, l);
      if (!FF || !vv) return std::nullopt;
      return std::hypot((*FF - zz).norm(), (*vv - v_t * v_t) / (2 * v_t));
    };
    const double m0 = std::hypot(G.norm(), (*v2 - v_t * v_t) / (2 * v_t));
    double w = 1.0;
    bool moved = false;
    for (int k = 0; k < 30; ++k, w *= 0.5) {
      const auto mk = merit(z + w * dy.head(N), lambda + w * dy[N]);
      if (mk && *mk < (1 - 1e-4 * w) * m0) {
        moved = true;
        break;
      }
    }
    if (!moved) return std::nullopt;
    z += w * dy.head(N);
    lambda += w * dy[N];
  }
  return std::nullopt;
}

// The orbit with the new impact(s) whose slowest impact has speed v_t, next to a grazing at λ_g
// where `graze` is the branch's orbit (at λ ≈ λ_g: its flight touches a stop). Seeds: along the
// line z_g + α·d at λ_g (d: the state part of the branch tangent, then each coordinate), the
// states whose first period has the new impact(s) are bounded at some α₀ (bisected on the impact
// count); Newton starts just past it.
struct AcrossGrazingResult {
  Point point;
  double speed = 0;  // the slowest impact speed of its period: the new impact's
};
std::optional<AcrossGrazingResult> AcrossGrazing(const Problem& p, const Point& graze, const Eigen::VectorXd& tangent,
                                                 double lambda, double v_t, const std::function<bool()>& stop) {
  const auto n2 = graze.y.size() - 1;
  const Eigen::VectorXd zg = graze.y.head(n2);
  const auto base = ImpactsAt(p, zg, graze.y[n2]);
  if (!base) return std::nullopt;
  const size_t more = base->size() + 1;
  const double scale = 1.0 + zg.cwiseAbs().maxCoeff();
  std::vector<Eigen::VectorXd> directions;
  if (tangent.head(n2).norm() > 1e-12) directions.push_back(tangent.head(n2).normalized());
  for (long k = 0; k < n2; ++k) directions.push_back(Eigen::VectorXd::Unit(n2, k));
  const auto has_more = [&](double alpha, const Eigen::VectorXd& d) -> std::optional<bool> {
    const auto imp = ImpactsAt(p, zg + alpha * d, lambda);
    if (!imp) return std::nullopt;
    return imp->size() >= more;
  };
  for (const auto& d : directions) {
    if (stop()) return std::nullopt;
    const auto at0 = has_more(0.0, d);
    if (!at0) continue;
    // The nearest α on either side where the count changes, then bisection to the boundary.
    for (const double sign : {1.0, -1.0}) {
      double a = 0, b = 0;
      bool found = false;
      for (int k = 0; k < 50 && !found; ++k) {
        b = sign * 1e-12 * scale * std::pow(2.0, k);
        const auto f = has_more(b, d);
        if (!f) break;
        if (*f != *at0) found = true;
        else a = b;
      }
      if (!found) continue;
      // a: the count at α = 0; b: the other. Bisect to the boundary.
      for (int k = 0; k < 200 && std::abs(b - a) > 1e-15 * scale; ++k) {
        const double mid = 0.5 * (a + b);
        const auto f = has_more(mid, d);
        if (!f) break;
        (*f == *at0 ? a : b) = mid;
      }
      const double outside = *at0 ? b : a, inside = *at0 ? a : b;  // without / with the new impact
      for (int j = 0; j < 8; ++j) {
        const double alpha = inside + (inside - outside) * (std::pow(16.0, j) - 1.0);
        const auto pt = NewtonOnNewImpact(p, zg + alpha * d, lambda, v_t, more, stop);
        if (!pt) continue;
        const auto imp = ImpactsAt(p, pt->y.head(n2), pt->y[n2]);
        if (!imp || imp->size() < more || SameFamily(graze, *pt)) continue;
        return AcrossGrazingResult{*pt, Slowest(*imp)};
      }
    }
  }
  return std::nullopt;
}

// ---- Approaching a grazing from the side of its slow impact (docs/orbits.md, "Through a grazing") ----

// A transition is named a grazing only where the grazing quantity of the orbit at the located
// point — its slowest isolated impact's speed, or its flight's closest approach to a stop, over
// the contact's largest speed or range (orbit_probe.hpp) — is below this.
constexpr double kGrazingTolerance = 1e-5;
// A branch whose slowest impact is slower than this (same measure) and slowing down is followed
// to the grazing by the speed itself (ApproachGrazing), not by arclength.
constexpr double kApproachSpeed = 1e-2;
// A corrected point is on the branch only within this many arclength steps of its predictor
// (docs/orbits.md, "One orbit family per branch"): along one family, a point corrected on the
// hyperplane at arclength s lies O(s) from it, by at most s/cos θ where the family turns by θ at
// a non-smooth point between (4: θ up to 75°). A point farther is another orbit, which the
// corrector reached on the same hyperplane (the tube's four-impact orbit at ω = 0.41290, whose
// corrector converged 153 steps away onto the symmetric two-impact orbit at ω = 0.42964).
constexpr double kSameFamilyReach = 4.0;

// The orbits of a branch whose slowest impact slows down towards a grazing, followed with that
// speed as the parameter: Newton on {F(z; λ) = z, v(z, λ) = v_t} (NewtonOnNewImpact: λ unknown)
// for v_t = v₀/4, v₀/16, … down to 1e-6 of the contact's largest speed, or as far as Newton
// converges. Near the grazing the orbit is strongly unstable (DF grows like 1/v): pseudo-arclength
// steps creep there, while in v the orbit and λ are smooth (λ − λ_g = v/c₁ + O(v²), docs/orbits.md
// "Near a grazing"). λ_g is where λ(v) extrapolates to v = 0: the constant of the cubic (or,
// with fewer points, quadratic) least-squares fit through the slowest ones; `bracket` is its
// distance to the fit of one degree less, three standard errors, the largest change when one
// orbit is left out and the distance to the line through the two slowest. Below 1e-6 of the
// scale the orbits add rounding to λ, not accuracy: the march stops there.
struct GrazingApproach {
  std::vector<Point> points;   // the march's orbits, the slow impact slowing down
  std::vector<double> speeds;  // its speed |ẋ⁻| on each
  double scale = 1;            // the contact's largest speed (the probe's scale)
  double value = 0, bracket = 0;
  bool located = false;  // the last speed is below kGrazingTolerance·scale and λ_g is fitted
  // The orbit is symmetric in a mirror-symmetric model and its slowest impacts are a mirror pair
  // (contacts `contacts`), dying out together: marched on the half map (NewtonOnNewImpact, `half`).
  bool mirrored = false;
  std::vector<int> contacts;
};
GrazingApproach ApproachGrazing(const Problem& p, const Point& from, const std::function<bool()>& stop) {
  GrazingApproach a;
  const auto n2 = from.y.size() - 1;
  const auto imp = ImpactsAt(p, from.y.head(n2), from.y[n2]);
  if (!imp || imp->empty()) return a;
  const double v0 = Slowest(*imp);
  if (!(v0 > 0) || !(from.probe.impact_speed > 0) || !std::isfinite(from.probe.impact_speed)) return a;
  a.scale = v0 / from.probe.impact_speed;
  const size_t more = imp->size();
  // A symmetric orbit (H(z) = z within 1e-9 of its scale) of a mirror-symmetric model, q odd, whose
  // slowest impact's mirror image (the image contact, half a period later) is as slow (1e-6).
  if (p.period() % 2 == 1) {
    const auto scene = p.SceneAt(from.y[n2]);
    const auto image = scene ? MirrorImage(System(*scene)) : std::nullopt;
    const auto h = image ? p.HalfMap(from.y.head(n2), from.y[n2], nullptr) : std::nullopt;
    if (h && (*h - from.y.head(n2)).cwiseAbs().maxCoeff() < 1e-9 * (1.0 + from.y.head(n2).cwiseAbs().maxCoeff())) {
      const double cycle = 2.0 * M_PI * p.period();
      for (const auto& i : *imp) {
        if (std::abs(std::abs(i.v_before) - v0) > 1e-12 * a.scale) continue;
        for (const auto& k : *imp)
          if (k.contact == (*image)[static_cast<size_t>(i.contact)] &&
              std::abs(std::remainder(k.phase - i.phase - 0.5 * cycle, cycle)) < 1e-6 &&
              std::abs(std::abs(k.v_before) - v0) < 1e-6 * std::max(v0, 1e-3 * a.scale)) {
            a.mirrored = true;
            a.contacts = {std::min(i.contact, k.contact), std::max(i.contact, k.contact)};
          }
        if (a.mirrored) break;
      }
    }
  }
  std::vector<Eigen::VectorXd> ys = {from.y};
  std::vector<double> vs = {v0};
  // Each step divides the speed by 4; a step whose Newton fails is retried dividing it by 2, then
  // by √2, before the march ends.
  double factor = 0.25;
  for (int k = 1; k <= 40; ++k) {
    if (stop()) return a;
    const double v_t = vs.back() * factor;
    // The predictor: the Lagrange polynomial in v through the last three orbits (the last orbit
    // itself before there are three). It must be quadratic: the orbit is z_g + a·v + b·v² + …,
    // and the depth the seed's flight reaches, which sets its speed, is ∝ v² with a contributing
    // nothing to it: a linear predictor gets the depth wrong by more than itself (the seed then has
    // no slow impact at all), while the last orbit's is 16 times too deep, which Newton corrects.
    Eigen::VectorXd y = ys.back();
    const size_t j = ys.size() - 1;
    if (ys.size() >= 3) {
      const double a0 = vs[j - 2], a1 = vs[j - 1], a2 = vs[j];
      y = ((v_t - a1) * (v_t - a2) / ((a0 - a1) * (a0 - a2))) * ys[j - 2] +
          ((v_t - a0) * (v_t - a2) / ((a1 - a0) * (a1 - a2))) * ys[j - 1] +
          ((v_t - a0) * (v_t - a1) / ((a2 - a0) * (a2 - a1))) * ys[j];
    }
    auto pt = NewtonOnNewImpact(p, y.head(n2), y[n2], v_t, more, stop, a.mirrored);
    // On the half map the orbit is judged by its first half period (its slow impact held there,
    // the same count as the seed's): at speeds near 1e-5 of the scale the mirror impact's depth,
    // ∝ v², is below the rounding of a full period's simulation (DF ∝ 1/v), which may lose it.
    const auto first_half = [&](const std::vector<BranchPoint::Impact>& all) {
      const double cycle = 2.0 * M_PI * p.period();
      std::vector<BranchPoint::Impact> h;
      for (const auto& i : all)
        if (std::fmod(std::fmod(i.phase - p.phase(), cycle) + cycle, cycle) < 0.5 * cycle) h.push_back(i);
      return h;
    };
    auto pi = pt && (a.mirrored || SameFamily(from, *pt)) ? ImpactsAt(p, pt->y.head(n2), pt->y[n2]) : std::nullopt;
    if (pi && a.mirrored) {
      pi = first_half(*pi);
      if (pi->size() != first_half(*imp).size()) pi.reset();
    }
    if (!pi || !(Slowest(*pi) < vs.back())) {
      if (factor > 0.7) break;
      factor = std::sqrt(factor);
      continue;
    }
    factor = 0.25;
    ys.push_back(pt->y);
    vs.push_back(Slowest(*pi));
    a.points.push_back(std::move(*pt));
    a.speeds.push_back(vs.back());
    if (v_t < 1e-6 * a.scale) break;
  }
  if (a.points.size() < 3 || !(a.speeds.back() < kGrazingTolerance * a.scale)) return a;
  // λ(v) through the slowest (up to six) orbits of the march, v scaled by the largest of them.
  const size_t count = std::min<size_t>(6, ys.size()), first = ys.size() - count;
  const double vmax = vs[first];
  // The constant of the fit (leaving out the orbit `skip`, if any), and (sigma) its standard error
  // from the fit's residuals: λ of the slowest orbits carries the rounding of a map whose DF grows
  // like 1/v.
  const auto fit = [&](int degree, double* sigma, size_t skip) {
    const long rows = static_cast<long>(count) - (skip < count ? 1 : 0);
    Eigen::MatrixXd A(rows, degree + 1);
    Eigen::VectorXd l(rows);
    long r = 0;
    for (size_t i = 0; i < count; ++i) {
      if (i == skip) continue;
      for (int d = 0; d <= degree; ++d) A(r, d) = std::pow(vs[first + i] / vmax, d);
      l[r++] = ys[first + i][n2] - ys.back()[n2];
    }
    const Eigen::VectorXd c = A.colPivHouseholderQr().solve(l);
    if (sigma) {
      const long dof = rows - (degree + 1);
      const double s2 = dof > 0 ? (A * c - l).squaredNorm() / static_cast<double>(dof) : 0.0;
      const Eigen::MatrixXd cov = (A.transpose() * A).inverse();
      *sigma = std::sqrt(s2 * std::max(cov(0, 0), 0.0));
    }
    return ys.back()[n2] + c[0];
  };
  const int degree = count >= 5 ? 3 : 2;
  double sigma = 0;
  a.value = fit(degree, &sigma, count);
  // The bracket: the distance to the fit of one degree less, three standard errors, and the
  // largest change when one orbit is left out (with enough orbits left for the degree).
  double jack = 0;
  if (count >= static_cast<size_t>(degree) + 3)
    for (size_t i = 0; i < count; ++i) jack = std::max(jack, std::abs(fit(degree, nullptr, i) - a.value));
  // And the line through the two slowest orbits alone: near v = 0 it is the leading term, and its
  // distance to the fit measures the rounding of those orbits' λ that the fit smooths over.
  const size_t e = ys.size() - 1;
  const double line = ys[e][n2] - vs[e] * (ys[e][n2] - ys[e - 1][n2]) / (vs[e] - vs[e - 1]);
  a.bracket = std::abs(a.value - fit(degree - 1, nullptr, count)) + 3.0 * sigma + jack +
              std::abs(a.value - line) + 4 * std::numeric_limits<double>::epsilon() * std::abs(a.value);
  a.located = std::isfinite(a.value);
  return a;
}

// How far apart two orbits at one λ are, from what does not depend on where their sections sit:
// their impacts over the period (phase mod 2π·q, sorted; contact; speed), max of |Δphase| and
// |Δv|/(1 + the largest speed); ∞ when they have different impacts. Orbits without impacts: their
// stroboscopic states (one contact coordinate each, at the scene's forcing phase).
double OrbitDistance(const BranchPoint& a, const BranchPoint& b, int q) {
  if (a.impacts.size() != b.impacts.size()) return std::numeric_limits<double>::infinity();
  const double cycle = 2.0 * M_PI * q;
  auto sa = a.impacts, sb = b.impacts;
  const auto by_phase = [](const auto& x, const auto& y) { return x.phase < y.phase; };
  std::sort(sa.begin(), sa.end(), by_phase);
  std::sort(sb.begin(), sb.end(), by_phase);
  double scale = 1.0, d = 0.0;
  for (const auto& i : sa) scale = std::max(scale, 1.0 + std::abs(i.v_before));
  // The first impact of one list may sort last in the other (a phase next to 0 ≡ 2π·q): match
  // every rotation, keep the best.
  double best = std::numeric_limits<double>::infinity();
  for (size_t shift = 0; shift < std::max<size_t>(sb.size(), 1); ++shift) {
    d = 0.0;
    for (size_t k = 0; k < sa.size() && d < best; ++k) {
      const auto& x = sa[k];
      const auto& y = sb[(k + shift) % sb.size()];
      if (x.contact != y.contact) {
        d = std::numeric_limits<double>::infinity();
        break;
      }
      d = std::max({d, std::abs(std::remainder(x.phase - y.phase, cycle)),
                    std::abs(x.v_before - y.v_before) / scale});
    }
    best = std::min(best, d);
  }
  if (sa.empty()) {
    best = 0.0;
    if (a.strobe.size() != b.strobe.size()) return std::numeric_limits<double>::infinity();
    for (size_t j = 0; j < a.strobe.size(); ++j) best = std::max(best, std::abs(a.strobe[j] - b.strobe[j]));
    if (!std::isfinite(best)) return std::numeric_limits<double>::infinity();
  }
  return best;
}

// The state (X, V, λ) at the section time phase/ω (mod q·T) of the periodic orbit through the free
// state (X, V) at t0, at λ: the orbit's point on another section (closed loops compare a branch's
// first point with its current one on the current section). Nothing when it cannot be simulated.
std::optional<Eigen::VectorXd> OnSection(const Problem& p, double lambda, double t0, const Eigen::VectorXd& X,
                                         const Eigen::VectorXd& V, double phase) {
  auto scene = p.DecidingSceneAt(lambda);
  if (!scene) return std::nullopt;
  const System sys(*scene);
  const double T = 2.0 * M_PI / sys.frequency(), cycle = p.period() * T;
  double t_to = phase / sys.frequency();
  t_to += std::ceil((t0 - t_to) / cycle) * cycle;  // the first section time at or after t0
  Eigen::VectorXd out(2 * X.size() + 1);
  if (std::abs(t_to - t0) < 1e-12 * cycle) {
    out << X, V, lambda;
    return out;
  }
  struct Near final : Observer {
    double target = 0, best = std::numeric_limits<double>::infinity();
    Eigen::VectorXd X, V;
    void OnSection(const Sample& s) override {
      if (std::abs(s.t - target) < best) {
        best = std::abs(s.t - target);
        X = s.X;
        V = s.V;
      }
    }
  } near;
  near.target = t_to;
  const int j = static_cast<int>(std::ceil((t_to - t0) / T - 1e-9));
  scene->run.periods = j + 1;
  scene->run.samples_per_period = 0;
  const InitialOverride here{t0, X, V};
  SimulationOptions opt;
  opt.initial = &here;
  opt.section_origin = t_to - j * T;
  opt.observers = {&near};
  opt.loads = false;
  opt.max_segments = kMapSegmentsPerPeriod * scene->run.periods;
  if (Simulate(sys, *scene, opt).status != RunStatus::kOk || near.best > 1e-6 * T) return std::nullopt;
  out << near.X, near.V, lambda;
  return out;
}

// A non-smooth point the branch goes through again (docs/orbits.md, "Closed loops"): an earlier
// bifurcation of the branch, `index`, that the last one repeats: the same kind at the same λ (within
// 1e-9 relative, or their brackets) with the same orbits on its two sides, in either order (the
// branch crossing it the other way), or those orbits mirrored (`mirrored`: the model's mirror
// symmetry x ↦ −x, t ↦ t + T/2 maps one transition onto the other, contacts swapped). The orbits on
// each side are compared by their contact sequences as cyclic words in their canonical rotation
// (contact_sequence.hpp) with several contacts, by their events per period with one. From there
// on the branch would draw again what it has drawn, or its mirror image: e.g. the tube's symmetric
// orbit through its grazing at ω = 1.3646 onto a three-impact orbit, down to the asymmetric
// orbits' grazing at 0.9559, through their pitchfork onto the mirror ones, and up through the
// mirror grazings, round and round.
struct RepeatedTransition {
  size_t index = 0;
  bool mirrored = false, reversed = false;
};
std::optional<RepeatedTransition> RepeatsATransition(const Branch& br, const Problem& p) {
  if (br.bifurcations.size() < 2) return std::nullopt;
  const Bifurcation& g = br.bifurcations.back();
  if (g.through.empty()) return std::nullopt;
  const bool words = !g.sequence_before.empty() && !g.sequence_after.empty();
  // A side as compared: the canonical text of its sequence (renamed by `image` when given), or its
  // events per period.
  const auto side = [&](const Bifurcation& b, bool after, const std::vector<int>* image) -> std::string {
    const std::string& text = after ? b.sequence_after : b.sequence_before;
    if (!words) return after ? b.events_after : b.events_before;
    std::string problem;
    const auto entries = ParseContactSequence(text, -1, problem);
    if (!entries) return text;
    return ContactSequenceText(image ? RenameContacts(*entries, *image) : *entries);
  };
  std::optional<std::vector<int>> image;
  if (words) {
    if (const auto scene = p.DecidingSceneAt(g.value)) image = MirrorImage(System(*scene));
  }
  const std::string before = side(g, false, nullptr), after = side(g, true, nullptr);
  for (size_t k = 0; k + 1 < br.bifurcations.size(); ++k) {
    const Bifurcation& e = br.bifurcations[k];
    if (e.kind != g.kind || e.through.empty() ||
        std::abs(e.value - g.value) > 1e-9 * std::max(1.0, std::abs(g.value)) + e.bracket + g.bracket)
      continue;
    for (const bool mirrored : {false, true}) {
      if (mirrored && !image) continue;
      const std::vector<int>* im = mirrored ? &*image : nullptr;
      const std::string b0 = side(e, false, im), a0 = side(e, true, im);
      if (b0 == before && a0 == after) return RepeatedTransition{k, mirrored, false};
      if (b0 == after && a0 == before) return RepeatedTransition{k, mirrored, true};
    }
  }
  return std::nullopt;
}

// The branch's end where it met a transition again (RepeatsATransition): a closed loop.
void EndAtRepeat(Branch& br, const RepeatedTransition& r) {
  const Bifurcation& g = br.bifurcations.back();
  const Bifurcation& e = br.bifurcations[r.index];
  const std::string way = r.reversed ? "the other way" : "the same way";
  br.end = r.mirrored
               ? fmt::format("closed loop: through the mirror image of the {} at λ = {:.17g} (bifurcation {}, "
                             "{}; contact sequence {} ↔ {} mirrored, the model being symmetric under x ↦ −x, "
                             "t ↦ t + T/2): from here on the branch is the mirror image of its part from there",
                             e.kind, e.value, r.index, way, g.sequence_before, g.sequence_after)
               : fmt::format("closed loop: through the {} at λ = {:.17g} again (bifurcation {}, {}; the same "
                             "orbits on its two sides)",
                             e.kind, e.value, r.index, way);
  br.closed_loop = true;
}

// The branch as returned, with how many map evaluations needed the quad engine.
Branch& Finish(Branch& br, const Problem& p) {
  br.quad_evaluations = p.quad_evaluations();
  if (!p.corner().empty())
    br.corner = p.corner() + ": the branch's Newton steps, multipliers and bifurcations follow the first order's "
                             "piece (the gaps closing in ascending contact order)";
  for (auto& b : br.bifurcations)  // found after the last point: that point is before it
    if (b.point < 0 && !br.points.empty()) b.point = static_cast<long long>(br.points.size()) - 1;
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
  std::vector<bool> compliant;
  for (const ContactModel& c : first_sys.contacts()) compliant.push_back(c.spec.compliance.compliant());
  const double span = req.to - req.from;
  double ds = req.step > 0 ? req.step : std::abs(span) / 50.0;
  const double ds_max = req.max_step > 0 ? req.max_step : std::abs(span) / 10.0;
  // Below this a failed step means a boundary. Next to a grazing the branch went through, the
  // orbit's new impact is slow (speed ∝ the distance d to it) and DF grows like 1/v per new impact:
  // the corrector's basin shrinks with d, so the floor is a fiftieth of d there.
  const double ds_retry_far = 1e-4 * std::abs(span);
  double ds_retry = ds_retry_far;
  std::optional<double> grazing_crossed;  // λ of the last grazing the branch went through

  const auto record = [&](const Point& pt) {
    // A point computed while a stop request came may rest on runs it cut short: not kept (the
    // branch kept is the start of the uninterrupted branch; the loop reports the interruption).
    if (stopped()) return;
    // The bifurcations found since the last point lie between it and this one: the last point is
    // the orbit before them (Bifurcation::point).
    for (auto& b : br.bifurcations)
      if (b.point < 0 && !br.points.empty()) b.point = static_cast<long long>(br.points.size()) - 1;
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
  bool went_away = false;  // the branch has been 1e-3 away from its first point (closed loops)
  Eigen::VectorXd first_y = cur.y;  // the first point on the section first_phase (closed loops)
  double first_phase = p.phase();
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

  // The branch's slowest impact dies out (docs/orbits.md, "Through a grazing", from the side of the
  // slow impact): the grazing is located by ApproachGrazing and the march's orbits are recorded;
  // then the orbit without that impact is looked for at λ_g ± δ, δ = 4 |λ_last − λ_g| (at least
  // 1e-9 relative), by Newton with λ held from the march's last state. It must be the grazing's
  // own orbit: its flight's closest approach to the stop at 2δ is twice that at δ (within 15 %:
  // linear in the distance). Returns 0 when the grazing is not located (the caller goes on as
  // before), 1 when the branch goes on along that orbit, 2 when it ends there (no orbit goes on,
  // or a closed loop).
  double approach_failed_at = std::numeric_limits<double>::infinity();  // the probe's speed where a march failed
  const auto through_slow_side = [&](const Point& from) -> int {
    GrazingApproach a = ApproachGrazing(p, from, stop_requested);
    if (!a.located || stop_requested()) {
      approach_failed_at = from.probe.impact_speed;
      return 0;
    }
    const Point last = a.points.back();
    const double lg = a.value, d_last = last.y[n2] - lg;
    const double toward = d_last > 0 ? -1.0 : 1.0;  // the march's direction in λ
    const double delta = std::max(4.0 * std::abs(d_last), 1e-9 * std::max(1.0, std::abs(lg)));
    const auto held = [&](const Eigen::VectorXd& seed, double lambda) -> std::optional<Point> {
      Eigen::VectorXd y = seed;
      y[n2] = lambda;
      Eigen::VectorXd e_lambda = Eigen::VectorXd::Zero(n2 + 1);
      e_lambda[n2] = 1.0;
      int iters = 0;
      const auto yc = Correct(p, y, e_lambda, iters);
      return yc ? p.Examine(*yc) : std::nullopt;
    };
    std::optional<Point> after;
    double side = 0, gap1 = 0, gap2 = 0;
    for (const double s : {toward, -toward}) {
      if (stop_requested()) break;
      const auto q1 = held(last.y, lg + s * delta);
      if (!q1 || SameFamily(from, *q1) || Sticks(*q1) != Sticks(from) ||
          Count(q1->probe.signature, 'I') >= Count(from.probe.signature, 'I'))
        continue;
      const auto q2 = held(q1->y, lg + 2.0 * s * delta);
      if (!q2 || !SameFamily(*q1, *q2)) continue;
      const double g1 = PreciseGap(p, q1->y), g2 = PreciseGap(p, q2->y);
      if (!(g1 > 0 && std::isfinite(g1) && std::isfinite(g2) && std::abs(g2 / g1 - 2.0) < 0.3)) continue;
      after = q1;
      side = s;
      gap1 = g1;
      gap2 = g2;
      break;
    }
    if (stop_requested()) return 0;
    // (a march on the half map: only its orbits whose full period has the branch's events)
    for (const auto& pt : a.points)
      if (SameFamily(from, pt)) record(pt);
    const double v_last = a.speeds.back();
    const int c = m > 1 ? from.probe.at.impact_speed : -1;
    Bifurcation g{"grazing", lg, "", a.bracket, c};
    g.events_before = from.probe.signature;
    g.sequence_before = from.orbit.sequence;
    g.events_after = after ? after->probe.signature : "";
    g.sequence_after = after ? after->orbit.sequence : "";
    g.through = !after ? "" : side == toward ? "past" : "back";
    g.new_impact_speed = v_last;
    g.new_impact_distance = std::abs(d_last);
    // A mirror pair of slow impacts dying out together: both contacts named.
    const std::string on =
        a.mirrored ? fmt::format("s on contacts {} and {} (a mirror pair half a period apart, equally slow: the orbit "
                                 "is symmetric under x ↦ −x, t ↦ t + T/2, and is followed on the half map "
                                 "z ↦ −Φ_{{T/2}}(z), one slow impact per half period)",
                                 a.contacts[0], a.contacts[1])
        : m > 1 ? fmt::format(" on contact {}", c)
                : "";
    const std::string change =
        after ? fmt::format("events per period {} → {}{}", g.events_before,
                            g.events_after.empty() ? "(none: a free orbit)" : g.events_after,
                            m > 1 ? fmt::format("; contact sequence {} → {}", g.sequence_before, g.sequence_after) : "")
              : fmt::format("events per period {}{}", g.events_before,
                            m > 1 ? fmt::format("; contact sequence {}", g.sequence_before) : "");
    g.detail = fmt::format(
        "the slowest impact{} {}: followed by {} speed, {} to {:.2e} ({:.1e} of the contact's "
        "largest speed; grazing tolerance {:.0e}) at {:.1e} from here, where λ against that speed extrapolates "
        "to 0 ({} orbits from speed {:.2e}); {}; {}",
        on, a.mirrored ? "die out together" : "dies out", a.mirrored ? "their" : "its",
        a.mirrored ? "they fall" : "it falls", v_last, v_last / a.scale, kGrazingTolerance, std::abs(d_last), a.points.size(), a.speeds.front(), change,
        !after ? fmt::format("no orbit without {} is found at λ_g ± {:.1e}: the orbit does not go on",
                             a.mirrored ? "them" : "it", delta)
        : fmt::format("the branch {} along the orbit without {} (its closest approach to the stop {:.2e} at {:.1e} "
                      "from the grazing, {:.2e} at {:.1e}: linear in the distance)",
                      g.through == "past" ? "goes on past it" : "turns back (a grazing fold: both orbits exist on this side)",
                      a.mirrored ? "them" : "it", gap1, delta, gap2, 2.0 * delta));
    br.bifurcations.push_back(g);
    transition.reset();
    if (!after) {
      br.end = "grazing (the orbit does not go on)";
      return 2;
    }
    if (const auto r = RepeatsATransition(br, p)) {
      record(*after);  // the branch's last orbit: the one it reached, where it would redraw itself
      EndAtRepeat(br, *r);
      return 2;
    }
    cur = *after;
    t = Tangent(cur.eval, Eigen::VectorXd());
    if (t[n2] * side < 0) t = -t;  // away from the grazing
    section_fresh = false;
    record(cur);
    ds = std::max(4.0 * delta, ds_retry_far);
    grazing_crossed = lg;
    if (cur.probe.section_margin < 0.3 && !move_section()) {
      br.end = "grazing (the orbit past it is too degenerate to continue)";
      return 2;
    }
    return 1;
  };
  // A stall (docs/orbits.md, "Through a grazing"): the last kStallSteps accepted steps, all on
  // strongly unstable orbits (largest |multiplier| above 1e3), add up to less than 1e-3 of the span
  // in arclength. The corrector creeps there (near a fold of an orbit next to a grazing, where DF
  // grows like 1/v): the branch ends with the numbers, rather than spend its points there.
  constexpr size_t kStallSteps = 40;
  std::deque<double> recent_steps;  // arclength of the last accepted steps on strongly unstable orbits
  const auto largest_multiplier = [](const Point& x) {
    double lead = 0;
    for (const auto& mu : x.orbit.multipliers) lead = std::max(lead, std::abs(mu));
    return lead;
  };

  // Another orbit the corrector converged to, beyond reach of its predictor (kSameFamilyReach),
  // since the last accepted point: said in the branch's end if it ends there.
  struct OtherOrbit {
    double lambda, distance, step;
    std::string sequence;
  };
  std::optional<OtherOrbit> other;
  const auto reach_floor = [&] { return 1e-9 * (1.0 + cur.y.norm()); };
  const auto note_other = [&](const Point& q, double s) {
    std::string sequence = m > 1 ? q.orbit.sequence : q.probe.signature;
    if (sequence.empty()) sequence = "a free orbit";
    other = OtherOrbit{q.y[n2], (q.y - cur.y).norm(), s, sequence};
  };
  const auto within_reach = [&](const Point& q, double s) {
    return (q.y - cur.y).norm() <= kSameFamilyReach * s + reach_floor();
  };
  const auto other_note = [&]() -> std::string {
    if (!other) return "";
    return fmt::format("; the corrector converges only to another orbit ({} at λ = {:.10g}, {:.2e} away for a step "
                       "of {:.2e}), not joined to this branch",
                       other->sequence, other->lambda, other->distance, other->step);
  };

  while (static_cast<int>(br.points.size()) < req.max_points) {
    if (stop_requested()) {
      br.status = "interrupted";
      br.end = "interrupted";
      return Finish(br, p);
    }
    if (grazing_crossed) {
      const double d = std::abs(cur.y[n2] - *grazing_crossed);
      ds_retry = std::min(ds_retry_far, 0.02 * d * std::hypot(1.0, cur.y.head(n2).norm()));
      p.SetLambdaStep(std::clamp(1e-2 * d * d / std::max(1.0, std::abs(cur.y[n2])), 1e-12, 1e-6));
    }
    auto next = trial(ds);
    // A corrected point beyond reach of its predictor is another orbit, whatever the step: never
    // joined to this branch (kSameFamilyReach); the step is shortened below, or the branch ends
    // saying so.
    if (next && (next->y - (cur.y + ds * t)).norm() > kSameFamilyReach * ds + reach_floor()) {
      note_other(*next, ds);
      next.reset();
    }
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
      // A closed loop (docs/orbits.md, "Closed loops"): after the branch went away from its first
      // point, the step crosses the hyperplane through the first orbit (taken to the current
      // section) normal to the branch, near it and on its events; the orbit corrected on that
      // hyperplane is the first one again (impacts within 1e-7, same λ). The branch stops there:
      // going on would draw the loop again.
      if (went_away && next->probe.signature == br.points.front().signature && !stop_requested()) {
        const double l0 = br.points.front().value;
        std::optional<Corrected> yc;
        int iters = 0;
        if (p.phase() != first_phase) {  // the first orbit on the current section
          const BranchPoint& f0 = br.points.front();
          if (auto y = OnSection(p, l0, f0.section_time, f0.X, f0.V, p.phase())) {
            first_y = *y;
            first_phase = p.phase();
          }
        }
        if (p.phase() == first_phase) {
          const double a0 = t.dot(cur.y - first_y), a1 = t.dot(next->y - first_y);
          if (a0 * a1 <= 0 && a0 != a1 && (cur.y - first_y).norm() < 4.0 * ds + 1e-9) {
            const Eigen::VectorXd from_here = cur.y + (a0 / (a0 - a1)) * (next->y - cur.y);
            yc = Correct(p, first_y, t, iters, false, &from_here);
          }
        }
        const auto back = yc ? p.Examine(*yc) : std::nullopt;
        if (back && SameFamily(cur, *back)) {
          const size_t before = br.points.size();
          record(*back);
          if (br.points.size() > before) {
            const double d = std::max(OrbitDistance(br.points.front(), br.points.back(), p.period()),
                                      std::abs(br.points.back().value - l0) / std::max(1.0, std::abs(l0)));
            if (d < 1e-7) {
              br.end = fmt::format("closed loop: back at its first point (λ = {:.17g}; orbit within {:.1e}) after "
                                   "{} points",
                                   br.points.back().value, d, br.points.size() - 1);
              br.closed_loop = true;
              return Finish(br, p);
            }
            br.points.pop_back();
          }
        }
      }
      const double speed_before = cur.probe.impact_speed, step = (next->y - cur.y).norm();
      cur = *next;
      t = t_new;
      section_fresh = false;
      record(cur);
      if (!went_away && br.points.size() > 1 &&
          OrbitDistance(br.points.front(), br.points.back(), p.period()) +
                  std::abs(br.points.back().value - br.points.front().value) /
                      std::max(1.0, std::abs(br.points.front().value)) > 1e-3)
        went_away = true;
      transition.reset();
      other.reset();
      ds = std::min(ds * 1.5, ds_max);
      // A slow impact slowing down: followed to its grazing by its speed (ApproachGrazing).
      const double speed = cur.probe.impact_speed;
      if (speed < kApproachSpeed && speed < speed_before && speed < 0.5 * approach_failed_at && !stop_requested()) {
        const int r = through_slow_side(cur);
        if (r == 2) return Finish(br, p);
        if (r == 1) {
          recent_steps.clear();
          continue;
        }
      }
      if (largest_multiplier(cur) > 1e3) {
        recent_steps.push_back(step);
        if (recent_steps.size() > kStallSteps) recent_steps.pop_front();
        double total = 0;
        for (const double x : recent_steps) total += x;
        if (recent_steps.size() == kStallSteps && total < 1e-3 * std::abs(span)) {
          br.end = fmt::format("stalled at λ = {:.17g}: the last {} steps add up to {:.1e} in arclength (1e-3 of the "
                               "span is {:.1e}) on strongly unstable orbits (largest |multiplier| {:.3g} here; slowest "
                               "impact speed {:.1e} of its contact's largest, grazing quantity {:.1e})",
                               cur.y[n2], kStallSteps, total, 1e-3 * std::abs(span), largest_multiplier(cur),
                               cur.probe.impact_speed, std::min(cur.probe.impact_speed, cur.probe.flight_gap));
          return Finish(br, p);
        }
      } else {
        recent_steps.clear();
      }
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
      double s_past = ds;  // the arclength from cur at which `past` was corrected
      p.ClearUndetermined();
      for (int it = 0; it < 100; ++it) {
        if (stop_requested()) break;
        const double mid = 0.5 * (lo + hi);
        auto pm = trial(mid);
        if (pm && !within_reach(*pm, mid)) {  // another orbit: as if the corrector had failed
          note_other(*pm, mid);
          pm.reset();
        }
        if (pm && SameFamily(cur, *pm)) {
          cur = *pm;  // the branch point nearest to the boundary so far
          moved = true;
          hi -= mid;
          s_past -= mid;
          lo = 0.0;
        } else {
          hi = mid;
          if (pm) {
            past = pm;
            s_past = mid;
          } else if (past && (past->y - cur.y).norm() > 2.0 * hi) {
            past.reset();
          }
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
      // along one branch, corrected points an arclength h apart are O(h) apart (kSameFamilyReach).
      if (past && !within_reach(*past, std::max(s_past, hi))) {
        note_other(*past, std::max(s_past, hi));
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
        if (po && !SameFamily(cur, *po)) {
          if (within_reach(*po, s_over)) {
            past = po;
            s_past = s_over;
          } else {
            note_other(*po, s_over);
          }
        }
      }
      // Isolated impacts vanish across a transition only by slowing down to zero there (a grazing,
      // docs/orbits.md "Near a grazing"): where the orbit past the point has fewer of them than the
      // located orbit, whose slowest impact is not slow (its test quantity not below the 1e-3 at
      // which NameNonSmooth calls one vanishing), the point is where the corrector gave out, short
      // of the grazing, and the orbit on the far side is another family met on the same hyperplane
      // (next to a grazing fold, e.g. the tube's symmetric two-impact orbit 1e-4 from its
      // four-impact one near ω = 0.4129, both meeting at the grazing at 0.41277): not joined.
      // (A regrouped chattering sequence changes the count of I without a vanishing impact: a
      // relabel, left alone.)
      if (past && past->probe.coarse_signature != cur.probe.coarse_signature &&
          Count(past->probe.signature, 'I') < Count(cur.probe.signature, 'I') && cur.probe.impact_speed >= 1e-3 &&
          cur.probe.impact_speed <= cur.probe.flight_gap) {
        note_other(*past, std::max(s_past, hi));
        past.reset();
      }
      auto [kind, detail, contact] = NameNonSmooth(cur, past ? &*past : nullptr, m, compliant);
      // The boundary lies between cur and its predictor at arclength hi.
      const double at = cur.y[n2] + 0.5 * hi * t[n2], bracket = hi * std::abs(t[n2]);
      if (moved) record(cur);
      if (kind == "relabel") {  // bookkeeping: recorded as such, and the branch goes on
        br.relabels.push_back({at, cur.probe.signature, past->probe.signature, detail, bracket});
        t = Tangent(past->eval, t);
        other.reset();
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
      // A grazing met from the side of its slow impact (cur's slowest impact is the grazing
      // quantity, below kApproachSpeed; a corrector that gives out next to it sees no vanishing
      // test quantity yet): located by the speed itself (through_slow_side), as after a smooth step.
      if ((kind == "grazing" || kind == "non-smooth") && cur.probe.impact_speed <= cur.probe.flight_gap &&
          cur.probe.impact_speed < kApproachSpeed && cur.probe.impact_speed < 0.5 * approach_failed_at &&
          !stop_requested()) {
        const int r = through_slow_side(cur);
        if (r == 2) return Finish(br, p);
        if (r == 1) {
          other.reset();
          continue;
        }
      }
      // A grazing is named so only where the grazing quantity at the located point (cur) is below
      // kGrazingTolerance: otherwise the corrector gave out before the grazing (e.g. creeping next
      // to a fold of a strongly unstable orbit), and the point is reported for what is known.
      if (kind == "grazing" && std::min(cur.probe.impact_speed, cur.probe.flight_gap) > kGrazingTolerance) {
        detail = fmt::format("not located as a grazing: the grazing quantity at λ = {:.17g} is {:.1e} (slowest impact "
                             "speed {:.1e} of its contact's largest, closest approach to a stop {:.1e} of its range), "
                             "above the tolerance {:.0e}; {}",
                             cur.y[n2], std::min(cur.probe.impact_speed, cur.probe.flight_gap), cur.probe.impact_speed,
                             cur.probe.flight_gap, kGrazingTolerance, detail);
        kind = "non-smooth";
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
        if (detail.rfind("not located as a grazing", 0) == 0) {
          br.end = fmt::format("no orbit found past λ = {:.17g} (bracket {:.1e}; largest |multiplier| {:.3g}): {}{}", at,
                               bracket, lead, detail, other_note());
          return Finish(br, p);
        }
        br.end = fmt::format("no orbit found past λ = {:.17g} (bracket {:.1e}) and no test quantity vanishes "
                             "there ({}; largest |multiplier| {:.3g}): not a bifurcation{}",
                             at, bracket, detail.substr(detail.find('(') + 1, detail.find(')') - detail.find('(') - 1),
                             lead, other_note());
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
        br.bifurcations.back().events_before = cur.probe.signature;
        br.bifurcations.back().sequence_before = cur.orbit.sequence;
        transition = Transition{br.bifurcations.size() - 1, br.points.size(), cur, t, p.phase(), {}};
      }
      br.bifurcations.back().events_after = past ? past->probe.signature : "";
      br.bifurcations.back().sequence_after = past ? past->orbit.sequence : "";
      // The branch goes on when the orbit past the point is of the same kind (a sticking orbit
      // that lost one of its sticking phases still sticks).
      // (Not when the orbit past it is itself at a sticking-lost boundary: e.g. a symmetric orbit
      // whose sticking phases on two contacts vanish together.)
      const bool goes_on = past && Sticks(*past) == Sticks(cur) &&
                           past->probe.signature.find_first_of("RI") != std::string::npos &&
                           !(kind == "sticking-lost" && past->probe.shortest_stick < 1e-6);
      if (!goes_on && kind == "grazing" && !past) {
        // Where the branch's orbit grazes a stop and no orbit with the same events goes on, the orbit
        // with the new low-velocity impact(s) is looked for on both sides, at ε and ε/2 from the
        // grazing: its new impact speed must grow linearly with the distance (docs/orbits.md, "Near a
        // grazing": v = √(2a)·μ/c + O(μ²)), which tells an orbit born at this grazing from another one.
        Bifurcation& g = br.bifurcations.back();
        const double dir = t[n2] != 0 ? (t[n2] > 0 ? 1.0 : -1.0) : (span > 0 ? 1.0 : -1.0);
        double v_scale = 0;
        for (const auto& imp : br.points.back().impacts) v_scale = std::max(v_scale, std::abs(imp.v_before));
        const double v_t = 1e-3 * (v_scale > 0 ? v_scale : 1.0);
        std::optional<AcrossGrazingResult> near, far = AcrossGrazing(p, cur, t, g.value, v_t, stop_requested);
        if (far) near = AcrossGrazing(p, cur, t, g.value, 0.5 * v_t, stop_requested);
        const double d_far = far ? far->point.y[n2] - g.value : 0.0, d_near = near ? near->point.y[n2] - g.value : 0.0;
        // Linear in the distance, on one side: d_near/d_far = 1/2 up to the O(μ²) term.
        if (!(near && d_far * d_near > 0 && std::abs(d_near / d_far - 0.5) < 0.15)) far.reset();
        const double eps = std::abs(d_far), side = d_far > 0 ? 1.0 : -1.0;
        if (far && near) {
          g.through = side == dir ? "past" : "back";
          g.events_after = far->point.probe.signature;
          g.sequence_after = far->point.orbit.sequence;
          g.new_impact_speed = near->speed;
          g.new_impact_distance = std::abs(near->point.y[n2] - g.value);
          if (const auto k = g.detail.find("; events per period"); k != std::string::npos) g.detail.resize(k);
          g.detail += fmt::format(
              "; events per period {} → {}{}; the branch {} along the orbit with the new impact{} (speed "
              "{:.3e} at {:.1e} from the grazing, {:.3e} at {:.1e}: linear in the distance)",
              g.events_before, g.events_after,
              m > 1 ? fmt::format("; contact sequence {} → {}", g.sequence_before, g.sequence_after) : "",
              g.through == "past" ? "goes on past it" : "turns back (a grazing fold: both orbits exist on this side)",
              Count(g.events_after, 'I') - Count(g.events_before, 'I') > 1 ? "s" : "", near->speed, std::abs(d_near),
              far->speed, eps);
          if (const auto r = RepeatsATransition(br, p)) {
            EndAtRepeat(br, *r);
            return Finish(br, p);
          }
          p.SetLambdaStep(std::clamp(1e-2 * eps * eps / std::max(1.0, std::abs(g.value)), 1e-12, 1e-6));
          record(near->point);
          other.reset();
          cur = far->point;
          cur.eval = p.Evaluate(cur.y.head(n2), cur.y[n2]);
          t = Tangent(cur.eval, Eigen::VectorXd());
          if (t[n2] * side < 0) t = -t;  // away from the grazing
          section_fresh = false;
          record(cur);
          ds = 0.25 * eps;
          grazing_crossed = g.value;
          transition.reset();
          if (cur.probe.section_margin < 0.3 && !move_section()) {
            br.end = "grazing (the orbit past it is too degenerate to continue)";
            return Finish(br, p);
          }
          continue;
        }
      }
      if (goes_on) {
        br.bifurcations.back().through = "past";
        if (const auto r = RepeatsATransition(br, p)) {
          EndAtRepeat(br, *r);
          return Finish(br, p);
        }
      }
      if (!goes_on) {
        br.end = kind == "sticking-lost" || kind == "undetermined" || kind == "no-jacobian" ? kind
                 : past && past->probe.signature.find_first_of("RI") == std::string::npos
                     ? kind + " (permanent contact beyond)"
                     : kind + " (the orbit does not go on)";
        if (!past) br.end += other_note();
        return Finish(br, p);
      }
      t = Tangent(past->eval, t);
      other.reset();
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
