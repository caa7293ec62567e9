// The rigid model beside a compliant one (include/vibro/rigid_model.hpp, docs/compliant.md).
#include "vibro/rigid_model.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "vibro/observer.hpp"

namespace vibro {

double EquivalentRestitution(double zeta, Separation rule) {
  if (!(zeta >= 0)) return std::nan("");
  if (zeta < 1) {
    const double s = std::sqrt(1 - zeta * zeta);
    if (rule == Separation::kGap) return std::exp(-zeta * M_PI / s);
    return std::exp(-zeta / s * (M_PI - std::atan2(2 * zeta * s, 1 - 2 * zeta * zeta)));
  }
  if (rule == Separation::kGap) return 0;  // overdamped: the gap never reopens
  // Overdamped, rule "force" (ω₀ = 1, v₀ = 1): x = −(e^{r₁t} − e^{r₂t})/(r₁ − r₂); λ = 0 where
  // e^{(r₁−r₂)t} = (1 + 2ζr₂)/(1 + 2ζr₁). Critical damping: x = −t e^{−t}, λ = 0 at t = 2.
  if (zeta == 1) return std::exp(-2.0);
  const double s = std::sqrt(zeta * zeta - 1), r1 = -zeta + s, r2 = -zeta - s;
  const double ratio = (1 + 2 * zeta * r2) / (1 + 2 * zeta * r1);
  if (!(ratio > 1)) return std::nan("");
  const double t = std::log(ratio) / (r1 - r2);
  return std::abs((r1 * std::exp(r1 * t) - r2 * std::exp(r2 * t)) / (r1 - r2));
}

RigidEquivalent RigidModelOf(const Scene& scene, const System& system) {
  RigidEquivalent out;
  out.scene = scene;
  bool any = false;
  for (const ContactModel& k : system.contacts()) {
    const Compliance& c = k.spec.compliance;
    if (!c.compliant()) {
      out.zeta.push_back(std::nan(""));
      out.restitution.push_back(k.restitution);
      continue;
    }
    any = true;
    const double mass = 1 / k.s_B;  // the contact's effective mass, 1/W_jj
    const double zeta = c.damping / (2 * std::sqrt(c.stiffness * mass));
    const double e = EquivalentRestitution(zeta, c.separation);
    out.zeta.push_back(zeta);
    out.restitution.push_back(std::isfinite(e) ? e : 0.0);
  }
  if (!any) throw std::invalid_argument("the scene has no compliant stop (give a stop a stiffness)");
  if (out.scene.contacts.empty()) {
    out.scene.stop_compliance = {};
    out.scene.restitution = out.restitution.front();
  } else {
    for (size_t j = 0; j < out.scene.contacts.size(); ++j) {
      if (!out.scene.contacts[j].compliance.compliant()) continue;
      out.scene.contacts[j].compliance = {};
      out.scene.contacts[j].restitution = out.restitution[j];
    }
  }
  if (!out.scene.title.empty()) out.scene.title += " (rigid model)";
  return out;
}

namespace {

// The dense samples of a run (time and state) and the compliant contacts' phases.
struct Trace final : Observer {
  std::vector<double> t;
  std::vector<Eigen::VectorXd> X;
  std::vector<Event> releases;
  void OnSample(const Sample& s) override {
    t.push_back(s.t);
    X.push_back(s.X);
  }
  void OnEvent(const Event& e) override {
    if (e.kind == EventKind::kRelease && std::isfinite(e.peak_time)) releases.push_back(e);
  }
};

struct Ran {
  RunResult result;
  LoadsSummary loads;
  Trace trace;
};

void RunOne(const Scene& scene, int blocks, Ran& out) {
  const System sys(scene);
  LoadsRecorder loads(sys, scene.run.periods / 10);
  SimulationOptions opt;
  opt.observers = {&out.trace, &loads};
  out.result = Simulate(sys, scene, opt);
  out.loads = loads.Summary(blocks);
}

}  // namespace

RigidComparison CompareWithRigid(const Scene& scene_in, int blocks) {
  Scene scene = scene_in;
  scene.run.samples_per_period = std::max(scene.run.samples_per_period, 64);
  scene.run.lyapunov = false;
  const System sys(scene);
  RigidComparison c;
  c.rigid = RigidModelOf(scene, sys);
  Ran compliant, rigid;
  RunOne(scene, blocks, compliant);
  RunOne(c.rigid.scene, blocks, rigid);
  c.compliant_result = compliant.result;
  c.rigid_result = rigid.result;
  c.compliant_loads = compliant.loads;
  c.rigid_loads = rigid.loads;
  const size_t n = std::min(compliant.trace.t.size(), rigid.trace.t.size());
  const auto physical = [&](const Eigen::VectorXd& X) -> Eigen::VectorXd {
    return sys.physical() ? Eigen::VectorXd(sys.mode_shapes() * X) : X;
  };
  for (size_t i = 0; i < n; ++i) {
    const double d = (physical(compliant.trace.X[i]) - physical(rigid.trace.X[i])).cwiseAbs().maxCoeff();
    if (d > c.distance || i == 0) {
      c.distance = d;
      c.distance_time = compliant.trace.t[i];
    }
    c.end_distance = d;
  }
  c.samples = static_cast<long long>(n);
  const size_t m = static_cast<size_t>(sys.contact_count());
  c.peak_force_max.assign(m, std::nan(""));
  c.peak_force_mean.assign(m, std::nan(""));
  c.duration_mean.assign(m, std::nan(""));
  c.phases.assign(m, 0);
  std::vector<double> peak_sum(m, 0), duration_sum(m, 0);
  for (const Event& e : compliant.trace.releases) {
    const auto j = static_cast<size_t>(e.contact);
    if (j >= m) continue;
    ++c.phases[j];
    peak_sum[j] += e.reaction_max;
    duration_sum[j] += e.stick_duration;
    if (!(c.peak_force_max[j] >= e.reaction_max)) c.peak_force_max[j] = e.reaction_max;
  }
  for (size_t j = 0; j < m; ++j)
    if (c.phases[j] > 0) {
      c.peak_force_mean[j] = peak_sum[j] / static_cast<double>(c.phases[j]);
      c.duration_mean[j] = duration_sum[j] / static_cast<double>(c.phases[j]);
    }
  return c;
}

std::string RigidComparisonJson(const RigidComparison& c) {
  const auto num = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
  nlohmann::json j;
  j["distance"] = {{"max", num(c.distance)},
                   {"time_of_max", num(c.distance_time)},
                   {"at_end", num(c.end_distance)},
                   {"samples", c.samples}};
  j["status"] = {{"compliant", ToString(c.compliant_result.status)}, {"rigid", ToString(c.rigid_result.status)}};
  auto contacts = nlohmann::json::array();
  for (size_t k = 0; k < c.rigid.zeta.size(); ++k) {
    nlohmann::json o;
    o["contact"] = k;
    o["zeta"] = num(c.rigid.zeta[k]);
    o["restitution"] = num(c.rigid.restitution[k]);
    o["phases"] = k < c.phases.size() ? c.phases[k] : 0;
    o["peak_force_max"] = k < c.peak_force_max.size() ? num(c.peak_force_max[k]) : nullptr;
    o["peak_force_mean"] = k < c.peak_force_mean.size() ? num(c.peak_force_mean[k]) : nullptr;
    o["duration_mean"] = k < c.duration_mean.size() ? num(c.duration_mean[k]) : nullptr;
    const auto loads = [&](const LoadsSummary& s) -> nlohmann::json {
      for (const ContactLoads& l : s.contacts)
        if (l.contact == static_cast<int>(k))
          return {{"impulse_per_period", num(l.impulse_per_period + l.reaction_integral_per_period)},
                  {"mean_force", num(l.mean_force)},
                  {"dissipated_power", num(l.dissipated_power)},
                  {"contact_fraction", num(l.contact_fraction)}};
      return nullptr;
    };
    o["compliant"] = loads(c.compliant_loads);
    o["rigid"] = loads(c.rigid_loads);
    contacts.push_back(o);
  }
  j["contacts"] = contacts;
  return j.dump();
}

namespace {

// The dense samples of q periods of an orbit from its section.
std::vector<std::pair<double, Eigen::VectorXd>> OrbitSamples(const System& sys, const Scene& scene, double t0,
                                                             const Eigen::VectorXd& X, const Eigen::VectorXd& V,
                                                             int q, bool& ok) {
  Scene sc = scene;
  sc.run.periods = q;
  sc.run.samples_per_period = 1024;
  sc.run.lyapunov = false;
  Trace trace;
  const InitialOverride start{t0, X, V};
  SimulationOptions opt;
  opt.initial = &start;
  opt.observers = {&trace};
  ok = Simulate(sys, sc, opt).status == RunStatus::kOk;
  std::vector<std::pair<double, Eigen::VectorXd>> out;
  for (size_t i = 0; i < trace.t.size(); ++i) out.emplace_back(trace.t[i], trace.X[i]);
  return out;
}

}  // namespace

namespace {

using Samples = std::vector<std::pair<double, Eigen::VectorXd>>;

// The rigid orbit of CompareOrbitWithRigid without the loads: Newton from `start` (or the compliant
// section state), the multipliers, and the distances. `compliant` holds the compliant orbit's dense
// samples once computed (they do not depend on the start: AddRigidModelAlongBranch computes them
// once per point for both starts).
RigidOrbitComparison RigidOrbitBeside(const Scene& scene, const System& sys, const RigidEquivalent& rigid,
                                      const System& rigid_sys, const OrbitResult& orbit,
                                      const OrbitRequest& request, const Eigen::VectorXd* start,
                                      std::optional<std::pair<bool, Samples>>& compliant) {
  RigidOrbitComparison c;
  c.rigid = rigid;
  if (orbit.status != "converged") {
    c.orbit.status = "not-converged";
    c.orbit.message = "no compliant orbit to start from";
    return c;
  }
  const int q = orbit.period;
  Eigen::VectorXd z(2 * sys.dof());
  if (start && start->size() == z.size())
    z = *start;
  else
    z << orbit.X, orbit.V;
  c.orbit.period = q;
  NewtonOnStroboscopicMap(rigid_sys, c.rigid.scene, orbit.section_time, z, q, request, c.orbit);
  if (c.orbit.status != "converged") {
    if (c.orbit.message.empty()) c.orbit.message = "Newton did not converge";
    c.orbit.message = fmt::format("the rigid model's map from the compliant orbit's section: {}", c.orbit.message);
    return c;
  }
  Characterize(rigid_sys, c.rigid.scene, c.orbit);
  const auto physical = [&](const Eigen::VectorXd& X) -> Eigen::VectorXd {
    return sys.physical() ? Eigen::VectorXd(sys.mode_shapes() * X) : X;
  };
  c.section_distance = (physical(orbit.X) - physical(c.orbit.X)).cwiseAbs().maxCoeff();
  if (!compliant) {
    bool ok = false;
    Samples s = OrbitSamples(sys, scene, orbit.section_time, orbit.X, orbit.V, q, ok);
    compliant.emplace(ok, std::move(s));
  }
  bool ok_r = false;
  const Samples& a = compliant->second;
  const auto b = OrbitSamples(rigid_sys, c.rigid.scene, orbit.section_time, c.orbit.X, c.orbit.V, q, ok_r);
  if (!compliant->first || !ok_r || a.size() != b.size()) return c;
  c.distance = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    if (std::abs(a[i].first - b[i].first) > 1e-9 * (1 + std::abs(a[i].first))) return c;  // not the same instants
    const double d = (physical(a[i].second) - physical(b[i].second)).cwiseAbs().maxCoeff();
    if (i == 0 || d > c.distance) {
      c.distance = d;
      c.distance_time = a[i].first;
    }
  }
  return c;
}

// The images of the rigid orbit of `c` (an impact orbit of its own period p forcing periods): the
// same closed curve met at the section 1, …, p − 1 periods later, each a fixed point of the
// q-period map too, as comparisons with the compliant orbit (`image(comparison)`). They have
// their impacts at the same forcing phases mod 2π, so Newton from the compliant section state may
// reach any of them; the one beside the compliant orbit is the one to compare with.
template <class Fn>
void ForEachImage(const RigidOrbitComparison& c, const Scene& scene, const System& sys, const System& rigid_sys,
                  const OrbitResult& orbit, const OrbitRequest& request,
                  std::optional<std::pair<bool, Samples>>& compliant, const Fn& image) {
  if (c.orbit.status != "converged" || c.orbit.summary.kind != "impact-periodic") return;
  const int p = c.orbit.summary.period.value_or(c.orbit.period);
  Eigen::VectorXd X = c.orbit.X, V = c.orbit.V;
  for (int k = 1; k < p; ++k) {
    const MapValue m = StroboscopicMap(rigid_sys, c.rigid.scene, orbit.section_time, X, V, 1);
    if (m.status != RunStatus::kOk) return;
    X = m.X;
    V = m.V;
    Eigen::VectorXd z(2 * sys.dof());
    z << X, V;
    image(RigidOrbitBeside(scene, sys, c.rigid, rigid_sys, orbit, request, &z, compliant));
  }
}

}  // namespace

