// `vibro prove`: the model as exact decimals, the orbit to prove (from the Poincaré solver), the
// proof by kind, and the certificate (prove.hpp, docs/prove.md).
#include "vibro/prove.hpp"

#include <cmath>
#include <functional>
#include <optional>
#include <stdexcept>

#include <fmt/format.h>

#include "proof/bifurcation_proof.hpp"
#include "proof/grazing_proof.hpp"
#include "proof/held_set_proof.hpp"
#include "proof/orbit_pitchfork.hpp"
#include "proof/modal_enclosure.hpp"
#include "proof/proof_common.hpp"
#include "proof/sticking_search.hpp"
#include "proof/prove_api.hpp"
#include "vibro/observer.hpp"
#include "vibro/orbit_from_state.hpp"

namespace vibro {
namespace {

using proof::Json;

// The shortest decimal that reads back as the double: the parameter the theorem is about (for a
// scene written in decimals, the decimal the user wrote).
std::string Decimal(double x) { return fmt::format("{}", x); }

// The model of the proof: the scene's modal data as decimals, or for a physical scene the
// enclosures of its modal data (`enclosed`, proof/modal_enclosure.hpp).
proof::IntervalModel ModelOf(const System& sys, const proof::ModalEnclosure* enclosed = nullptr) {
  std::vector<std::string> omega, forcing, contact, shape, damping;
  for (int i = 0; i < sys.dof(); ++i) {
    omega.push_back(Decimal(sys.omega()(i)));
    forcing.push_back(Decimal(sys.forcing()(i)));
    contact.push_back(Decimal(sys.contact()(i)));
    shape.push_back(Decimal(sys.contact_shape()(i)));
    if (sys.damped()) damping.push_back(Decimal(sys.damping()(i)));
  }
  if (enclosed != nullptr) {
    omega = enclosed->omega;
    forcing = enclosed->forcing;
    contact = enclosed->contact;
    shape = enclosed->shape;
  }
  auto model = proof::IntervalModel::FromDecimals(omega, forcing, contact, shape, Decimal(sys.stop()),
                                                  Decimal(sys.restitution()), Decimal(sys.amplitude()),
                                                  Decimal(sys.frequency()), damping);
  // Contacts 1, 2, ... of a scene with several (docs/contacts.md): gap c_jᵀX − e_j, projection T_j.
  for (int j = 1; j < sys.contact_count(); ++j) {
    const auto& c = sys.contacts()[static_cast<std::size_t>(j)];
    std::vector<std::string> cs, ct;
    for (int i = 0; i < sys.dof(); ++i) {
      cs.push_back(Decimal(c.shape(i)));
      ct.push_back(Decimal(c.contact(i)));
    }
    if (enclosed != nullptr) {
      cs = enclosed->more_shape[static_cast<std::size_t>(j - 1)];
      ct = enclosed->more_contact[static_cast<std::size_t>(j - 1)];
    }
    model.AddContact(cs, ct, Decimal(c.stop), Decimal(c.restitution));
  }
  return model;
}

// A physical scene's modal data enclosed (empty failure and structure for the modal form).
proof::ModalEnclosure EnclosureOf(const System& sys, const Scene& scene) {
  if (!scene.physical) return {};
  return proof::EncloseModalData(sys, scene);
}

Json ModelJson(const proof::IntervalModel& m) {
  Json j = {{"frequencies", m.omega_text}, {"forcing", m.forcing_text},   {"contact", m.contact_text},
            {"shape", m.shape_text},       {"stop", m.stop_text},         {"restitution", m.restitution_text},
            {"amplitude", m.amplitude_text}, {"frequency", m.frequency_text}};
  if (m.damped()) j["damping"] = m.damping_text;  // ζ_i, docs/model.md §7
  if (m.contact_count() > 1) {
    Json more = Json::array();
    for (std::size_t k = 1; k < m.contacts.size(); ++k) {
      const auto& c = m.contacts[k];
      more.push_back({{"shape", c.shape_text}, {"contact", c.contact_text}, {"stop", c.stop_text},
                      {"restitution", c.restitution_text}});
    }
    j["more_contacts"] = more;  // contacts 1, 2, ... (contact 0 is the fields above)
  }
  return j;
}

// The impacts of one period of an orbit (time, state just after), as the simulator meets them.
class ImpactRecorder final : public Observer {
 public:
  void OnEvent(const Event& e) override {
    if (e.kind == EventKind::kImpact) {
      times.push_back(e.t);
      if (e.simultaneous) simultaneous = true;
    }
    else if (e.kind != EventKind::kGrazing) other = ToString(e.kind);
    else grazing = true;
  }
  void OnReset(const Reset& r) override {
    if (r.kind == ResetKind::kImpact) {
      X.push_back(r.X_after);
      V.push_back(r.V_after);
      contacts.push_back(r.contact);
      if (r.simultaneous) simultaneous = true;
    } else if (r.kind == ResetKind::kPlasticLeave) {
      ++plastic_departures;
    }
  }
  std::vector<double> times;
  std::vector<Eigen::VectorXd> X, V;
  std::vector<int> contacts;
  std::string other;
  bool grazing = false, simultaneous = false;
  int plastic_departures = 0;
};

struct Found {
  std::string failure;  // "" when an impacting orbit was found
  int requested = 0;    // --period Q of an orbit whose least period p < Q divides Q: Q (the proof is at p)
  bool sticking = false;
  bool stopped = false;  // the budget ended the search (time limit or stop request): no result
  proof::ImpactGuess guess;
};

// The least period of the impacts found over q periods: the smallest p dividing q such that p
// periods later the impacts repeat (times within 1e-7 T, states within 1e-7 relative).
int LeastPeriod(const proof::ImpactGuess& g, double T) {
  const int q = g.period;
  const auto m = static_cast<long long>(g.times.size());
  for (int p = 1; p < q; ++p) {
    if (q % p != 0 || (m * p) % q != 0) continue;
    const long long h = m * p / q;
    bool repeats = true;
    for (long long j = 0; j < m && repeats; ++j) {
      const auto k = static_cast<std::size_t>((j + h) % m), i = static_cast<std::size_t>(j);
      const double dt = g.times[k] + (j + h >= m ? q * T : 0.0) - g.times[i] - p * T;
      const auto close = [](const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
        return (a - b).cwiseAbs().maxCoeff() <= 1e-7 * (1 + a.cwiseAbs().maxCoeff());
      };
      repeats = std::abs(dt) <= 1e-7 * T && close(g.X[k], g.X[i]) && close(g.V[k], g.V[i]) &&
                (g.contacts.empty() || g.contacts[k] == g.contacts[i]);
    }
    if (repeats) return p;
  }
  return q;
}

Found FindImpactOrbit(const System& sys, const Scene& scene, const ProofRequest& request, const proof::Budget& budget) {
  Found f;
  OrbitRequest req;
  req.kind = request.kind;
  req.period = request.period;
  req.transient_periods = request.start ? 0 : request.transient_periods;
  req.start = request.start;
  OrbitResult orbit;
  ImpactRecorder rec;
  RunResult run;
  // The search runs under the budget: the time limit and the stop requests end its transient.
  budget.Watch([&] {
    orbit = SolveOrbit(sys, scene, req);
    if (orbit.status != "converged" || orbit.summary.kind == "sticking-periodic" || budget.passed()) return;
    Scene one = scene;
    one.run.periods = orbit.period;
    one.run.samples_per_period = 0;
    one.run.lyapunov = false;
    const InitialOverride start{orbit.section_time, orbit.X, orbit.V};
    SimulationOptions opt;
    opt.observers = {&rec};
    opt.initial = &start;
    run = Simulate(sys, one, opt);
  });
  if (budget.passed()) {
    f.stopped = true;
    return f;
  }
  if (orbit.status != "converged") {
    f.failure = "the Poincaré solver found no orbit to prove (" + orbit.status +
                (orbit.message.empty() ? "" : ": " + orbit.message) + ")";
    return f;
  }
  if (orbit.summary.kind == "sticking-periodic") {
    f.sticking = true;
    return f;
  }
  if (run.status != RunStatus::kOk) f.failure = "the orbit found could not be followed over one period: " + run.message;
  else if (!rec.other.empty()) f.failure = "the orbit found has a " + rec.other + " event: it is not an impacting orbit";
  else if (rec.grazing) f.failure = "the orbit found grazes the stop: a grazing orbit cannot be proven";
  else if (rec.simultaneous)
    f.failure = "the orbit found has a simultaneous impact of two contacts: an orbit through a simultaneous impact "
                "is not proven (the impact map has no derivative there, docs/prove.md)";
  else if (rec.plastic_departures > 0)
    f.failure = fmt::format("r = 0: the orbit found has {} plastic impact(s) per {} period(s), each leaving the stop "
                            "at once with zero contact velocity; impacting orbits with plastic impacts are not proven "
                            "by this version (docs/prove.md)", rec.plastic_departures, orbit.period);
  else if (rec.times.empty()) f.failure = "the orbit found has no impact: it never touches the stop";
  else if (rec.times.size() != rec.X.size()) f.failure = "the orbit found has impacts the prover cannot follow";
  if (!f.failure.empty()) return f;
  // Impact 0 first in time; the rest follow it within one period.
  f.guess.period = orbit.period;
  // The forcing is T-periodic: shifted by whole periods, impact 0 falls in [0, T) (small times keep
  // the box, relative to 1 + |t|, narrow).
  const double shift = std::floor(rec.times.front() / sys.period()) * sys.period();
  for (double& t : rec.times) t -= shift;
  f.guess.times = rec.times;
  f.guess.X = rec.X;
  f.guess.V = rec.V;
  if (sys.contact_count() > 1) f.guess.contacts = rec.contacts;
  // The least period: the orbit's own (asked for none), or a refusal of a period it does not have.
  const int least = LeastPeriod(f.guess, sys.period());
  if (least < f.guess.period) {
    // Asked for a period Q that the orbit's least period p divides: the orbit is proven at p (a
    // p-periodic orbit is Q-periodic), and the result says so.
    if (request.period > 0) f.requested = request.period;
    const auto keep = f.guess.times.size() * static_cast<std::size_t>(least) / static_cast<std::size_t>(f.guess.period);
    f.guess.times.resize(keep);
    f.guess.X.resize(keep);
    f.guess.V.resize(keep);
    if (!f.guess.contacts.empty()) f.guess.contacts.resize(keep);
    f.guess.period = least;
  }
  const std::size_t unknowns = f.guess.times.size() * static_cast<std::size_t>(2 * sys.dof() + 1);
  if (unknowns > proof::kMaxUnknowns)
    f.failure = fmt::format("the orbit found has {} impacts in {} period(s) and {} mode(s): {} unknowns, more than the "
                            "{} the prover takes (docs/prove.md \"Bounds\")", f.guess.times.size(), f.guess.period,
                            sys.dof(), unknowns, proof::kMaxUnknowns);
  return f;
}

// The releases and plastic landings of a sticking orbit, in order, with their times and the states
// just after (a release event follows its reset, a plastic impact precedes its reset: they are
// paired in order).
class StickRecorder final : public Observer {
 public:
  struct Item {
    std::string kind;  // "release", "stick", "leave", "other"
    double t = 0;
    Eigen::VectorXd X, V;
  };
  void OnEvent(const Event& e) override {
    if (e.kind == EventKind::kRelease || e.kind == EventKind::kImpact) times.push_back(e.t);
    if (e.kind == EventKind::kAccumulation || e.kind == EventKind::kGrazing) other = true;
  }
  void OnReset(const Reset& r) override {
    Item it;
    it.kind = r.kind == ResetKind::kRelease        ? "release"
              : r.kind == ResetKind::kPlasticStick ? "stick"
              : r.kind == ResetKind::kPlasticLeave ? "leave"
                                                   : "other";
    it.X = r.X_after;
    it.V = r.V_after;
    items.push_back(std::move(it));
  }
  std::vector<double> times;
  std::vector<Item> items;
  bool other = false;
};

// A sticking orbit of several modes held on one contact with plastic landings: the release and the
// landings up to the sticking that lasts until the next release, q periods later.
struct FoundSticking {
  std::string failure;
  bool stopped = false;
  proof::StickingGuess guess;
};

FoundSticking FindStickingOrbit(const System& sys, const Scene& scene, const ProofRequest& request,
                                const proof::Budget& budget) {
  FoundSticking f;
  StickRecorder rec;
  const proof::StickingSearch found = proof::FollowStickingOrbit(sys, scene, request, budget, rec);
  if (found.stopped || !found.failure.empty()) {
    f.stopped = found.stopped;
    f.failure = found.failure;
    return f;
  }
  if (rec.other || rec.times.size() != rec.items.size()) {
    f.failure = "the sticking orbit found has a chattering sequence or a grazing the prover cannot follow";
    return f;
  }
  for (std::size_t k = 0; k < rec.items.size(); ++k) rec.items[k].t = rec.times[k];
  const auto& it = rec.items;
  std::size_t r0 = 0;
  while (r0 < it.size() && it[r0].kind != "release") ++r0;
  std::size_t end = r0 + 1;
  while (end < it.size() && it[end].kind == "leave") ++end;
  const double T = sys.period();
  if (r0 >= it.size() || end >= it.size() || it[end].kind != "stick" || end + 1 >= it.size() ||
      it[end + 1].kind != "release") {
    f.failure = "the sticking orbit found is not a release, plastic landings and one sticking phase per period";
    return f;
  }
  const double turns = (it[end + 1].t - it[r0].t) / T;
  const int q = static_cast<int>(std::lround(turns));
  if (q < 1 || std::abs(turns - q) > 1e-6) {
    f.failure = "the sticking orbit found has more than one sticking phase per period (not proven by this version)";
    return f;
  }
  const double shift = std::floor(it[r0].t / T) * T;
  f.guess.period = q;
  f.guess.release_time = it[r0].t - shift;
  f.guess.X_release = it[r0].X;
  f.guess.V_release = it[r0].V;
  for (std::size_t k = r0 + 1; k <= end; ++k) {
    f.guess.landing_times.push_back(it[k].t - shift);
    f.guess.X.push_back(it[k].X);
    f.guess.V.push_back(it[k].V);
  }
  return f;
}

// An impact of the orbit at a contact with r = 0.
bool PlasticImpact(const System& sys, const proof::ImpactGuess& g) {
  for (std::size_t j = 0; j < g.times.size(); ++j) {
    const int c = g.contacts.empty() ? 0 : g.contacts[j];
    if (sys.contacts()[static_cast<std::size_t>(c)].restitution == 0) return true;
  }
  return false;
}

// Every enclosure of a time or of the section in the summary is at most box_width wide (docs/prove.md).
double WidestClaim(const Json& summary) {
  double w = summary.contains("box_width") ? summary["box_width"].get<double>() : 0.0;
  const auto widen = [&](const Json& p) { w = std::max(w, p[1].get<double>() - p[0].get<double>()); };
  for (const auto& e : summary["events"]) widen(e["time"]);
  if (summary["section"].is_object()) {
    widen(summary["section"]["time"]);
    for (const char* key : {"X", "V"})
      for (const auto& p : summary["section"][key]) widen(p);
  }
  return w;
}

// Contacts 1, 2, ... alike (the parameter interval of a branch is one of contact 0's or the forcing's).
bool SameMoreContacts(const proof::IntervalModel& a, const proof::IntervalModel& b) {
  if (a.contacts.size() != b.contacts.size()) return false;
  for (std::size_t c = 1; c < a.contacts.size(); ++c) {
    const auto &x = a.contacts[c], &y = b.contacts[c];
    if (x.shape_text != y.shape_text || x.contact_text != y.contact_text || x.stop_text != y.stop_text ||
        x.restitution_text != y.restitution_text)
      return false;
  }
  return true;
}

ProofResult Wrap(proof::Outcome outcome, const std::string& kind, const proof::IntervalModel& model,
                 const ProofRequest& request, const proof::Budget& budget, const std::string& stage,
                 const Json& structure = nullptr) {
  ProofResult result;
  if (budget.interrupted()) {  // no verdict, nothing proven, no certificate
    result.interrupted = true;
    result.reason = "interrupted: nothing is proven";
    result.summary_json = Json{{"verdict", "not-proven"}, {"reason", result.reason}, {"kind", kind}}.dump();
    return result;
  }
  if (!outcome.proven && budget.expired())
    outcome.reason = fmt::format("the time limit of {:g} s was reached {}: nothing is proven",
                                 budget.seconds(), stage);
  result.proven = outcome.proven;
  result.reason = outcome.reason;
  Json summary = {{"verdict", outcome.proven ? "proven" : "not-proven"}, {"reason", outcome.reason}, {"kind", kind}};
  for (const auto& [key, value] : outcome.summary.items()) summary[key] = value;
  if (!summary.contains("period")) summary["period"] = request.period > 0 ? Json(request.period) : Json(nullptr);
  for (const char* key : {"sequence", "events", "multipliers"})
    if (!summary.contains(key)) summary[key] = Json::array();
  if (!summary.contains("section")) summary["section"] = nullptr;
  if (!summary.contains("stability")) summary["stability"] = "undecided";
  if (outcome.proven) summary["box_width"] = WidestClaim(summary);
  // The modal data: the scene's (modal form), or enclosed from its matrices (physical form).
  summary["modal_data"] = structure.is_null() ? "given" : "enclosed";
  result.summary_json = summary.dump();
  result.kind = kind;
  if (summary["period"].is_number_integer()) result.period = summary["period"].get<int>();
  if (summary.contains("requested_period")) result.requested_period = summary["requested_period"].get<int>();
  const auto enclosure = [](const Json& p) { return Enclosure{p[0].get<double>(), p[1].get<double>()}; };
  for (const auto& e : summary["events"])
    result.events.push_back({e["kind"].get<std::string>(), enclosure(e["phase"]), enclosure(e["velocity_before"]),
                             e["contact"].get<int>()});
  for (const auto& m : summary["multipliers"]) result.multipliers.emplace_back(enclosure(m["re"]), enclosure(m["im"]));
  result.stability = summary["stability"].get<std::string>();
  result.modal_data = summary["modal_data"].get<std::string>();
  if (summary.contains("box_width")) result.box_width = summary["box_width"].get<double>();
  Json cert = {{"format", "vibro-proof-certificate/1"},
               {"verdict", summary["verdict"]},
               {"reason", outcome.reason},
               {"kind", kind},
               {"period", summary["period"]},
               {"model", ModelJson(model)},
               {"libraries", proof::LibraryVersions()},
               {"precision_bits", 128},
               {"summary", summary}};
  if (!structure.is_null()) cert["structure"] = structure;
  for (const auto& [key, value] : outcome.certificate.items()) cert[key] = value;
  result.certificate_json = cert.dump(1);
  return result;
}

}  // namespace

ProofResult proof::ProveOrbit(const System& system, const Scene& scene, const ProofRequest& request) {
  const proof::Budget budget(request.time_limit, request.stop_requested);
  const auto enclosed = EnclosureOf(system, scene);
  proof::Outcome outcome;
  if (enclosed.failure.empty() && system.harmonic_sum()) {
    outcome.reason = "orbits under a sum of harmonics are not proven by this version (docs/harmonics.md)";
    return Wrap(outcome, "", ModelOf(system), request, budget, "before the proof");
  }
  if (!enclosed.failure.empty()) {
    outcome.reason = enclosed.failure;
    return Wrap(outcome, "", ModelOf(system), request, budget, "during the proof");
  }
  const auto model = ModelOf(system, scene.physical ? &enclosed : nullptr);
  std::string kind, stage = "during the proof";
  const bool one_dof = system.dof() == 1 && system.contact_shape()(0) == 1;
  const auto sticking = [&]() {
    kind = "sticking";
    if (system.contact_count() > 1) {
      // Held on one contact or on a set of contacts, plastic landings (proof/held_set_proof.hpp).
      const auto found = proof::FindHeldSetOrbit(system, scene, model, request, budget);
      if (found.stopped)
        stage = fmt::format("during the orbit search (a transient of {} periods, then Newton)",
                            request.start ? 0 : request.transient_periods);
      else if (!found.failure.empty()) outcome.reason = found.failure;
      else outcome = proof::ProveHeldSet(model, found.guess, request, budget);
    } else if (one_dof) {
      outcome = proof::ProveSticking1Dof(model, request, budget);  // r = 0, or r > 0 with chattering
    } else if (system.restitution() > 0) {
      outcome.reason = "sticking orbits with chattering (r > 0) of a model with more than one mode are not proven "
                       "by this version (docs/prove.md)";
    } else {
      const auto found = FindStickingOrbit(system, scene, request, budget);
      if (found.stopped)
        stage = fmt::format("during the orbit search (a transient of {} periods, then Newton)",
                            request.start ? 0 : request.transient_periods);
      else if (!found.failure.empty()) outcome.reason = found.failure;
      else outcome = proof::ProveStickingModes(model, found.guess, request, budget);
    }
  };
  if (request.kind == OrbitKind::kSticking) {
    sticking();
  } else if (request.kind == OrbitKind::kAuto && one_dof && system.restitution() == 0 && system.contact_count() == 1) {
    sticking();  // r = 0, one mode: every impact is plastic, an orbit with impacts sticks or departs
  } else {
    const auto found = FindImpactOrbit(system, scene, request, budget);
    if (found.stopped) {
      kind = request.kind == OrbitKind::kSticking ? "sticking" : "impact";
      stage = fmt::format("during the orbit search (a transient of {} periods, then Newton)",
                          request.start ? 0 : request.transient_periods);
    } else if (found.sticking && request.kind == OrbitKind::kAuto) {
      sticking();
    } else {
      kind = "impact";
      if (found.sticking) outcome.reason = "the orbit found sticks: it is not an impacting orbit (try --kind sticking)";
      else if (!found.failure.empty()) outcome.reason = found.failure;
      else if (PlasticImpact(system, found.guess))
        outcome.reason = "r = 0: every impact is plastic (try --kind sticking)";
      else outcome = proof::ProveImpactOrbit(model, found.guess, request, budget);
      if (outcome.proven && found.requested > 0) proof::StateLeastPeriod(outcome, found.requested);
    }
  }
  return Wrap(outcome, kind, model, request, budget, stage, enclosed.structure);
}

}  // namespace vibro

