// The commands validate, score and partition as the CLI and the Python module share them
// (commands.hpp).
#include "frontend/commands.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "vibro/branch_csv.hpp"
#include "vibro/child_process.hpp"
#include "vibro/contact_sequence.hpp"
#include "vibro/events_csv.hpp"
#include "vibro/scene_file.hpp"
#include "vibro/system.hpp"

namespace vibro::frontend {

std::string NotANumericKey(const std::string& option, const std::string& key) {
  const std::string near = NearestSceneKey(key);
  if (!near.empty() && near != key) return fmt::format("{} {}: not a scene key; did you mean {}?", option, key, near);
  return fmt::format("{} {}: not a numeric key of the scene (give it in the scene or with --set {}=VALUE)",
                     option, key, key);
}

// ---- validate ----

namespace {

H5Table ValidationTable(const std::vector<ClaimedPoint>& claims,
                               const std::vector<PointCheck>& checks) {
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  const size_t N = checks.size();
  size_t m = 1, n = 1;
  for (const auto& c : checks) {
    m = std::max(m, c.orbit.multipliers.size());
    n = std::max(n, static_cast<size_t>(c.orbit.X.size()));
  }
  std::vector<double> value, distance, period, stable, sp, sim, t0, cp, cs, csp;
  std::vector<double> mu(N * m * 2, kNaN), X(N * n, kNaN), V(N * n, kNaN);
  std::vector<std::string> verdict, detail, sequence, claimed_sequence;
  for (size_t i = 0; i < N; ++i) {
    const auto& c = checks[i];
    const auto& o = c.orbit;
    const bool ok = o.status == "converged";
    value.push_back(c.value);
    verdict.push_back(c.verdict);
    detail.push_back(c.detail);
    sequence.push_back(ok ? o.sequence : "");
    claimed_sequence.push_back(claims[i].sequence);
    distance.push_back(c.distance.value_or(kNaN));
    period.push_back(ok ? o.summary.period.value_or(o.period) : kNaN);
    stable.push_back(ok ? (o.stable ? 1 : 0) : kNaN);
    sp.push_back(ok ? o.summary.sticking_fraction.value_or(kNaN) : kNaN);
    sim.push_back(c.simulated_distance.value_or(kNaN));
    t0.push_back(ok ? o.section_time : kNaN);
    for (size_t k = 0; k < o.multipliers.size(); ++k) {
      mu[(i * m + k) * 2] = o.multipliers[k].real();
      mu[(i * m + k) * 2 + 1] = o.multipliers[k].imag();
    }
    for (Eigen::Index k = 0; ok && k < o.X.size(); ++k) {
      X[i * n + static_cast<size_t>(k)] = o.X[k];
      V[i * n + static_cast<size_t>(k)] = o.V[k];
    }
    cp.push_back(claims[i].period ? *claims[i].period : kNaN);
    cs.push_back(claims[i].stable ? (*claims[i].stable ? 1.0 : 0.0) : kNaN);
    csp.push_back(claims[i].sticking_fraction.value_or(kNaN));
  }
  H5Table t;
  const auto col = [&](const char* name, const std::vector<double>& v) { t.arrays.push_back({name, {v.size()}, v}); };
  col("value", value);
  col("distance", distance);
  col("period", period);
  col("stable", stable);
  col("sticking_fraction", sp);
  col("simulated_distance", sim);
  col("section_time", t0);
  col("claimed_period", cp);
  col("claimed_stable", cs);
  col("claimed_sticking_fraction", csp);
  t.arrays.push_back({"multipliers", {N, m, 2}, mu});
  t.arrays.push_back({"X", {N, n}, X});
  t.arrays.push_back({"V", {N, n}, V});
  t.strings = {{"verdict", verdict}, {"detail", detail}, {"sequence", sequence}, {"claimed_sequence", claimed_sequence}};
  return t;
}

}  // namespace

namespace {

// The options of a validation, before any file is read (InputError).
void CheckValidationSpec(const LoadedScene& loaded, const ValidationSpec& a, Naming naming) {
  const auto opt = [&](const char* o) { return OptionName(naming, o); };
  if (!SceneNumber(loaded.text_as_run, a.param)) {
    const bool element = a.param.find('[') != std::string::npos;
    const std::string key = element ? a.param.substr(0, a.param.find('[')) : a.param;
    const std::string how = naming == Naming::kCli
                                ? (element ? "--set " + key + "=[...] (the whole array)" : "--set " + key + "=VALUE")
                                : (element ? "set={\"" + key + "\": [...]} (the whole array)"
                                           : "set={\"" + key + "\": VALUE}");
    throw InputError({fmt::format("{} {}: not a numeric key of the scene (give it in the scene or with {})",
                                  opt("--param"), a.param, how)});
  }
  std::vector<std::string> problems;
  if (!(a.tolerance > 0 && std::isfinite(a.tolerance)))
    problems.push_back(fmt::format("{} {}: expected a finite positive number", opt("--tolerance"), a.tolerance));
  if (!(a.sticking_tolerance > 0 && std::isfinite(a.sticking_tolerance)))
    problems.push_back(fmt::format("{} {}: expected a finite positive number", opt("--sticking-tolerance"),
                                   a.sticking_tolerance));
  if (a.period < 0) problems.push_back(fmt::format("{} {}: expected Q ≥ 1", opt("--period"), a.period));
  else CheckInteger(naming, "--period", a.period, kPeriodLimit, problems);
  if (!problems.empty()) throw InputError(problems);
}

}  // namespace

int ClaimedStateSize(const LoadedScene& loaded) {
  return loaded.scene.physical ? static_cast<int>(loaded.scene.physical->mass.rows())
                               : static_cast<int>(loaded.scene.modal->frequencies.size());
}

ValidationJob PrepareValidationTable(const SceneOrigin& origin, const LoadedScene& loaded, const ValidationSpec& a,
                                     std::vector<ClaimedPoint> claims,
                                     const std::function<std::string(const ClaimedPoint&)>& where, Naming naming,
                                     const std::atomic<bool>* stop) {
  CheckValidationSpec(loaded, a, naming);
  const int n = ClaimedStateSize(loaded);
  std::vector<std::string> problems;
  ValidationJob job;
  job.claims = std::move(claims);
  if (job.claims.empty()) throw InputError({"no points to validate"});
  // Every row's scene and state before anything is computed or written (bad input). A stop
  // request ends the preparation (rows are read at about 10 000 a second): the job is then
  // interrupted, with the rows prepared so far.
  for (size_t i = 0; i < job.claims.size(); ++i) {
    if (problems.size() >= 20) {
      problems.push_back("stopped checking the points after 20 problems");
      break;
    }
    if (stop && stop->load()) {
      if (!problems.empty()) break;
      job.interrupted = true;
      job.claims.resize(job.scenes.size());
      return job;
    }
    const ClaimedPoint& p = job.claims[i];
    if (p.displacement.size() != n || p.velocity.size() != n) {
      problems.push_back(fmt::format("{}: the state has {} displacements and {} velocities, the scene {} entries",
                                     where(p), p.displacement.size(), p.velocity.size(), n));
      job.scenes.push_back(loaded.scene);
      continue;
    }
    if (!std::isfinite(p.value)) {
      problems.push_back(fmt::format("{}: value {} is not a finite number", where(p), p.value));
      job.scenes.push_back(loaded.scene);
      continue;
    }
    // The claims, as the CSV reader checks them (a table from elsewhere is held to the same).
    if (p.period && !(*p.period >= 1 && *p.period <= 1000000))
      problems.push_back(fmt::format("{}: period {} is not a whole number of forcing periods in [1, 1e6]", where(p),
                                     *p.period));
    if (p.sticking_fraction && !(*p.sticking_fraction >= 0 && *p.sticking_fraction <= 1))
      problems.push_back(fmt::format("{}: sticking fraction {} is not in [0, 1]", where(p), *p.sticking_fraction));
    try {
      job.scenes.push_back(origin.Load({Assignment(a.param, p.value)}).scene);
    } catch (const InputError& e) {
      for (const auto& m : e.messages()) problems.push_back(fmt::format("{}: value {}: {}", where(p), p.value, m));
      job.scenes.push_back(loaded.scene);
      continue;
    }
    std::string why;
    const System sys(job.scenes.back());
    ClaimedStart(sys, job.scenes.back(), p, why);
    if (!why.empty()) problems.push_back(fmt::format("{}: {}", where(p), why));
    // A claimed contact sequence names contacts of the scene, which has several (docs/validation.md).
    if (!p.sequence.empty()) {
      if (sys.contact_count() < 2)
        problems.push_back(fmt::format("{}: sequence '{}': the scene has one contact; a contact sequence is checked "
                                       "on scenes with several [[contact]] tables (leave the cell empty)",
                                       where(p), p.sequence.substr(0, 80)));
      else if (!ParseContactSequence(p.sequence, sys.contact_count(), why))
        problems.push_back(fmt::format("{}: sequence: {}", where(p), why));
    }
  }
  if (!problems.empty()) throw InputError(problems);
  return job;
}

ValidationJob PrepareValidation(const SceneOrigin& origin, const LoadedScene& loaded, const ValidationSpec& a,
                                Naming naming, const std::atomic<bool>* stop) {
  CheckValidationSpec(loaded, a, naming);
  std::vector<ClaimedPoint> claims;
  try {
    claims = ReadBranchCsv(a.csv, ClaimedStateSize(loaded));
  } catch (const Interrupted&) {  // a stop request while the file is read: no point prepared
    ValidationJob job;
    job.interrupted = true;
    return job;
  }
  return PrepareValidationTable(
      origin, loaded, a, std::move(claims),
      [&a](const ClaimedPoint& p) { return fmt::format("{}:{}", a.csv, p.line); }, naming, stop);
}

Validation RunValidation(const ValidationJob& job, const ValidationSpec& spec, const std::atomic<bool>* stop,
                         const std::function<void(size_t, size_t)>& progress) {
  CheckTolerances tol;
  tol.distance = spec.tolerance;
  tol.sticking_fraction = spec.sticking_tolerance;
  Validation v;
  v.interrupted = job.interrupted;
  for (size_t i = 0; i < job.claims.size() && !v.interrupted; ++i) {
    if (stop && stop->load()) {
      v.interrupted = true;
      break;
    }
    PointCheck c = CheckPoint(job.scenes[i], job.claims[i], spec.kind, spec.period, tol);
    // A check cut short by the stop request (its runs end interrupted) is no verdict.
    if (stop && stop->load()) {
      v.interrupted = true;
      break;
    }
    v.checks.push_back(std::move(c));
    const std::string& verdict = v.checks.back().verdict;
    if (verdict == "undetermined") ++v.undetermined;
    else if (verdict != "confirmed") ++v.disagreements;
    if (progress) progress(i + 1, job.claims.size());
  }
  return v;
}

void FinishValidation(Hdf5Store& store, const ValidationJob& job, const Validation& v) {
  store.WriteTable("/validation", ValidationTable(job.claims, v.checks));
  RunResult r;
  r.status = v.interrupted ? RunStatus::kInterrupted : RunStatus::kOk;
  r.message = v.interrupted ? fmt::format("interrupted after {} of {} points, {} disagree", v.checks.size(),
                                          job.claims.size(), v.disagreements)
                            : fmt::format("{} of {} points disagree, {} undetermined", v.disagreements,
                                          v.checks.size(), v.undetermined);
  store.Finish(r, Attractor{});
}

// ---- score ----

namespace {
struct EventLog final : Observer {
  std::vector<Event> events;
  void OnEvent(const Event& e) override { events.push_back(e); }
};
}  // namespace

Scoring ScoreEventTable(const LoadedScene& loaded, const std::vector<TheirEvent>& theirs,
                        const std::function<std::string(const TheirEvent&)>& where, double window, double tolerance,
                        const std::atomic<bool>* stop, Naming naming) {
  std::vector<std::string> problems;
  if (!(window > 0 && std::isfinite(window)))
    problems.push_back(fmt::format("{} {}: expected a finite positive number", OptionName(naming, "--window"), window));
  if (!(tolerance > 0 && std::isfinite(tolerance)))
    problems.push_back(
        fmt::format("{} {}: expected a finite positive number", OptionName(naming, "--tolerance"), tolerance));
  if (!problems.empty()) throw InputError(problems);
  Scoring s;
  s.scene = loaded.scene;
  s.scene.run.samples_per_period = 0;
  const System sys(s.scene);
  const double T = sys.period();
  // vibro runs the whole scene, and their events must lie within it (bad input otherwise).
  const double t_end = s.scene.initial_time + static_cast<double>(s.scene.run.periods) * T;
  problems = EventTableProblems(theirs, s.scene.initial_time, t_end, T, window, where);
  if (theirs.empty()) problems.push_back("no events to score");
  // Several contacts: the contacts named, every row's or none, each one of the scene's.
  const int m = sys.contact_count();
  const TheirEvent* without = nullptr;
  bool named = false;
  for (const auto& e : theirs) {
    if (problems.size() >= 40) break;
    if (!e.contact) {
      without = without ? without : &e;
      continue;
    }
    named = true;
    if (*e.contact >= m)
      problems.push_back(fmt::format("{}: contact {}: the scene has {} contact{} (0 to {})", where(e), *e.contact, m,
                                     m == 1 ? "" : "s", m - 1));
  }
  if (named && without)
    problems.push_back(fmt::format("{}: no contact: give the contact of every event, or of none", where(*without)));
  if (!problems.empty()) throw InputError(problems);
  EventLog log;
  SimulationOptions opt;
  opt.observers = {&log};
  opt.stop_requested = stop;
  s.run = Simulate(sys, s.scene, opt);
  ScoreOptions so;
  so.window = window;
  so.tolerance = tolerance;
  so.t_end = t_end;
  s.report = ScoreEvents(log.events, theirs, T, so);
  return s;
}

Scoring ScoreEventsCsv(const LoadedScene& loaded, const std::string& csv, double window, double tolerance,
                       const std::atomic<bool>* stop, Naming naming) {
  const auto theirs = ReadEventsCsv(csv);
  return ScoreEventTable(
      loaded, theirs, [&csv](const TheirEvent& e) { return fmt::format("{}:{}", csv, e.line); }, window, tolerance,
      stop, naming);
}

// ---- partition ----

PartitionRequest PartitionRequestFor(const SceneOrigin& origin, const LoadedScene& loaded, const PartitionSpec& a,
                                     Naming naming, std::function<void(double)> on_scene) {
  const auto opt = [&](const char* o) { return OptionName(naming, o); };
  std::vector<std::string> problems;
  if (a.params.size() != 2) problems.push_back(opt("--params") + ": expected KEY1,KEY2");
  if (a.range1.size() != 2 || !(a.range1[0] < a.range1[1]))
    problems.push_back(opt("--range1") + ": expected A,B with A < B");
  if (a.range2.size() != 2 || !(a.range2[0] < a.range2[1]))
    problems.push_back(opt("--range2") + ": expected C,D with C < D");
  CheckInteger(naming, "--steps1", a.steps1, kSteps1Limit, problems);
  CheckInteger(naming, "--period", a.period, kPeriodLimit, problems);
  CheckInteger(naming, "--threads", a.threads, kThreadsLimit, problems);
  if (a.levels.empty()) problems.push_back(opt("--sticking-fraction") + ": expected S1,S2,... in (0, 1)");
  for (double s : a.levels)
    if (!(s > 0 && s < 1)) problems.push_back(fmt::format("{} {}: not in (0, 1)", opt("--sticking-fraction"), s));
  std::optional<double> start2 = a.from2;
  if (a.params.size() == 2) {
    for (const auto& k : a.params)
      if (!SceneNumber(loaded.text_as_run, k)) problems.push_back(NotANumericKey(opt("--params"), k));
    if (!start2) start2 = SceneNumber(loaded.text_as_run, a.params[1]);
  }
  if (start2 && a.range2.size() == 2 && !(*start2 >= a.range2[0] && *start2 <= a.range2[1]))
    problems.push_back(fmt::format("{} {}: outside {}", opt("--from2"), *start2, opt("--range2")));
  if (!problems.empty()) throw InputError(problems);
  PartitionRequest req;
  req.scene_at = [origin, key1 = a.params[0], key2 = a.params[1], on_scene = std::move(on_scene)](double v1,
                                                                                                    double v2) {
    if (on_scene) on_scene(v1);
    SceneOrigin at = origin;
    at.sets.push_back(Assignment(key1, v1));
    return SceneWith(at, key2, v2);
  };
  for (long long i = 0; i <= a.steps1; ++i)
    req.values1.push_back(a.range1[0] + (a.range1[1] - a.range1[0]) * static_cast<double>(i) /
                                            static_cast<double>(a.steps1));
  // The corners of range1 at the start value must be valid scenes (bad input before anything is
  // written); values of KEY2 outside its valid range just end a column's branch.
  for (double v1 : {a.range1[0], a.range1[1]}) req.scene_at(v1, *start2);
  req.start2 = *start2;
  req.lo2 = a.range2[0];
  req.hi2 = a.range2[1];
  req.levels = a.levels;
  req.orbit.period = static_cast<int>(a.period);
  req.threads = static_cast<int>(a.threads);
  return req;
}

void FinishPartition(Hdf5Store& store, const PartitionSpec& spec, const std::vector<PartitionColumn>& columns,
                     bool interrupted) {
  store.WritePartition(spec.params[0], spec.params[1], spec.levels, columns);
  RunResult r;
  r.status = interrupted ? RunStatus::kInterrupted : RunStatus::kOk;
  store.Finish(r, NoAttractor());
}

}  // namespace vibro::frontend