RigidOrbitComparison CompareOrbitWithRigid(const Scene& scene, const System& sys, const OrbitResult& orbit,
                                           const OrbitRequest& request, const Eigen::VectorXd* start) {
  const RigidEquivalent rigid = RigidModelOf(scene, sys);
  const System rigid_sys(rigid.scene);
  std::optional<std::pair<bool, Samples>> compliant;
  RigidOrbitComparison c = RigidOrbitBeside(scene, sys, rigid, rigid_sys, orbit, request, start, compliant);
  if (c.orbit.status != "converged") return c;
  c.compliant_loads = OrbitLoads(sys, scene, orbit);
  c.rigid_loads = OrbitLoads(rigid_sys, c.rigid.scene, c.orbit);
  return c;
}

namespace {

// Whether the rigid model's orbit of `c` is beside the branch point's orbit (rigid_model.hpp,
// AddRigidModelAlongBranch): an impact orbit with one impact per contact phase of the point's orbit
// on each contact, each impact inside a contact phase of its contact widened by the phase's
// duration on either side. Phases are compared over the orbit's whole period (mod 2π·q, q its
// forcing periods), not mod 2π: the orbit's images under the map of one forcing period (the same
// closed curve met at the section one, two, … periods later, each a fixed point of the q-period map
// too) have their impacts at the same forcing phases mod 2π, each a period away from its contact
// phase. The rigid orbit's impact phases are the attractor's, φ = (ωt₀ mod 2π) + ω(t − t₀) mod 2π·q
// (AttractorRecorder::Phase, the run started at the section time t₀); the contact phases' absolute
// times are mapped the same way.
bool Beside(const RigidOrbitComparison& c, const BranchPoint& pt, const System& sys) {
  if (c.orbit.status != "converged" || c.orbit.summary.kind != "impact-periodic" || !std::isfinite(c.distance))
    return false;
  std::vector<int> phases(static_cast<size_t>(sys.contact_count()), 0), impacts(phases.size(), 0);
  for (const auto& p : pt.contact_phases)
    if (p.contact >= 0 && static_cast<size_t>(p.contact) < phases.size()) ++phases[static_cast<size_t>(p.contact)];
  for (const int j : c.orbit.summary.impact_contacts)
    if (j >= 0 && static_cast<size_t>(j) < impacts.size()) ++impacts[static_cast<size_t>(j)];
  if (phases != impacts) return false;
  const double w = sys.frequency();
  const auto& a = c.orbit.summary;
  const double full = 2 * M_PI * static_cast<double>(a.period.value_or(c.orbit.period));
  const double t0 = c.orbit.section_time, phase0 = std::fmod(w * t0, 2 * M_PI);
  for (size_t i = 0; i < a.impact_phases.size() && i < a.impact_contacts.size(); ++i) {
    bool inside = false;
    for (const auto& p : pt.contact_phases) {
      if (p.contact != a.impact_contacts[i]) continue;
      const double from = phase0 + w * (p.entry - p.duration - t0), span = w * 3 * p.duration;
      const double rel = std::remainder(a.impact_phases[i] - from - span / 2, full) + span / 2;
      inside = inside || (rel >= 0 && rel <= span);
    }
    if (!inside) return false;
  }
  return true;
}

}  // namespace