namespace vibro {

std::vector<ProofResult> proof::ProveOrbitOverInterval(const System& system_lo, const Scene& scene_lo,
                                                       const ProofRequest& lo, const System& system_hi,
                                                       const Scene& scene_hi, const ProofRequest& hi) {
  const proof::Budget budget(lo.time_limit, lo.stop_requested);
  const auto enclosed = EnclosureOf(system_lo, scene_lo), enclosed_hi = EnclosureOf(system_hi, scene_hi);
  proof::Outcome outcome;
  if (!enclosed.failure.empty() || !enclosed_hi.failure.empty()) {
    outcome.reason = enclosed.failure.empty() ? enclosed_hi.failure : enclosed.failure;
    return {Wrap(outcome, "impact", ModelOf(system_lo), lo, budget, "during the proof")};
  }
  auto model = ModelOf(system_lo, scene_lo.physical ? &enclosed : nullptr);
  const auto model_hi = ModelOf(system_hi, scene_hi.physical ? &enclosed_hi : nullptr);
  const Json& scene_structure = enclosed.structure;  // a physical scene's matrices and eigenpair boxes
  // The one scalar that differs, as the interval between its two decimals.
  using proof::Interval;
  std::vector<std::string> differs;
  const auto between = [&](std::string& a, const std::string& b, const char* name) {
    if (a == b) return;
    differs.push_back(name);
    const bool ordered = Interval::Decimal(a).lo() <= Interval::Decimal(b).lo();
    a = "[" + (ordered ? a : b) + ", " + (ordered ? b : a) + "]";
  };
  std::string amplitude = model.amplitude_text, frequency = model.frequency_text, stop = model.stop_text,
              restitution = model.restitution_text;
  between(amplitude, model_hi.amplitude_text, "amplitude");
  between(frequency, model_hi.frequency_text, "frequency");
  between(stop, model_hi.stop_text, "stop position");
  between(restitution, model_hi.restitution_text, "restitution");
  const bool same_structure = model.omega_text == model_hi.omega_text && model.forcing_text == model_hi.forcing_text &&
                              model.contact_text == model_hi.contact_text && model.shape_text == model_hi.shape_text &&
                              model.damping_text == model_hi.damping_text && SameMoreContacts(model, model_hi);
  if (!same_structure || differs.size() != 1) {
    outcome.reason = "the two ends differ in more than one scalar of the modal model (a parameter interval is proven "
                     "for the amplitude, the forcing frequency, the stop position or the restitution alone)";
    return {Wrap(outcome, "impact", model, lo, budget, "during the proof", scene_structure)};
  }
  const auto a = FindImpactOrbit(system_lo, scene_lo, lo, budget);
  const auto b = a.stopped ? Found{} : FindImpactOrbit(system_hi, scene_hi, hi, budget);
  if (a.stopped || b.stopped || budget.passed())
    return {Wrap(outcome, "impact", model, lo, budget, "during the orbit search at the ends of the interval", scene_structure)};
  if (!a.failure.empty() || !b.failure.empty() || a.sticking || b.sticking) {
    outcome.reason = "no impacting orbit at one end: " + (a.failure.empty() ? b.failure : a.failure);
    return {Wrap(outcome, "impact", model, lo, budget, "during the proof", scene_structure)};
  }
  if (a.guess.times.size() != b.guess.times.size() || a.guess.period != b.guess.period) {
    outcome.reason = "the orbits at the two ends have different impact sequences";
    return {Wrap(outcome, "impact", model, lo, budget, "during the proof", scene_structure)};
  }
  // The parameter interval [p_lo, p_hi] is proven whole, or halved (at a decimal shared by both
  // halves) up to kMaxSplit times, each piece with the orbits interpolated between the two ends.
  constexpr int kMaxSplit = 10;
  std::string* field = differs.front() == "amplitude"     ? &amplitude
                       : differs.front() == "frequency"   ? &frequency
                       : differs.front() == "restitution" ? &restitution
                                                          : &stop;
  const std::string whole = *field;
  const auto comma = whole.find(',');
  const std::string first = whole.substr(1, comma - 1), last = whole.substr(comma + 2, whole.size() - comma - 3);
  const bool a_is_lo = Interval::Decimal(first).lo() == Interval::Decimal(differs.front() == "amplitude"     ? model.amplitude_text
                                                                          : differs.front() == "frequency"   ? model.frequency_text
                                                                          : differs.front() == "restitution" ? model.restitution_text
                                                                                                             : model.stop_text).lo();
  const auto& g_lo = a_is_lo ? a.guess : b.guess;
  const auto& g_hi = a_is_lo ? b.guess : a.guess;
  const auto structure = model;
  std::vector<ProofResult> results;
  std::string failure;
  // Proves [x0, x1] (decimal texts) at the fractions [f0, f1] of the whole interval.
  std::function<bool(const std::string&, const std::string&, double, double, int)> piece =
      [&](const std::string& x0, const std::string& x1, double f0, double f1, int depth) -> bool {
    // The model with the parameter at `text` (a decimal, or the interval "[a, b]").
    const auto model_at = [&](const std::string& text) {
      *field = text;
      auto m = proof::IntervalModel::FromDecimals(structure.omega_text, structure.forcing_text, structure.contact_text,
                                                  structure.shape_text, stop, restitution, amplitude, frequency,
                                                  structure.damping_text);
      for (std::size_t c = 1; c < structure.contacts.size(); ++c) {
        const auto& k = structure.contacts[c];
        m.AddContact(k.shape_text, k.contact_text, k.stop_text, k.restitution_text);
      }
      return m;
    };
    // The residual is affine in the amplitude, the stop position and the restitution: Krawczyk's
    // constant term from the two ends (proof_common.hpp AffineEnds). Not in the forcing frequency:
    // there the mean-value form in ω (impact_proof.cpp CentreInFrequency).
    std::optional<proof::AffineEnds> ends;
    if (field != &frequency) ends = proof::AffineEnds{model_at(x0), model_at(x1)};
    const auto m = model_at("[" + x0 + ", " + x1 + "]");
    const auto at = [&](double f, const auto& lo_v, const auto& hi_v) { return lo_v + f * (hi_v - lo_v); };
    proof::ImpactGuess g = g_lo;
    for (std::size_t j = 0; j < g.times.size(); ++j) {
      const double t0 = at(f0, g_lo.times[j], g_hi.times[j]), t1 = at(f1, g_lo.times[j], g_hi.times[j]);
      const Eigen::VectorXd X0 = at(f0, g_lo.X[j], g_hi.X[j]), X1 = at(f1, g_lo.X[j], g_hi.X[j]);
      const Eigen::VectorXd V0 = at(f0, g_lo.V[j], g_hi.V[j]), V1 = at(f1, g_lo.V[j], g_hi.V[j]);
      g.spread.push_back(std::abs(t1 - t0));
      for (int i = 0; i < system_lo.dof(); ++i) g.spread.push_back(std::abs(X1(i) - X0(i)));
      for (int i = 0; i < system_lo.dof(); ++i) g.spread.push_back(std::abs(V1(i) - V0(i)));
      g.times[j] = (t0 + t1) / 2;
      g.X[j] = (X0 + X1) / 2;
      g.V[j] = (V0 + V1) / 2;
    }
    auto o = proof::ProveImpactOrbit(m, g, lo, budget, ends ? &*ends : nullptr, field == &frequency);
    const std::string interval = *field;
    const double v0 = Interval::Decimal(x0).mid(), v1 = Interval::Decimal(x1).mid(), vm = v0 + (v1 - v0) / 2;
    const std::string xm = Decimal(vm);
    const bool can_split = depth < kMaxSplit && !budget.passed() && v0 < vm && vm < v1;
    if (o.proven && field == &frequency) {
      // Stability along the piece: the spectral radius below 1 on sub-pieces (segment_stability.cpp).
      // No multiplier enclosure is claimed over a frequency piece: the checker's, the hull over its
      // own pieces of the interval, need not lie in the prover's enclosure over the whole box (near
      // the pitchfork, where two real multipliers nearly meet, it did not).
      o.summary["multipliers"] = Json::array();
      o.summary["stability"] = "undecided";
      o.summary.erase("stability_note");
      const auto st = proof::ProveSegmentStability(model_at, x0, x1, o.certificate, g_lo.period, budget);
      *field = interval;
      if (st.proven) {
        o.certificate["spectral_bound"] = st.certificate;
        o.summary["stability"] = "stable";
        o.summary["stability_note"] = proof::kSegmentStableNote;
      }
    }
    if (o.proven) {
      o.reason = "for every " + differs.front() + " in " + interval + ": " + o.reason;
      results.push_back(Wrap(o, "impact", m, lo, budget, "during the proof", scene_structure));
      return true;
    }
    if (!can_split) {
      failure = fmt::format("{} in [{}, {}]: {}", differs.front(), x0, x1, o.reason);
      outcome = o;
      return false;
    }
    const double fm = f0 + (f1 - f0) / 2;
    return piece(x0, xm, f0, fm, depth + 1) && piece(xm, x1, fm, f1, depth + 1);
  };
  if (piece(first, last, 0.0, 1.0, 0) && !budget.interrupted()) return results;
  outcome.reason = "not proven over the whole interval: " + failure;
  *field = whole;
  auto whole_model = proof::IntervalModel::FromDecimals(structure.omega_text, structure.forcing_text,
                                                        structure.contact_text, structure.shape_text, stop, restitution,
                                                        amplitude, frequency, structure.damping_text);
  for (std::size_t c = 1; c < structure.contacts.size(); ++c) {
    const auto& k = structure.contacts[c];
    whole_model.AddContact(k.shape_text, k.contact_text, k.stop_text, k.restitution_text);
  }
  return {Wrap(outcome, "impact", whole_model, lo, budget, "during the proof", scene_structure)};
}

}  // namespace vibro

