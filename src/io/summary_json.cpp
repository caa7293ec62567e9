// JSON summaries (docs/cli.md, docs/output.md).
#include "vibro/summary_json.hpp"

#include <cmath>
#include <optional>

#include <nlohmann/json.hpp>

namespace vibro {
namespace {

nlohmann::json Array(const Eigen::VectorXd& v) {
  auto a = nlohmann::json::array();
  for (Eigen::Index i = 0; i < v.size(); ++i) a.push_back(v[i]);
  return a;
}

// An optional value, or JSON null.
template <class T>
nlohmann::json OrNull(const std::optional<T>& v) {
  return v ? nlohmann::json(*v) : nlohmann::json(nullptr);
}

nlohmann::json AttractorObject(const Attractor& a) {
  nlohmann::json j;
  j["kind"] = a.kind;
  j["period"] = OrNull(a.period);
  j["impacts_per_period"] = OrNull(a.impacts_per_period);
  j["sticking_fraction"] = OrNull(a.sticking_fraction);
  auto phases = nlohmann::json::array();
  for (const auto& [s, e] : a.stick_phases) phases.push_back({s, e});
  j["stick_phases"] = phases;
  j["stick_contacts"] = a.stick_contacts;
  if (a.kind == "impact-periodic") {
    j["impact_phases"] = a.impact_phases;
    j["impact_velocities"] = a.impact_velocities;
    j["impact_contacts"] = a.impact_contacts;
  }
  if (a.searched_period) {
    j["searched_period"] = *a.searched_period;
    j["recurrence_period"] = OrNull(a.recurrence_period);
    j["recurrence_distance"] = OrNull(a.recurrence_distance);
  }
  return j;
}

}  // namespace

// A finite number, or JSON null for ±∞ (Lyapunov exponents of collapsed directions).
nlohmann::json FiniteOrNull(double x) { return std::isfinite(x) ? nlohmann::json(x) : nlohmann::json(nullptr); }

// The keys of a Lyapunov spectrum (docs/output.md): lyapunov_exponents (largest first, per unit
// time, null for −∞), lyapunov_ci, lyapunov_periods, [lyapunov_singular_periods], [lyapunov_corner],
// [lyapunov_undefined], chaotic.
void AddLyapunov(nlohmann::json& j, const LyapunovSpectrum& ly) {
  auto exponents = nlohmann::json::array(), ci = nlohmann::json::array();
  for (double e : ly.exponents) exponents.push_back(FiniteOrNull(e));
  for (const auto& [lo, hi] : ly.ci) ci.push_back({FiniteOrNull(lo), FiniteOrNull(hi)});
  j["lyapunov_exponents"] = exponents;
  j["lyapunov_ci"] = ci;
  j["lyapunov_periods"] = ly.periods;
  if (ly.singular_periods) j["lyapunov_singular_periods"] = ly.singular_periods;
  if (!ly.corner.empty()) j["lyapunov_corner"] = ly.corner;
  if (!ly.undefined.empty()) j["lyapunov_undefined"] = ly.undefined;
  j["chaotic"] = ly.chaotic();
}

void AddLoads(nlohmann::json& j, const LoadsSummary& s) {
  auto arr = nlohmann::json::array();
  const auto ci = [](const ContactLoads::Interval& c) {
    return c ? nlohmann::json::array({c->first, c->second}) : nlohmann::json(nullptr);
  };
  for (const ContactLoads& c : s.contacts) {
    // A compliant stop (docs/loads.md, "Peak force and contact duration over a run"): its contact
    // phases per period, the mean peak force and duration per phase, the largest peak force.
    const auto compliant = [&](nlohmann::json& o) {
      if (!c.compliant) return;
      // No impacts, so no normal work in the rigid limit (docs/loads.md §4): not a zero.
      o["work_rate"] = nullptr;
      if (s.blocks != 0) o["work_rate_ci"] = nullptr;
      o["contact_phases_per_period"] = c.phases_per_period;
      o["peak_force_mean"] = c.peak_force_mean;
      o["contact_duration_mean"] = c.contact_duration_mean;
      o["peak_force_max"] = c.peak_force_max;
      if (s.blocks == 0) return;
      o["contact_phases_per_period_ci"] = ci(c.phases_per_period_ci);
      o["peak_force_mean_ci"] = ci(c.peak_force_mean_ci);
      o["contact_duration_mean_ci"] = ci(c.contact_duration_mean_ci);
    };
    if (s.blocks == 0) {  // a periodic orbit's exact values: no interval
      arr.push_back({{"contact", c.contact},
                     {"impacts_per_period", c.impacts_per_period},
                     {"impulse_per_period", c.impulse_per_period},
                     {"reaction_integral_per_period", c.reaction_integral_per_period},
                     {"mean_force", c.mean_force},
                     {"dissipated_power", c.dissipated_power},
                     {"work_rate", c.work_rate},
                     {"contact_fraction", c.contact_fraction}});
      compliant(arr.back());
      continue;
    }
    arr.push_back({{"contact", c.contact},
                   {"impacts_per_period", c.impacts_per_period},
                   {"impacts_per_period_ci", ci(c.impacts_per_period_ci)},
                   {"impulse_per_period", c.impulse_per_period},
                   {"impulse_per_period_ci", ci(c.impulse_per_period_ci)},
                   {"reaction_integral_per_period", c.reaction_integral_per_period},
                   {"reaction_integral_per_period_ci", ci(c.reaction_integral_per_period_ci)},
                   {"mean_force", c.mean_force},
                   {"mean_force_ci", ci(c.mean_force_ci)},
                   {"dissipated_power", c.dissipated_power},
                   {"dissipated_power_ci", ci(c.dissipated_power_ci)},
                   {"work_rate", c.work_rate},
                   {"work_rate_ci", ci(c.work_rate_ci)},
                   {"contact_fraction", c.contact_fraction},
                   {"contact_fraction_ci", ci(c.contact_fraction_ci)}});
    compliant(arr.back());
  }
  j["loads"] = arr;
  if (s.blocks == 0) {
    if (!s.note.empty()) j["loads_note"] = s.note;
    return;
  }
  j["loads_window"] = {{"first_period", s.first_period},
                       {"periods", s.periods},
                       {"blocks", s.blocks},
                       {"block_periods", s.block_periods},
                       {"note", s.note},
                       {"whole_run", s.whole_run}};
  // A run resumed or extended from a file without its per-period loads (docs/loads.md §5).
  if (!s.whole_run) {
    j["loads_window"]["known_from"] = s.known_from;
    j["loads_window"]["coverage"] = s.coverage;
  }
}

// A branch point's or partition cell's exact loads (no intervals): "loads", and "loads_note"
// when there is one.
void AddPointLoads(nlohmann::json& j, const std::vector<ContactLoads>& loads, const std::string& note) {
  LoadsSummary s;
  s.contacts = loads;
  s.note = note;
  AddLoads(j, s);
}

std::string SimulationJson(const Scene& scene, const RunResult& r, const Attractor& a, const LyapunovSpectrum* ly,
                           const LoadsSummary* loads) {
  nlohmann::json j;
  j["status"] = ToString(r.status);
  if (r.status != RunStatus::kOk) j["message"] = r.message;
  j["engine"] = ToString(scene.run.engine);
  j["t_end"] = r.t_end;
  j["periods"] = r.end.period;
  j["counts"] = {{"impacts", r.counts.impacts},
                 {"accumulations", r.counts.accumulations},
                 {"sticks", r.counts.sticks},
                 {"releases", r.counts.releases},
                 {"grazings", r.counts.grazings}};
  // Per contact, in [[contact]] order (one entry for a [stop]), docs/contacts.md.
  auto contacts = nlohmann::json::array();
  for (const EventCounts& c : r.contact_counts)
    contacts.push_back({{"impacts", c.impacts},
                        {"accumulations", c.accumulations},
                        {"sticks", c.sticks},
                        {"releases", c.releases},
                        {"grazings", c.grazings},
                        {"simultaneous", c.simultaneous}});
  j["contacts"] = contacts;
  j["attractor"] = AttractorObject(a);
  j["precision"] = ToString(scene.run.precision);
  j["chattering"] = {{"accumulations_predicted", r.chatter.accumulations_predicted},
                     {"impacts_followed", r.chatter.impacts_followed},
                     {"max_estimated_error", r.chatter.max_estimated_error},
                     {"tolerance", ChatterTolerance(scene.run)}};
  if (scene.run.engine == Engine::kCvode)
    j["solver"] = {{"steps", r.solver.steps},
                   {"rhs_evals", r.solver.rhs_evals},
                   {"root_evals", r.solver.root_evals},
                   {"jac_evals", r.solver.jac_evals},
                   {"error_test_failures", r.solver.error_test_failures},
                   {"reinits", r.solver.reinits}};
  if (ly) AddLyapunov(j, *ly);
  if (loads) AddLoads(j, *loads);
  return j.dump();
}

namespace {

// The contact phases of compliant stops over an orbit's q periods (docs/compliant.md), as `vibro
// orbit --json` and each point of `vibro continue --json` give them.
nlohmann::json ContactPhasesJson(const std::vector<OrbitResult::ContactPhase>& contact_phases) {
  auto phases = nlohmann::json::array();
  for (const auto& p : contact_phases)
    phases.push_back({{"contact", p.contact},
                      {"entry", p.entry},
                      {"exit", p.exit},
                      {"duration", p.duration},
                      {"entry_velocity", p.entry_velocity},
                      {"exit_velocity", p.exit_velocity},
                      {"peak_force", p.peak_force},
                      {"peak_time", p.peak_time},
                      {"penetration", p.penetration},
                      {"impulse", p.impulse},
                      {"energy_dissipated", p.dissipated}});
  return phases;
}

}  // namespace

std::string OrbitJson(const OrbitResult& o, OrbitKind kind, const LoadsSummary* loads) {
  nlohmann::json j;
  j["status"] = o.status;
  if (!o.message.empty()) j["message"] = o.message;
  j["period"] = o.period;
  // The orbit's least period (docs/orbits.md): a divisor of `period`, smaller when --period Q found an
  // orbit of a period that divides Q; null when no orbit converged.
  j["least_period"] = o.status == "converged" ? OrNull(o.summary.period) : nlohmann::json(nullptr);
  // kAuto: both sets of fields (the orbit's kind is attractor_kind).
  if (kind != OrbitKind::kImpact) {
    j["sticking_fraction"] = OrNull(o.summary.sticking_fraction);
    auto phases = nlohmann::json::array();
    for (const auto& [s, e] : o.summary.stick_phases) phases.push_back({s, e});
    j["stick_phases"] = phases;
    j["stick_contacts"] = o.summary.stick_contacts;
    j["impacts_per_period"] = OrNull(o.summary.impacts_per_period);
  }
  if (kind != OrbitKind::kSticking) {
    j["impact_phases"] = o.summary.impact_phases;
    j["impact_velocities"] = o.summary.impact_velocities;
    j["impact_contacts"] = o.summary.impact_contacts;
  }
  auto mu = nlohmann::json::array();
  for (const auto& m : o.multipliers) mu.push_back({m.real(), m.imag()});
  j["floquet_multipliers"] = mu;
  // Stability is a property of a converged orbit with a Jacobian only.
  j["stable"] = o.status == "converged" && o.no_jacobian.empty() ? nlohmann::json(o.stable)
                                                                  : nlohmann::json(nullptr);
  // Several contacts (docs/contacts.md): the contact sequence, and why there are no multipliers.
  if (!o.sequence.empty()) j["sequence"] = o.sequence;
  if (!o.no_jacobian.empty()) j["no_jacobian"] = o.no_jacobian;
  // A compliant stop (docs/compliant.md, "Periodic orbits"): each contact phase of the orbit's q
  // periods with its exact loads.
  if (!o.contact_phases.empty()) j["contact_phases"] = ContactPhasesJson(o.contact_phases);
  j["distance_from_start"] = OrNull(o.distance_from_start);
  if (!o.reached.empty()) j["reached"] = o.reached;
  j["newton_iterations"] = o.newton_iterations;
  j["residual"] = o.residual;
  j["section_time"] = o.section_time;
  j["attractor_kind"] = o.summary.kind;
  j["quad_evaluations"] = o.quad_evaluations;
  if (loads) AddLoads(j, *loads);
  return j.dump();
}

std::string ScoreJson(const ScoreReport& r, const Scene& scene, bool complete) {
  nlohmann::json j;
  j["period"] = r.period;
  j["engine"] = ToString(scene.run.engine);
  j["chatter"] = ToString(scene.run.chatter);
  j["agrees"] = complete ? nlohmann::json(r.agrees()) : nlohmann::json(nullptr);
  j["matched"] = r.matched;
  j["unmatched"] = r.unmatched;
  j["max_time_error"] = r.matched > 0 ? nlohmann::json(r.max_time_error) : nlohmann::json(nullptr);
  j["max_velocity_error"] = OrNull(r.max_velocity_error);
  auto kinds = nlohmann::json::array();
  for (const auto& k : r.kinds) {
    const auto matched_only = [&](double v) { return k.matched > 0 ? nlohmann::json(v) : nlohmann::json(nullptr); };
    kinds.push_back({{"kind", ToString(k.kind)},
                     {"theirs", k.theirs},
                     {"ours", k.ours},
                     {"matched", k.matched},
                     {"matched_fraction", OrNull(k.matched_fraction)},
                     {"scored", k.scored},
                     {"in_accumulation", k.in_accumulation},
                     {"ours_in_accumulation", k.ours_in_accumulation},
                     {"unmatched_theirs", k.unmatched_theirs},
                     {"unmatched_ours", k.unmatched_ours},
                     {"max_time_error", matched_only(k.max_time_error)},
                     {"mean_time_error", matched_only(k.mean_time_error)},
                     {"max_velocity_error", OrNull(k.max_velocity_error)}});
  }
  j["kinds"] = kinds;
  if (r.divergence)
    j["first_divergence"] = {{"t", r.divergence->t},
                             {"kind", ToString(r.divergence->kind)},
                             {"side", r.divergence->side},
                             {"why", r.divergence->why},
                             {"ours_t", OrNull(r.divergence->ours_t)}};
  else
    j["first_divergence"] = nullptr;
  return j.dump();
}

std::string ValidationJson(const std::vector<PointCheck>& checks) {
  nlohmann::json j;
  auto points = nlohmann::json::array();
  int disagreements = 0, undetermined = 0;
  for (const auto& c : checks) {
    const bool ok = c.orbit.status == "converged";
    auto mu = nlohmann::json::array();
    for (const auto& m : c.orbit.multipliers) mu.push_back({m.real(), m.imag()});
    points.push_back({{"value", c.value},
                      {"verdict", c.verdict},
                      {"detail", c.detail},
                      {"distance", OrNull(c.distance)},
                      {"period", ok ? nlohmann::json(c.orbit.summary.period.value_or(c.orbit.period)) : nlohmann::json(nullptr)},
                      {"stable", ok ? nlohmann::json(c.orbit.stable) : nlohmann::json(nullptr)},
                      {"floquet_multipliers", mu},
                      {"sticking_fraction", ok ? OrNull(c.orbit.summary.sticking_fraction) : nlohmann::json(nullptr)},
                      {"kind", ok ? nlohmann::json(c.orbit.summary.kind) : nlohmann::json(nullptr)},
                      {"sequence", ok ? nlohmann::json(c.orbit.sequence) : nlohmann::json(nullptr)},
                      {"simulated_distance", OrNull(c.simulated_distance)}});
    if (c.verdict == "undetermined") ++undetermined;
    else if (c.verdict != "confirmed") ++disagreements;
  }
  j["points"] = points;
  j["disagreements"] = disagreements;
  j["undetermined"] = undetermined;
  return j.dump();
}

namespace {

// A branch point's stroboscopic state, one entry per contact (null: not simulated).
nlohmann::json StrobeJson(const std::vector<double>& strobe) {
  auto a = nlohmann::json::array();
  for (const double x : strobe) a.push_back(std::isfinite(x) ? nlohmann::json(x) : nlohmann::json());
  return a;
}

nlohmann::json BranchObject(const Branch& b) {
  nlohmann::json j;
  j["status"] = b.status;
  j["param"] = b.param;
  j["period"] = b.period;
  auto points = nlohmann::json::array();
  for (const auto& pt : b.points) {
    auto phases = nlohmann::json::array();
    for (const auto& [s, e] : pt.summary.stick_phases) phases.push_back({s, e});
    auto mu = nlohmann::json::array();
    for (const auto& m : pt.multipliers) mu.push_back({m.real(), m.imag()});
    points.push_back({{"value", pt.value},
                      {"sticking_fraction", OrNull(pt.summary.sticking_fraction)},
                      {"stick_phases", phases},
                      {"stick_contacts", pt.summary.stick_contacts},
                      {"impacts_per_period", OrNull(pt.summary.impacts_per_period)},
                      {"stable", pt.stable},
                      {"floquet_multipliers", mu},
                      {"events", pt.signature},
                      {"sequence", pt.sequence},
                      {"x_B", pt.x_B},
                      {"section_phase", pt.section_phase},
                      {"strobe", StrobeJson(pt.strobe)}});
    AddPointLoads(points.back(), pt.loads, pt.loads_note);
    // A compliant stop (docs/compliant.md, "Along a continued branch"): the point's contact phases
    // and the rigid model's distance (null: not computed, or no rigid orbit there).
    if (!pt.contact_phases.empty()) {
      points.back()["contact_phases"] = ContactPhasesJson(pt.contact_phases);
      points.back()["rigid_distance"] = std::isfinite(pt.rigid_distance) ? nlohmann::json(pt.rigid_distance) : nlohmann::json(nullptr);
    }
  }
  j["points"] = points;
  auto bif = nlohmann::json::array();
  for (const auto& x : b.bifurcations) {
    bif.push_back({{"kind", x.kind}, {"value", x.value}, {"detail", x.detail}, {"bracket", x.bracket},
                   {"contact", x.contact >= 0 ? nlohmann::json(x.contact) : nlohmann::json()},
                   {"point", x.point >= 0 ? nlohmann::json(x.point) : nlohmann::json()}});
    if (std::isfinite(x.rotation_number)) bif.back()["rotation_number"] = x.rotation_number;
    // Non-smooth points: the events (and contact sequences) before and past it, and how the branch
    // went through ("past", "back" at a grazing fold; null where it ended there).
    if (!x.events_before.empty()) {
      auto& o = bif.back();
      o["events_before"] = x.events_before;
      o["events_after"] = x.events_after.empty() ? nlohmann::json() : nlohmann::json(x.events_after);
      o["sequence_before"] = x.sequence_before;
      o["sequence_after"] = x.events_after.empty() ? nlohmann::json() : nlohmann::json(x.sequence_after);
      o["through"] = x.through.empty() ? nlohmann::json() : nlohmann::json(x.through);
      if (std::isfinite(x.new_impact_speed)) {
        o["new_impact_speed"] = x.new_impact_speed;
        o["new_impact_distance"] = x.new_impact_distance;
      }
    }
  }
  j["bifurcations"] = bif;
  auto rel = nlohmann::json::array();
  for (const auto& x : b.relabels)
    rel.push_back({{"value", x.value}, {"from", x.from}, {"to", x.to}, {"detail", x.detail}, {"bracket", x.bracket}});
  j["relabels"] = rel;
  j["end"] = b.end;
  j["closed_loop"] = b.closed_loop;
  j["quad_evaluations"] = b.quad_evaluations;
  if (!b.corner.empty()) j["corner"] = b.corner;
  return j;
}
}  // namespace

std::string BranchJson(const Branch& b) { return BranchObject(b).dump(); }

std::string BranchJson(const Branch& b, const SwitchRecord& sw) {
  auto j = BranchObject(b);
  j["switch"] = {{"kind", sw.kind},           {"at", sw.at},         {"start", sw.start},
                 {"period", sw.period},       {"direction", sw.direction}, {"half", sw.half},
                 {"x_B_offset", sw.x_B_offset}, {"distance", sw.distance}};
  return j.dump();
}

std::string PartitionJson(const std::string& param1, const std::string& param2,
                          const std::vector<double>& levels, const std::vector<PartitionColumn>& columns) {
  nlohmann::json j;
  j["params"] = {param1, param2};
  j["levels"] = levels;
  auto cols = nlohmann::json::array();
  for (const auto& c : columns) {
    auto xs = nlohmann::json::array();
    for (const auto& x : c.crossings) xs.push_back({{"level", x.level}, {"value", x.value}});
    auto bs = nlohmann::json::array();
    for (const auto& b : c.bifurcations) bs.push_back({{"kind", b.kind}, {"value", b.value}});
    auto cells = nlohmann::json::array();
    for (const auto& pt : c.points) {
      cells.push_back({{"value2", pt.value2}, {"sticking_fraction", pt.sticking_fraction}, {"stable", pt.stable}});
      AddPointLoads(cells.back(), pt.loads, pt.loads_note);
    }
    cols.push_back({{"value1", c.value1}, {"status", c.status}, {"crossings", xs},
                    {"bifurcations", bs}, {"end_down", c.end_down}, {"end_up", c.end_up}, {"points", cells}});
    if (!c.sequences.empty()) {  // several contacts (docs/contacts.md)
      auto spans = nlohmann::json::array();
      for (const auto& sp : c.sequences) spans.push_back({{"from", sp.from}, {"to", sp.to}, {"sequence", sp.sequence}});
      cols.back()["sequences"] = spans;
    }
  }
  j["columns"] = cols;
  return j.dump();
}

std::string StudyJson(const StudyResult& st, const Coordinate& x, const Coordinate& y) {
  nlohmann::json j;
  auto list = nlohmann::json::array();
  for (const auto& a : st.attractors) {
    nlohmann::json o = AttractorObject(a.attractor);
    o["basin_fraction"] = a.basin_fraction;
    o["basin_fraction_error"] = a.basin_fraction_error;
    o["example_initial_state"] = {{x.name, a.example.at(0)}, {y.name, a.example.at(1)}};
    // The Poincaré solver's orbit of the class (vibro extension).
    o["orbit_status"] = a.orbit.status;
    auto mu = nlohmann::json::array();
    for (const auto& m : a.orbit.multipliers) mu.push_back({m.real(), m.imag()});
    o["floquet_multipliers"] = mu;
    o["stable"] = a.orbit.stable ? nlohmann::json(*a.orbit.stable) : nlohmann::json(nullptr);
    o["merged_classes"] = a.orbit.merged;
    if (a.lyapunov) AddLyapunov(o, *a.lyapunov);
    list.push_back(o);
  }
  j["attractors"] = list;
  j["unresolved_fraction"] = st.unresolved_fraction;
  j["inadmissible_fraction"] = st.inadmissible_fraction;
  j["not_computed_fraction"] = st.pending_fraction;
  j["cells"] = st.cells;
  if (st.unresolved_lyapunov) {
    nlohmann::json u;
    u["example_initial_state"] = {{x.name, st.unresolved_example.at(0)}, {y.name, st.unresolved_example.at(1)}};
    AddLyapunov(u, *st.unresolved_lyapunov);
    j["unresolved_lyapunov"] = u;
  }
  return j.dump();
}

std::string SweepJson(const std::vector<SweepPoint>& sweep) {
  nlohmann::json j;
  auto pts = nlohmann::json::array();
  for (const auto& p : sweep) {
    nlohmann::json o = AttractorObject(p.attractor);
    o["value"] = p.value;
    o["direction"] = p.upward ? "up" : "down";
    o["x_B"] = p.x_B;
    o["v_B"] = p.v_B;
    if (p.status != "ok") {  // the run that ended the sweep
      o["status"] = p.status;
      o["message"] = p.message;
    }
    if (p.lyapunov) AddLyapunov(o, *p.lyapunov);
    pts.push_back(o);
  }
  j["points"] = pts;
  return j.dump();
}

std::string DiagramJson(const DiagramResult& d) {
  nlohmann::json j;
  j["param"] = d.param;
  j["from"] = d.from;
  j["to"] = d.to;
  j["status"] = d.status;
  j["duplicates"] = d.duplicates;
  j["seeds_tried"] = d.seeds_tried;
  j["cap_reached"] = d.cap_reached;
  j["seeds_left_out"] = d.seeds_left_out;
  j["switches_left_out"] = d.switches_left_out;
  j["seconds"] = {{"sweep", d.sweep_seconds},
                  {"search", d.search_seconds},
                  {"continuation", d.continuation_seconds},
                  {"switching", d.switching_seconds},
                  {"coverage", d.coverage_seconds}};
  auto branches = nlohmann::json::array();
  for (size_t k = 0; k < d.branches.size(); ++k) {
    const auto& b = d.branches[k];
    auto o = BranchObject(b.branch);
    o["index"] = k;
    o["origin"] = b.origin;
    o["parent"] = b.parent >= 0 ? nlohmann::json(b.parent) : nlohmann::json(nullptr);
    o["born_at"] = b.born_at;
    o["end_first"] = b.end_first;
    o["end_last"] = b.end_last;
    branches.push_back(std::move(o));
  }
  j["branches"] = branches;
  auto coverage = nlohmann::json::array();
  int uncovered = 0;
  for (const auto& c : d.coverage) {
    uncovered += c.branch < 0 ? 1 : 0;
    coverage.push_back({{"value", c.value},
                        {"direction", c.upward ? "up" : "down"},
                        {"source", c.source},
                        {"kind", c.kind},
                        {"period", c.period > 0 ? nlohmann::json(c.period) : nlohmann::json(nullptr)},
                        {"branch", c.branch >= 0 ? nlohmann::json(c.branch) : nlohmann::json(nullptr)},
                        {"distance", c.distance},
                        {"reason", c.reason}});
  }
  j["coverage"] = coverage;
  j["uncovered"] = uncovered;
  auto windows = nlohmann::json::array();
  for (const auto& w : d.uncovered_windows)
    windows.push_back({{"from", w.from}, {"to", w.to}, {"source", w.source}, {"count", w.count}, {"reason", w.reason}});
  j["uncovered_windows"] = windows;
  j["notes"] = d.notes;
  j["sweep"] = nlohmann::json::parse(SweepJson(d.sweep))["points"];
  return j.dump();
}

std::string CheckJson(const CheckReport& r) {
  nlohmann::json j;
  j["ok"] = r.ok;
  j["exact_kind"] = r.exact_kind;
  j["cvode_kind"] = r.cvode_kind;
  j["orbit_status"] = r.orbit_status;
  if (!r.quad_kind.empty()) j["quad_kind"] = r.quad_kind;
  auto rows = nlohmann::json::array();
  for (const auto& row : r.rows) {
    nlohmann::json o = {{"quantity", row.quantity}, {"exact", OrNull(row.exact)},
                        {"cvode", OrNull(row.cvode)}, {"orbit", OrNull(row.orbit)},
                        {"difference", row.difference}, {"tolerance", row.tolerance},
                        {"ok", row.ok}, {"note", row.note}};
    if (!r.quad_kind.empty()) o["quad"] = OrNull(row.quad);
    rows.push_back(o);
  }
  j["rows"] = rows;
  return j.dump();
}

std::string StoredRunJson(const StoredRun& run) {
  nlohmann::json j;
  j["status"] = run.status;
  j["message"] = run.message;
  j["engine"] = run.engine;
  j["chatter"] = run.chatter;
  j["created"] = run.created;
  j["vibro_version"] = run.version;
  j["git_commit"] = run.git_commit;
  j["command"] = run.command;
  j["groups"] = run.groups;
  j["rows"] = {{"events", run.events}, {"samples", run.samples}, {"sections", run.sections}};
  if (run.checkpoint) {
    const auto& c = run.checkpoint->counts;
    j["checkpoint"] = {{"period", run.checkpoint->clock.period},
                       {"counts", {{"impacts", c.impacts}, {"accumulations", c.accumulations},
                                   {"sticks", c.sticks}, {"releases", c.releases},
                                   {"grazings", c.grazings}}}};
  }
  j["attractor"] = run.attractor.kind.empty() ? nlohmann::json(nullptr) : AttractorObject(run.attractor);
  j["scene"] = run.scene_text;
  return j.dump();
}

std::string ModelJson(const System& s) {
  nlohmann::json j;
  j["frequencies"] = Array(s.omega());
  j["forcing"] = Array(s.forcing());
  j["contact"] = Array(s.contact());
  j["constrained_frequencies"] = Array(s.constrained().frequencies);
  if (auto r = s.static_reaction())
    j["static_reaction"] = *r;
  else
    j["static_reaction"] = nullptr;
  j["modes_kept"] = s.dof();
  j["damping_ratios"] = Array(s.damping());
  j["s_A"] = s.s_A();
  j["s_B"] = s.s_B();
  j["static_flexibility"] = s.flexibility();
  // Every contact (docs/contacts.md): as written, and in the modal coordinates.
  auto contacts = nlohmann::json::array();
  for (const ContactModel& k : s.contacts()) {
    contacts.push_back({{"dof", k.spec.dof >= 0 ? nlohmann::json(k.spec.dof) : nlohmann::json(nullptr)},
                        {"partner", k.spec.partner >= 0 ? nlohmann::json(k.spec.partner) : nlohmann::json(nullptr)},
                        {"side", k.spec.side == Side::kBelow ? "below" : "above"},
                        {"position", k.spec.position},
                        {"restitution", k.restitution},
                        {"stiffness", k.spec.compliance.compliant() ? nlohmann::json(k.spec.compliance.stiffness)
                                                                    : nlohmann::json(nullptr)},
                        {"damping", k.spec.compliance.damping},
                        {"separation", ToString(k.spec.compliance.separation)},
                        {"shape", Array(k.shape)},
                        {"contact", Array(k.contact)},
                        {"stop", k.stop},
                        {"s_A", k.s_A},
                        {"s_B", k.s_B},
                        {"constrained_frequencies", Array(k.constrained.frequencies)},
                        {"static_flexibility", k.flexibility}});
  }
  j["contacts"] = contacts;
  if (s.physical()) {
    // mode_shapes[i] = ψ_i over the physical DOFs (unit component at B for contact modes).
    auto shapes = nlohmann::json::array();
    for (Eigen::Index i = 0; i < s.mode_shapes().cols(); ++i)
      shapes.push_back(Array(s.mode_shapes().col(i)));
    j["mode_shapes"] = shapes;
    j["modal_masses"] = Array(s.modal_masses());
    auto seen = nlohmann::json::array();
    for (Eigen::Index i = 0; i < s.contact_shape().size(); ++i)
      seen.push_back(s.contact_shape()[i] > 0);
    j["contact_modes"] = seen;  // false: a node at B, out of the contact model
  }
  return j.dump();
}

}  // namespace vibro