void AddRigidModelAlongBranch(Branch& branch, const std::function<Scene(double)>& scene_at,
                              const OrbitRequest& request, const std::atomic<bool>* stop_requested) {
  // The rigid orbit beside the last point that had one: its section state, a Newton start for the
  // next point (the section is at one forcing phase along the branch, so the states correspond).
  std::optional<Eigen::VectorXd> followed;
  for (BranchPoint& pt : branch.points) {
    if (stop_requested && stop_requested->load()) return;
    const Scene scene = scene_at(pt.value);
    if (!HasCompliantContact(scene)) return;
    const System sys(scene);
    OrbitResult orbit;
    orbit.status = "converged";
    orbit.period = branch.period;
    orbit.section_time = pt.section_time;
    orbit.X = pt.X;
    orbit.V = pt.V;
    // The rigid scene and the compliant orbit's samples once for both starts; no loads (only the
    // distance is kept along a branch).
    const RigidEquivalent rigid = RigidModelOf(scene, sys);
    const System rigid_sys(rigid.scene);
    std::optional<std::pair<bool, Samples>> compliant;
    std::optional<RigidOrbitComparison> best;
    const auto consider = [&](const Eigen::VectorXd* start) {
      RigidOrbitComparison c = RigidOrbitBeside(scene, sys, rigid, rigid_sys, orbit, request, start, compliant);
      if (c.orbit.status != "converged") return;
      // A rigid orbit not beside may be beside once met at the section a few forcing periods later:
      // its images are fixed points of the q-period map too (Beside).
      const auto take = [&](RigidOrbitComparison r) {
        if (Beside(r, pt, sys) && (!best || r.distance < best->distance)) best = std::move(r);
      };
      if (Beside(c, pt, sys)) {
        take(std::move(c));
        return;
      }
      ForEachImage(c, scene, sys, rigid_sys, orbit, request, compliant, take);
    };
    consider(nullptr);
    if (followed) consider(&*followed);
    pt.rigid_distance = best ? best->distance : std::numeric_limits<double>::quiet_NaN();
    if (best) {
      followed = Eigen::VectorXd(2 * sys.dof());
      *followed << best->orbit.X, best->orbit.V;
    }
  }
}