namespace vibro {

ProofResult proof::ProveBifurcation(const System& system, const Scene& scene, const BifurcationRequest& request) {
  const proof::Budget budget(request.time_limit, request.stop_requested);
  const auto enclosed = EnclosureOf(system, scene);
  proof::Outcome outcome;
  ProofRequest as_orbit;
  as_orbit.time_limit = request.time_limit;
  as_orbit.period = 1;
  if (!enclosed.failure.empty()) {
    outcome.reason = enclosed.failure;
    return Wrap(outcome, "bifurcation", ModelOf(system), as_orbit, budget, "during the proof");
  }
  auto model = ModelOf(system, scene.physical ? &enclosed : nullptr);
  const bool amplitude = request.parameter == "excitation.amplitude";
  const bool frequency = request.parameter == "excitation.frequency";
  // Two stops on one DOF, on opposite sides: c_1 = −c_0 exactly, whatever the enclosures of c.
  const auto contacts = Contacts(scene);
  const bool mirrored = scene.physical.has_value() && contacts.size() == 2 && contacts[0].dof == contacts[1].dof && contacts[0].partner < 0 &&
                        contacts[1].partner < 0 && contacts[0].side != contacts[1].side;
  std::string interval;
  if (request.kind != "branch-point" && request.kind != "fold" && request.kind != "grazing") {
    outcome.reason = "a " + request.kind + " is not proven by this version (it proves the symmetry-breaking pitchfork "
                     "and the fold of the symmetric two-sided one-DOF oscillator, and grazings; docs/prove.md)";
  } else if (!amplitude && !frequency) {
    outcome.reason = "the parameter " + request.parameter + " is not proven by this version (the amplitude or the "
                     "forcing frequency; docs/prove.md)";
  } else {
    (amplitude ? model.amplitude_text : model.frequency_text) = Decimal(request.value);
    model = [&] {
      auto m = proof::IntervalModel::FromDecimals(model.omega_text, model.forcing_text, model.contact_text,
                                                  model.shape_text, model.stop_text, model.restitution_text,
                                                  model.amplitude_text, model.frequency_text, model.damping_text);
      for (std::size_t c = 1; c < model.contacts.size(); ++c) {
        const auto& k = model.contacts[c];
        m.AddContact(k.shape_text, k.contact_text, k.stop_text, k.restitution_text);
      }
      return m;
    }();
    std::string one_dof_why;
    const bool general_pitchfork =
        request.kind == "branch-point" && !proof::SymmetricTwoSided(model, mirrored, one_dof_why) && model.n >= 1 &&
        model.contact_count() == 2;
    if (request.kind == "grazing" || general_pitchfork) {
      // The orbit that grazes, at the located value: from the given state, else searched.
      as_orbit.kind = OrbitKind::kImpact;
      as_orbit.period = request.period;
      as_orbit.start = request.start;
      Scene there = scene;
      if (request.start) (amplitude ? there.amplitude : there.frequency) = request.start_value;
      const System at(there);
      const auto found = FindImpactOrbit(request.start ? at : system, request.start ? there : scene, as_orbit, budget);
      as_orbit.period = 1;
      if (found.stopped || budget.passed())
        return Wrap(outcome, "bifurcation", model, as_orbit, budget, "during the orbit search", enclosed.structure);
      if (!found.failure.empty() || found.sticking)
        outcome.reason = "no impacting orbit found at the located value: " +
                         (found.failure.empty() ? std::string("the orbit found sticks") : found.failure);
      else
        outcome = general_pitchfork ? proof::ProveOrbitPitchfork(model, mirrored, found.guess, frequency, request.value,
                                                                 request.bracket, budget, interval)
                                    : proof::ProveGrazing(model, mirrored, found.guess, frequency, request.value,
                                                          request.bracket, budget, interval);
    } else {
      outcome = request.kind == "fold"
                    ? proof::ProveSymmetricFold(model, mirrored, frequency, request.value, request.bracket, budget,
                                                interval)
                    : proof::ProvePitchfork(model, mirrored, frequency, request.value, request.bracket, budget, interval);
    }
    if (outcome.proven) {
      // The certificate's model carries the parameter as the proven interval.
      (amplitude ? model.amplitude_text : model.frequency_text) = interval;
      outcome.summary["param"] = request.parameter;
    }
  }
  return Wrap(outcome, "bifurcation", model, as_orbit, budget, "during the proof", enclosed.structure);
}

}  // namespace vibro

namespace {
const VibroProveApi kApi{sizeof(vibro::ProofResult), sizeof(vibro::ProofRequest), &vibro::proof::ProveOrbit,
                         &vibro::proof::ProveOrbitOverInterval, &vibro::proof::ProveBifurcation};
}  // namespace

extern "C" __attribute__((visibility("default"))) const VibroProveApi* vibro_prove_api() { return &kApi; }
