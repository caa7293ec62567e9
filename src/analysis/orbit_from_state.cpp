// Periodic orbits from a given state (see include/vibro/orbit_from_state.hpp).
#include "vibro/orbit_from_state.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "vibro/attractor.hpp"

namespace vibro {
namespace {

constexpr int kSamples = 1024;  // dense samples per period where the section may be placed

Eigen::VectorXd Stack(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  Eigen::VectorXd z(a.size() + b.size());
  z << a, b;
  return z;
}

double RelativeDistance(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return (a - b).cwiseAbs().maxCoeff() / (1.0 + b.cwiseAbs().maxCoeff());
}

// Dense samples of a trajectory with the number of events met before each, so that two samples
// lie in one free flight when both are free and no event separates them. `keep` selects the
// sample indices kept (all when empty).
struct Trace final : Observer {
  int keep_every = 0, keep_index = 0;  // keep_every > 0: keep indices i ≡ keep_index (mod keep_every)
  long long events = 0, index = 0;
  struct Row {
    long long index, events;
    double t;
    Eigen::VectorXd z;
    Mode mode;
  };
  std::vector<Row> rows;
  void OnEvent(const Event&) override { ++events; }
  void OnSample(const Sample& s) override {
    const long long i = index++;
    if (keep_every > 0 && i % keep_every != keep_index) return;
    rows.push_back({i, events, s.t, Stack(s.X, s.V), s.mode});
  }
};

Trace Run(const System& sys, const Scene& scene, const InitialOverride& start, long long periods,
          std::vector<Observer*> more = {}, int keep_every = 0, int keep_index = 0,
          RunResult* result = nullptr) {
  Scene sc = scene;
  sc.initial_time = start.time;
  sc.run.periods = periods;
  sc.run.samples_per_period = kSamples;
  Trace trace;
  trace.keep_every = keep_every;
  trace.keep_index = keep_index;
  more.push_back(&trace);
  SimulationOptions opt;
  opt.initial = &start;
  opt.observers = more;
  const RunResult r = Simulate(sys, sc, opt);
  if (result) *result = r;
  return trace;
}

// The middle of the longest free flight among rows [0, end): the row index, or -1.
long long MiddleOfLongestFlight(const std::vector<Trace::Row>& rows, size_t end) {
  size_t best_len = 0, best_mid = 0;
  for (size_t i = 0; i < end;) {
    if (rows[i].mode != Mode::kFree) {
      ++i;
      continue;
    }
    size_t j = i + 1;
    while (j < end && rows[j].mode == Mode::kFree && rows[j].events == rows[i].events) ++j;
    // A flight cut by the first row (the start may be an event) or the last one counts too.
    if (j - i > best_len) {
      best_len = j - i;
      best_mid = (i + j - 1) / 2;
    }
    i = j;
  }
  return best_len >= 3 ? static_cast<long long>(best_mid) : -1;
}

std::string KindName(OrbitKind k) {
  return k == OrbitKind::kSticking ? "sticking-periodic" : k == OrbitKind::kImpact ? "impact-periodic" : "";
}

}  // namespace

OrbitResult OrbitFromState(const System& sys, const Scene& scene, const InitialOverride& start,
                           const OrbitRequest& req, double far) {
  OrbitResult out;

  // 1. The period: the first return of the start's trajectory, compared at a sample in a free
  //    flight of the first period (a start on an event would be compared with x⁻ at the
  //    section otherwise).
  int q = req.period;
  const int q_max = std::max(q, std::max(1, scene.run.max_period));
  RunResult run;
  const Trace trace = Run(sys, scene, start, q > 0 ? q : q_max, {}, 0, 0, &run);
  const auto& rows = trace.rows;
  if (rows.size() < static_cast<size_t>(kSamples)) {
    out.status = "no-orbit";
    out.undetermined = run.status == RunStatus::kUndetermined;
    out.message = "the simulation from the start state failed: " + run.message;
    return out;
  }
  const long long ref = MiddleOfLongestFlight(rows, kSamples);
  if (q == 0) {
    q = 1;
    if (ref >= 0) {
      std::vector<double> back;
      for (size_t k = 1; k <= static_cast<size_t>(q_max); ++k) {
        const size_t i = static_cast<size_t>(ref) + k * kSamples;
        back.push_back(i < rows.size() && rows[i].mode == Mode::kFree
                           ? RelativeDistance(rows[i].z, rows[static_cast<size_t>(ref)].z)
                           : std::numeric_limits<double>::infinity());
      }
      const double closest = *std::min_element(back.begin(), back.end());
      for (size_t k = 0; k < back.size(); ++k)
        if (back[k] <= std::max(1e-6, 10.0 * closest)) {
          q = static_cast<int>(k) + 1;
          break;
        }
    }
  }
  out.period = q;

  // 2. The section: the middle of the longest free flight of the first q periods.
  const long long mid = MiddleOfLongestFlight(rows, std::min(rows.size(), static_cast<size_t>(q) * kSamples));
  if (mid < 0) {
    out.status = "no-orbit";
    out.message = fmt::format("the trajectory from the start state has no free flight in {} period(s)", q);
    return out;
  }
  const double t1 = rows[static_cast<size_t>(mid)].t;
  const Eigen::VectorXd z1 = rows[static_cast<size_t>(mid)].z;
  Eigen::VectorXd z = z1;

  // 3. Newton on F(z) − z with the analytic DF (poincare.hpp).
  NewtonOnStroboscopicMap(sys, scene, t1, z, q, req, out);
  z << out.X, out.V;
  if (out.status != "converged") {
    if (out.message.empty()) out.message = "Newton did not converge from the start state";
    return out;
  }
  out.distance_from_start = RelativeDistance(z1, z);

  // 4. Summary, multipliers, and the kind asked for.
  Characterize(sys, scene, out);
  const int p = out.summary.period.value_or(q);
  if (req.period == 0 && p < q && q % p == 0) {
    // The first return came after q periods, but the orbit repeats after p: its own period.
    OrbitRequest again = req;
    again.period = p;
    const double d = *out.distance_from_start;
    OrbitResult shorter = OrbitFromState(sys, scene, {t1, out.X, out.V}, again, far);
    if (shorter.status == "converged") {
      shorter.distance_from_start = d;
      shorter.message.clear();
      out = shorter;
    }
  }
  if (req.kind != OrbitKind::kAuto && out.summary.kind != KindName(req.kind)) {
    out.status = "no-orbit";
    out.message = fmt::format("Newton converged to a {} orbit, not a {} one", out.summary.kind,
                              KindName(req.kind));
    return out;
  }
  if (*out.distance_from_start > far)
    out.message = fmt::format("converged at distance {:.3g} from the start state (more than {:g}): "
                              "the start is not on this orbit",
                              *out.distance_from_start, far);
  return out;
}

OrbitResult SolveOrbit(const System& sys, const Scene& scene, const OrbitRequest& req) {
  const double w = sys.frequency();
  InitialOverride start;
  if (req.guess_phase) {
    // As FindOrbit starts from a guess: on the stop (or at the origin with a clearance), leaving
    // it with the given contact velocity.
    start = {*req.guess_phase / w, sys.stop() * sys.static_shape(),
             sys.contact() * (req.guess_velocity.value_or(0.0) / sys.s_B())};
    if (sys.stop() < 0) start.X = Eigen::VectorXd::Zero(sys.dof());
  } else if (req.start) {
    start = *req.start;
  } else {
    const auto init = sys.Initial(scene);
    start = {init.time, init.X, init.V};
  }
  if (req.transient_periods <= 0) return OrbitFromState(sys, scene, start, req);

  // The transient, seen at one forcing phase of the start (a sample in a free flight of its first
  // period, or the start itself), to measure the distance from the start to what it reaches.
  const Trace first = Run(sys, scene, start, 1);
  long long ref = MiddleOfLongestFlight(first.rows, first.rows.size());
  if (ref < 0) ref = 0;
  Scene sc = scene;
  sc.initial_time = start.time;
  AttractorRecorder recorder(sys, sc);
  const Trace transient = Run(sys, scene, start, req.transient_periods, {&recorder}, kSamples,
                              static_cast<int>(ref));
  const Attractor reached = recorder.Classify();

  std::vector<OrbitKind> kinds = {req.kind};
  if (req.kind == OrbitKind::kAuto) {
    if (HoldsContact(reached.kind)) kinds = {OrbitKind::kSticking};
    else if (reached.kind == "impact-periodic") kinds = {OrbitKind::kImpact};
    // Not settled: Newton from where the transient ended, whichever kind it converges to; then
    // each kind on its own (an impact orbit may be searched from other departures).
    else if (reached.kind == "not-periodic") kinds = {OrbitKind::kAuto, OrbitKind::kSticking, OrbitKind::kImpact};
    else {
      OrbitResult out;
      out.status = "no-orbit";
      out.reached = reached.kind;
      out.message = fmt::format("the transient reached a {} attractor: neither a sticking nor an "
                                "impact orbit",
                                reached.kind);
      return out;
    }
  }
  OrbitResult out;
  for (OrbitKind k : kinds) {
    // The same request (and start) as given: FindOrbit searches departures of several phases and
    // speeds for an impact orbit only when neither a start nor a guess is given.
    OrbitRequest r = req;
    r.kind = k;
    out = FindOrbit(sys, scene, r);
    if (out.status == "converged") break;
  }
  if (out.status != "converged") {
    // FindOrbit's message may name options of `vibro orbit`; the CLI adds its own hints.
    const auto cut = out.message.find("; give");
    if (cut != std::string::npos) out.message.resize(cut);
    out.reached = reached.kind;
    return out;
  }
  // The distance in the start's stroboscopic section: to the nearest of the last q section points
  // of the transient (on the attractor when it settled).
  if (!transient.rows.empty() && !first.rows.empty()) {
    const Eigen::VectorXd& z_start = first.rows[static_cast<size_t>(ref)].z;
    double d = std::numeric_limits<double>::infinity();
    const size_t N = transient.rows.size();
    for (size_t j = 0; j < static_cast<size_t>(out.period) && j < N; ++j)
      d = std::min(d, RelativeDistance(z_start, transient.rows[N - 1 - j].z));
    out.distance_from_start = d;
    // Said only for a start the user chose (the scene's [initial], a --guess or a given state):
    // from the default start, reaching an attractor away from it is the ordinary case, and the
    // distance is printed as plain information.
    const bool chosen_start = req.start || req.guess_phase || scene.initial_displacement.size() > 0 ||
                              scene.initial_time != 0.0;
    if (d > 1e-6 && chosen_start && out.message.empty())
      out.message = fmt::format("converged at distance {:.3g} from the start state, after a transient "
                                "of {} periods: the orbit the start reaches, not one through it",
                                d, req.transient_periods);
  }
  return out;
}

}  // namespace vibro