std::string RigidOrbitJson(const RigidOrbitComparison& c) {
  const auto num = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
  nlohmann::json j;
  j["status"] = c.orbit.status;
  if (!c.orbit.message.empty()) j["message"] = c.orbit.message;
  j["restitution"] = c.rigid.restitution;
  auto zeta = nlohmann::json::array();
  for (double z : c.rigid.zeta) zeta.push_back(num(z));
  j["zeta"] = zeta;
  auto mu = nlohmann::json::array();
  for (const auto& m : c.orbit.multipliers) mu.push_back({m.real(), m.imag()});
  j["floquet_multipliers"] = mu;
  j["stable"] = c.orbit.status == "converged" && c.orbit.no_jacobian.empty() ? nlohmann::json(c.orbit.stable)
                                                                              : nlohmann::json(nullptr);
  j["attractor_kind"] = c.orbit.summary.kind;
  j["distance"] = {{"max", num(c.distance)}, {"time_of_max", num(c.distance_time)}, {"at_section", num(c.section_distance)}};
  auto loads = nlohmann::json::array();
  for (size_t k = 0; k < c.compliant_loads.contacts.size() && k < c.rigid_loads.contacts.size(); ++k) {
    const ContactLoads& a = c.compliant_loads.contacts[k];
    const ContactLoads& b = c.rigid_loads.contacts[k];
    // The impulse per period: impacts' and contact phases' (∫λ dt) together.
    loads.push_back({{"contact", a.contact},
                     {"impulse_per_period", {num(a.impulse_per_period + a.reaction_integral_per_period),
                                             num(b.impulse_per_period + b.reaction_integral_per_period)}},
                     {"mean_force", {num(a.mean_force), num(b.mean_force)}},
                     {"dissipated_power", {num(a.dissipated_power), num(b.dissipated_power)}}});
  }
  j["loads"] = loads;  // per contact: [compliant, rigid]
  return j.dump();
}

}  // namespace vibro
