// Checking orbits computed elsewhere (see include/vibro/branch_check.hpp).
#include "vibro/branch_check.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include <fmt/format.h>

#include "vibro/contact_sequence.hpp"
#include "vibro/orbit_from_state.hpp"
#include "vibro/simulator.hpp"
#include "vibro/system.hpp"

namespace vibro {
namespace {

constexpr double kHugeEntry = 1e100;  // the bound of [initial] (docs/scenes.md)

double RelativeDistance(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return (a - b).cwiseAbs().maxCoeff() / (1.0 + b.cwiseAbs().maxCoeff());
}

// The orbit's samples at the claim's time t (modulo its period q·T): the orbit is simulated for
// q periods from its section state with 1024 samples a period, a grid the claim's time lies on
// (orbit_from_state.hpp puts the section at t + j·T/1024). Returns the distance of the claimed
// state (as given, and as the start ClaimedStart makes of it) to the orbit's state at t, the
// state just after an impact included when the orbit is on the stop moving into it there; empty
// when t is not on the grid or the run fails.
std::optional<double> DistanceAtClaim(const System& sys, const Scene& scene, const OrbitResult& o,
                                      const std::vector<Eigen::VectorXd>& claimed, double t) {
  constexpr int kSamples = 1024;
  const double T = sys.period(), qT = o.period * T;
  double tau = std::fmod(t - o.section_time, qT);
  if (tau < 0) tau += qT;
  const double k = tau / T * kSamples;
  long long index = std::llround(k);
  if (!(std::abs(k - static_cast<double>(index)) < 1e-3)) return std::nullopt;
  index %= static_cast<long long>(o.period) * kSamples;
  struct Pick final : Observer {
    double want = 0, off = std::numeric_limits<double>::infinity();
    Eigen::VectorXd X, V;
    void OnSample(const Sample& smp) override {
      if (std::abs(smp.t - want) < off) {
        off = std::abs(smp.t - want);
        X = smp.X;
        V = smp.V;
      }
    }
  } pick;
  pick.want = o.section_time + static_cast<double>(index) * T / kSamples;
  Scene sc = scene;
  sc.initial_time = o.section_time;
  sc.run.periods = o.period;
  sc.run.samples_per_period = kSamples;
  const InitialOverride here{o.section_time, o.X, o.V};
  SimulationOptions opt;
  opt.initial = &here;
  opt.observers = {&pick};
  const RunResult r = Simulate(sys, sc, opt);
  if (r.status != RunStatus::kOk || pick.X.size() == 0 || !(pick.off <= 1e-6 * T)) return std::nullopt;
  std::vector<Eigen::VectorXd> orbit;
  Eigen::VectorXd z(2 * pick.X.size());
  z << pick.X, pick.V;
  orbit.push_back(z);
  if (sys.contact_count() > 1) {
    // Several contacts: the state after the impact of each contact the orbit sits on moving in.
    for (const ContactModel& c : sys.contacts()) {
      const double gap = c.shape.dot(pick.X) - c.stop;
      if (!(std::abs(gap) <= 1e-9 * std::max(1.0, std::abs(c.stop)) && c.shape.dot(pick.V) < 0)) continue;
      const Eigen::VectorXd after = pick.V - (1.0 + c.restitution) * c.shape.dot(pick.V) / c.s_B * c.contact;
      z << pick.X, after;
      orbit.push_back(z);
    }
  } else {
    const double gap = sys.ContactDisplacement(pick.X) - sys.stop();
    if (std::abs(gap) <= 1e-9 * std::max(1.0, std::abs(sys.stop())) && sys.ContactVelocity(pick.V) < 0) {
      Eigen::VectorXd after = pick.V;
      sys.ApplyImpact(after, sys.restitution());
      z << pick.X, after;
      orbit.push_back(z);
    }
  }
  double best = std::numeric_limits<double>::infinity();
  for (const auto& a : claimed)
    for (const auto& b : orbit) best = std::min(best, RelativeDistance(a, b));
  return best;
}

// ClaimedStart's admissibility with several contacts (docs/contacts.md): each gap
// g_j = c_jᵀX − e_j, with another tool's rounding forgiven per contact, and each contact's own
// impact law (V⁺ = V − (1 + r_j)(c_jᵀV/W_jj) T_j) for a state on it moving in.
void ClaimedStartOnContacts(const System& sys, InitialOverride& start, std::string& problem) {
  std::vector<int> closing;
  for (int j = 0; j < sys.contact_count(); ++j) {
    const ContactModel& k = sys.contacts()[static_cast<size_t>(j)];
    const double gap = k.shape.dot(start.X) - k.stop, snap = 1e-9 * std::max(1.0, std::abs(k.stop));
    if (gap < -snap) {
      problem = fmt::format("the state is outside the gap of contact {} (g_{} = {:.3g} < 0): not an admissible "
                            "state of the scene",
                            j, j, gap);
      return;
    }
    if (gap > snap) continue;
    start.X -= k.contact * (gap / k.s_B);  // onto the contact: g_j = 0
    if (k.shape.dot(start.V) < 0) closing.push_back(j);
  }
  const Eigen::MatrixXd& W = sys.delassus();
  for (size_t a = 0; a < closing.size(); ++a)
    for (size_t b = a + 1; b < closing.size(); ++b)
      if (std::abs(W(closing[a], closing[b])) > 1e-12 * std::sqrt(W(closing[a], closing[a]) * W(closing[b], closing[b]))) {
        problem = fmt::format("the state is on contacts {} and {} moving into both, and they are coupled "
                              "(W_{}{} = {:.3g} ≠ 0): their simultaneous impact is no one contact's law; give the "
                              "state just after it",
                              closing[a], closing[b], closing[a], closing[b], W(closing[a], closing[b]));
        return;
      }
  for (int j : closing) {  // independent contacts: each impact law on its own
    const ContactModel& k = sys.contacts()[static_cast<size_t>(j)];
    start.V -= (1.0 + k.restitution) * (k.shape.dot(start.V) / k.s_B) * k.contact;
  }
}

}  // namespace

InitialOverride ClaimedStart(const System& sys, const Scene& scene, const ClaimedPoint& p,
                             std::string& problem) {
  problem.clear();
  // A state at all: finite, within the bounds of the scene's [initial] table.
  const double T = sys.period();
  for (const auto* v : {&p.displacement, &p.velocity})
    for (Eigen::Index i = 0; i < v->size(); ++i)
      if (!(std::abs((*v)[i]) <= kHugeEntry)) {
        problem = fmt::format("{}_{} = {}: not a state of the scene (|value| ≤ {:g}, as for initial.{})",
                              v == &p.displacement ? "displacement" : "velocity", i + 1, (*v)[i], kHugeEntry,
                              v == &p.displacement ? "displacement" : "velocity");
        return {p.time, Eigen::VectorXd::Zero(p.displacement.size()), Eigen::VectorXd::Zero(p.velocity.size())};
      }
  if (!(std::abs(p.time) / T <= 1e12)) {
    problem = fmt::format("time = {}: not a time of the scene (|time|/T ≤ 1e12, as for initial.time)", p.time);
    return {0.0, Eigen::VectorXd::Zero(p.displacement.size()), Eigen::VectorXd::Zero(p.velocity.size())};
  }
  Scene at = scene;
  at.initial_time = p.time;
  at.initial_displacement = p.displacement;
  at.initial_velocity = p.velocity;
  const auto init = sys.Initial(at);
  InitialOverride start{init.time, init.X, init.V};

  if (sys.contact_count() > 1) {
    ClaimedStartOnContacts(sys, start, problem);
    return start;
  }
  // Admissibility, with the rounding of another tool's output forgiven.
  const double x0 = sys.stop(), gap = sys.ContactDisplacement(start.X) - x0;
  const double snap = 1e-9 * std::max(1.0, std::abs(x0));
  if (gap < -snap) {
    problem = fmt::format("the state is below the stop (x_B − x0 = {:.3g} < 0): not an admissible state "
                          "of the scene", gap);
  } else if (gap <= snap) {
    start.X += sys.contact() * (-gap / sys.s_B());  // onto the stop: x_B = x0
    if (sys.ContactVelocity(start.V) < 0) sys.ApplyImpact(start.V, sys.restitution());
  }
  return start;
}

PointCheck CheckPoint(const Scene& scene, const ClaimedPoint& p, OrbitKind kind, int period,
                      const CheckTolerances& tol) {
  PointCheck out;
  out.value = p.value;
  const System sys(scene);
  std::string problem;
  const InitialOverride start = ClaimedStart(sys, scene, p, problem);

  OrbitRequest req;
  req.kind = kind;
  req.period = p.period.value_or(period);
  req.transient_periods = 0;
  out.orbit = OrbitFromState(sys, scene, start, req, tol.distance);
  const OrbitResult& o = out.orbit;
  out.distance = o.distance_from_start;
  if (o.status != "converged") {
    out.verdict = o.undetermined ? "undetermined" : "no-orbit-near";
    out.detail = o.message;
    return out;
  }
  // The distance is measured from the state as claimed, at its own time: the start carried
  // forward (orbit_from_state.hpp) may have been brought onto the orbit by the motion itself (a
  // plastic impact, a sticking phase), which says nothing of the claim.
  {
    Scene at = scene;
    at.initial_time = p.time;
    at.initial_displacement = p.displacement;
    at.initial_velocity = p.velocity;
    const auto raw = sys.Initial(at);
    Eigen::VectorXd a(2 * raw.X.size()), b(2 * start.X.size());
    a << raw.X, raw.V;
    b << start.X, start.V;
    const auto d = DistanceAtClaim(sys, scene, o, {a, b}, p.time);
    if (d) out.distance = std::max(*d, o.distance_from_start.value_or(0.0));
  }
  if (*out.distance > tol.distance) {
    out.verdict = "no-orbit-near";
    out.detail = fmt::format("the nearest orbit Newton finds lies {:.3g} from the claimed state at its time "
                             "(tolerance {:g})",
                             *out.distance, tol.distance);
    return out;
  }
  // A stable orbit is also confirmed by simulating from the orbit's section state (the claimed
  // state is within tolerance of it): the motion must stay on the orbit.
  if (o.stable) {
    Scene sc = scene;
    sc.initial_time = o.section_time;
    sc.run.periods = static_cast<long long>(tol.simulate_periods) * o.period;
    sc.run.samples_per_period = 0;
    const InitialOverride here{o.section_time, o.X, o.V};
    SimulationOptions opt;
    opt.initial = &here;
    const RunResult r = Simulate(sys, sc, opt);
    Eigen::VectorXd a(2 * o.X.size()), b(2 * o.X.size());
    a << r.X, r.V;
    b << o.X, o.V;
    out.simulated_distance = (a - b).cwiseAbs().maxCoeff() / (1.0 + b.cwiseAbs().maxCoeff());
    if (r.status == RunStatus::kUndetermined || r.status == RunStatus::kNumericalFailure) {
      out.simulated_distance.reset();
      out.verdict = "undetermined";
      out.detail = fmt::format("the check simulation of {} periods from the orbit ended {}: {}", sc.run.periods,
                               ToString(r.status), r.message);
      return out;
    }
    if (r.status != RunStatus::kOk || *out.simulated_distance > tol.distance) {
      out.verdict = "stability-differs";
      out.detail = fmt::format("Floquet multipliers say stable, but a simulation of {} periods from the "
                               "orbit ends {:.3g} away from it",
                               sc.run.periods, *out.simulated_distance);
      return out;
    }
  }
  const int vibro_period = o.summary.period.value_or(o.period);
  std::string unused;
  const auto claimed_sequence = ParseContactSequence(p.sequence, sys.contact_count(), unused);
  const auto vibro_sequence = ParseContactSequence(o.sequence, -1, unused);
  if (p.period && *p.period != vibro_period) {
    out.verdict = "period-differs";
    out.detail = fmt::format("claimed period {}, vibro's orbit has period {}", *p.period, vibro_period);
  } else if (!p.sequence.empty() &&
             !(claimed_sequence && vibro_sequence && SameContactSequence(*claimed_sequence, *vibro_sequence))) {
    out.verdict = "sequence-differs";
    out.detail = fmt::format("claimed sequence {}, vibro's orbit has {}", p.sequence,
                             o.sequence.empty() ? "none (one contact)" : o.sequence);
  } else if (p.stable && *p.stable != o.stable) {
    double lead = 0;
    for (const auto& m : o.multipliers) lead = std::max(lead, std::abs(m));
    out.verdict = "stability-differs";
    out.detail = fmt::format("claimed {}, vibro finds {} (largest |multiplier| {:.6g})",
                             *p.stable ? "stable" : "unstable", o.stable ? "stable" : "unstable", lead);
  } else if (p.sticking_fraction &&
             std::abs(*p.sticking_fraction - o.summary.sticking_fraction.value_or(0.0)) > tol.sticking_fraction) {
    out.verdict = "sticking-fraction-differs";
    out.detail = fmt::format("claimed {:.10g}, vibro finds {:.10g}", *p.sticking_fraction,
                             o.summary.sticking_fraction.value_or(0.0));
  } else {
    out.verdict = "confirmed";
  }
  return out;
}

}  // namespace vibro
