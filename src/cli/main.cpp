// The `vibro` command (docs/cli.md; exit codes and JSON in docs/output.md). The only file that includes CLI11.
//
// Exit codes: 0 success · 1 internal error · 2 bad input · 3 numerical failure · 130 interrupted.
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "cli/stop_signals.hpp"
#include "vibro/attractor.hpp"
#include "vibro/check.hpp"
#include "vibro/continuation.hpp"
#include "vibro/distribute.hpp"
#include "vibro/studies.hpp"
#include "vibro/hdf5_store.hpp"
#include "vibro/hdf5_branch.hpp"
#include "vibro/orbit_from_state.hpp"
#include "vibro/poincare.hpp"
#include "vibro/scene_file.hpp"
#include "vibro/simulator.hpp"
#include "vibro/summary_json.hpp"
#include "vibro/system.hpp"
#include "cli/progress.hpp"
#include "cli/text_format.hpp"
#include "cli/cli_common.hpp"

#include "cli/plot_script.hpp"
#include "frontend/frontend.hpp"

namespace {

using vibro::frontend::HeaderOf;
using vibro::frontend::SceneWith;
using vibro::frontend::WriteOrbit;

constexpr int kExitInternal = 1;
constexpr int kExitBadInput = 2;
constexpr int kExitNumerical = 3;
constexpr int kExitInterrupted = 130;
constexpr int kExitDisagree = 4;  // vibro check: the methods disagree beyond tolerance

// A number option must be finite: nan, inf and values that overflow to inf are bad input (exit 2),
// refused before anything is computed or written.
const CLI::Validator kFinite(
    [](std::string& text) -> std::string {
      char* end = nullptr;
      const double v = std::strtod(text.c_str(), &end);
      if (end == text.c_str() || !std::isfinite(v)) return "expected a finite number, got " + text;
      return {};
    },
    "FINITE");

// Set by SIGINT/SIGTERM (cli/stop_signals.hpp); polled by every long loop.
const std::atomic<bool>& g_stop_requested = vibro::cli::StopFlag();

std::string Vec(const Eigen::VectorXd& v) {
  std::string s = "[";
  for (Eigen::Index i = 0; i < v.size(); ++i) s += fmt::format("{}{:.10g}", i ? ", " : "", v[i]);
  return s + "]";
}

int RunModel(const std::string& path, const std::vector<std::string>& sets, bool json) {
  const auto loaded = vibro::LoadScene(path, sets);
  const vibro::System sys(loaded.scene);
  if (json) {
    fmt::print("{}\n", vibro::ModelJson(sys));
    return 0;
  }
  fmt::print("scene               {}{}\n", path,
             loaded.scene.title.empty() ? "" : "  (" + loaded.scene.title + ")");
  fmt::print("form                {}, {} mode(s) kept\n", sys.physical() ? "physical" : "modal",
             sys.dof());
  fmt::print("frequencies ω_i     {}\n", Vec(sys.omega()));
  fmt::print("forcing T_A         {}\n", Vec(sys.forcing()));
  fmt::print("contact T_B         {}\n", Vec(sys.contact()));
  if (sys.damped()) fmt::print("damping ratios ζ_i  {}\n", Vec(sys.damping()));
  fmt::print("s_A, s_B            {:.10g}, {:.10g}\n", sys.s_A(), sys.s_B());
  fmt::print("constrained ω'_k    {}\n", Vec(sys.constrained().frequencies));
  fmt::print("static flexibility  {:.10g}\n", sys.flexibility());
  if (auto r = sys.static_reaction())
    fmt::print("static reaction     {:.10g}\n", *r);
  else
    fmt::print("static reaction     none (clearance)\n");
  fmt::print("stop x0, r          {:.10g}, {:.10g}\n", sys.stop(), sys.restitution());
  fmt::print("excitation f, ω, T  {:.10g}, {:.10g}, {:.10g}\n", sys.amplitude(), sys.frequency(),
             sys.period());
  if (sys.physical()) {
    for (int i = 0; i < sys.dof(); ++i)
      fmt::print("mode shape ψ_{}{}     {}\n", i + 1,
                 sys.contact_shape()[i] > 0 ? "" : " (node at B)",
                 Vec(sys.mode_shapes().col(i)));
  }
  return 0;
}

// An argument as a POSIX shell reads it back.
std::string ShellQuoted(const std::string& arg) {
  if (!arg.empty() && arg.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789"
                                            "_-+=/.,:@%") == std::string::npos)
    return arg;
  std::string q = "'";
  for (char c : arg) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

// restitution: NaN when unknown (then the velocities after impact are not printed).
void PrintAttractor(const vibro::Attractor& a, double restitution = std::nan("")) {
  fmt::print("{}", vibro::cli::AttractorText(a, restitution));
}

int ExitCode(vibro::RunStatus s) {
  switch (s) {
    case vibro::RunStatus::kOk: return 0;
    case vibro::RunStatus::kNumericalFailure: return kExitNumerical;
    case vibro::RunStatus::kInterrupted: return kExitInterrupted;
    case vibro::RunStatus::kUndetermined: return kExitNumerical;
  }
  return kExitInternal;
}

int RunSimulate(const std::string& path, const std::vector<std::string>& sets, bool json,
                const std::string& out, bool resume) {
  const auto loaded = vibro::LoadScene(path, sets);
  const vibro::System sys(loaded.scene);
  vibro::AttractorRecorder recorder(sys, loaded.scene);
  vibro::SimulationOptions options;
  options.observers.push_back(&recorder);
  options.stop_requested = &g_stop_requested;

  std::unique_ptr<vibro::Hdf5Store> store;
  vibro::StoredRun stored;
  if (resume && out.empty()) throw vibro::InputError({"--resume needs --out FILE.h5 (the file to continue)"});
  if (!out.empty()) {
    if (resume) {
      store = vibro::Hdf5Store::Resume(out, HeaderOf(loaded, sys), stored);
      options.resume_from = &*stored.checkpoint;
      // Give the classification the history it would have had.
      for (size_t i = 0; i < stored.tail_section_clocks.size(); ++i) {
        const auto& c = stored.tail_section_clocks[i];
        recorder.OnSection({c, loaded.scene.initial_time + static_cast<double>(c.period) * sys.period(),
                            stored.tail_section_X[i], stored.tail_section_V[i],
                            sys.ContactDisplacement(stored.tail_section_X[i]),
                            stored.tail_section_modes[i]});
      }
      for (const auto& e : stored.tail_events) recorder.OnEvent(e);
    } else {
      store = vibro::Hdf5Store::Create(out, HeaderOf(loaded, sys));
    }
    options.observers.push_back(store.get());
  }

  std::optional<vibro::cli::Progress> progress(std::in_place, "simulate", json);
  vibro::cli::PeriodProgress periods(*progress, loaded.scene.run.periods,
                                     stored.checkpoint ? stored.checkpoint->clock.period : 0);
  if (progress->active()) options.observers.push_back(&periods);
  const auto result = vibro::Simulate(sys, loaded.scene, options);
  progress.reset();
  const auto attractor = recorder.Classify();
  if (store) {
    const vibro::cli::FinalWrite writing;
    store->Finish(result, attractor);
    store.reset();
  }

  if (json) {
    fmt::print("{}\n", vibro::SimulationJson(loaded.scene, result, attractor));
  } else {
    fmt::print("scene        {}{}\n", path,
               loaded.scene.title.empty() ? "" : "  (" + loaded.scene.title + ")");
    fmt::print("engine       {}, {} precision, chatter {}\n",
               vibro::ToString(loaded.scene.run.engine),
               vibro::ToString(loaded.scene.run.precision),
               vibro::ToString(loaded.scene.run.chatter));
    fmt::print("status       {}{}\n", vibro::ToString(result.status),
               result.message.empty() ? "" : ": " + result.message);
    fmt::print("t_end        {:.10g} ({} periods)\n", result.t_end, result.end.period);
    fmt::print("events       {} impacts, {} accumulations, {} sticks, {} releases, {} grazings\n",
               result.counts.impacts, result.counts.accumulations, result.counts.sticks,
               result.counts.releases, result.counts.grazings);
    if (result.chatter.accumulations_predicted + result.chatter.impacts_followed > 0)
      fmt::print("chattering   {} accumulation points predicted (largest estimated error {:.2g} T, "
                 "target {:.2g} T), {} impacts followed before a prediction was good enough\n",
                 result.chatter.accumulations_predicted, result.chatter.max_estimated_error,
                 vibro::ChatterTolerance(loaded.scene.run), result.chatter.impacts_followed);
    PrintAttractor(attractor, loaded.scene.restitution);
    if (loaded.scene.run.engine == vibro::Engine::kCvode)
      fmt::print("cvode        {} ({}), rtol {:g}, atol {:g}: {} steps, {} rhs, {} root evals, "
                 "{} re-initialisations\n",
                 vibro::ToString(loaded.scene.run.method), "SUNDIALS 6.4", loaded.scene.run.rtol,
                 loaded.scene.run.atol, result.solver.steps, result.solver.rhs_evals,
                 result.solver.root_evals, result.solver.reinits);
    if (store)
      fmt::print("output       {}{} ({} flushes, {:.3f} s writing)\n", out, resume ? " (resumed)" : "",
                 store->stats().flushes, store->stats().flush_seconds);
  }
  if (result.status != vibro::RunStatus::kOk)
    fmt::print(stderr, "vibro: {}: {}\n", vibro::ToString(result.status), result.message);
  return ExitCode(result.status);
}

int RunOrbit(const std::string& path, const std::vector<std::string>& sets, bool json,
             const vibro::OrbitRequest& req, const std::string& out) {
  const auto loaded = vibro::LoadScene(path, sets);
  const vibro::System sys(loaded.scene);
  if (!out.empty()) vibro::Hdf5Store::Create(out, HeaderOf(loaded, sys)).reset();  // fail early
  // An orbit is found whole or not at all: a stop request removes the unfilled file and leaves.
  vibro::cli::DiscardOnStop(out);
  const auto orbit = vibro::SolveOrbit(sys, loaded.scene, req);
  vibro::cli::KeepOnStop();
  const bool converged = orbit.status == "converged";
  if (!out.empty() && converged) {
    const vibro::cli::FinalWrite writing;
    WriteOrbit(out, loaded, sys, orbit);
  } else if (!out.empty()) {
    const vibro::cli::FinalWrite writing;
    vibro::frontend::WriteOrbitFailure(out, loaded, sys, orbit);
  }
  if (json) {
    fmt::print("{}\n", vibro::OrbitJson(orbit, req.kind));
  } else {
    fmt::print("status       {}{}\n", orbit.status, orbit.message.empty() ? "" : ": " + orbit.message);
    fmt::print("period       {} (Newton: {} iterations, residual {:.2e})\n", orbit.period,
               orbit.newton_iterations, orbit.residual);
    if (orbit.distance_from_start)
      fmt::print("from start   distance {:.3g} ({})\n", *orbit.distance_from_start,
                 req.transient_periods > 0 ? fmt::format("after a transient of {} periods", req.transient_periods)
                                           : "Newton started at the start state");
    PrintAttractor(orbit.summary, loaded.scene.restitution);
    const std::string mu = vibro::cli::FormatMultipliers(orbit.multipliers);
    fmt::print("multipliers  {}\n", !mu.empty()                     ? mu
                                     : orbit.status == "converged" ? "none (superstable: one-DOF sticking)"
                                                                   : "-");
    fmt::print("stable       {}\n", !converged ? "-" : orbit.stable ? "yes" : "no");
  }
  if (!converged) {
    const bool sticking = req.kind == vibro::OrbitKind::kSticking, impact = req.kind == vibro::OrbitKind::kImpact;
    std::string hint = "vibro: try ";
    if (sticking && orbit.reached == "impact-periodic") hint += "--kind impact (the attractor has impacts and no sticking), ";
    if (impact && orbit.reached == "sticking-periodic") hint += "--kind sticking (the attractor sticks), ";
    hint += req.transient_periods > 0
                ? "--guess PHASE[,VELOCITY], --period Q, or --transient 0 from a state on the orbit "
                  "([initial], or --set initial.time=T --set initial.displacement=[...] --set initial.velocity=[...])"
                : "--period Q, another start state, or --transient N to start Newton after N periods";
    fmt::print(stderr, "{}\n", hint);
  }
  return converged ? 0 : kExitNumerical;
}

int RunCheck(const std::string& path, const std::vector<std::string>& sets, bool json,
             bool with_quad) {
  const auto loaded = vibro::LoadScene(path, sets);
  const vibro::System sys(loaded.scene);
  vibro::cli::DiscardOnStop("");  // nothing partial to keep
  const auto report = vibro::CrossCheck(sys, loaded.scene, with_quad);
  vibro::cli::KeepOnStop();
  if (json) {
    fmt::print("{}\n", vibro::CheckJson(report));
  } else {
    const auto cell = [](const std::optional<double>& v) {
      return v ? fmt::format("{:>18.12g}", *v) : fmt::format("{:>18}", "-");
    };
    fmt::print("{:<40} {:>18} {:>18} {:>18}{} {:>10} {:>10}  {}\n", "quantity", "exact", "cvode",
               "poincare", with_quad ? fmt::format(" {:>18}", "quad") : "", "max diff",
               "tolerance", "");
    for (const auto& r : report.rows) {
      fmt::print("{:<40} {} {} {}{} {:>10.2e} {:>10.2e}  {}{}\n", r.quantity, cell(r.exact),
                 cell(r.cvode), cell(r.orbit), with_quad ? " " + cell(r.quad) : "", r.difference,
                 r.tolerance, r.ok ? "ok" : "FAIL", r.note.empty() ? "" : "  " + r.note);
    }
    fmt::print("{}\n", report.ok ? "agreement: ok" : "agreement: FAILED (beyond tolerance)");
  }
  return report.ok ? 0 : kExitDisagree;
}

// The message for a --param KEY the scene has no number at, with the nearest known key.
std::string NotANumericKey(const std::string& option, const std::string& key) {
  const std::string near = vibro::NearestSceneKey(key);
  if (!near.empty() && near != key) return fmt::format("{} {}: not a scene key; did you mean {}?", option, key, near);
  return fmt::format("{} {}: not a numeric key of the scene (give it in the scene or with --set {}=VALUE)",
                     option, key, key);
}

int RunContinue(const std::string& path, std::vector<std::string> sets, bool json,
                const std::string& key, double to, double step, int max_points,
                vibro::OrbitRequest orbit, const std::string& out, const std::string& restart_file,
                long long restart_point) {
  if (!restart_file.empty()) {
    // Restart from a stored point: its parameter value, period and section state (Newton from
    // there, no transient).
    const auto pt = vibro::ReadBranchPoint(restart_file, restart_point);
    if (pt.param != key)
      throw vibro::InputError({fmt::format("--from {}: the branch varies {}, not --param {}", restart_file,
                                           pt.param, key)});
    sets.push_back(fmt::format("{}={:.17g}", key, pt.value));
    orbit.start = vibro::InitialOverride{pt.section_time, pt.X, pt.V};
    orbit.transient_periods = 0;
    orbit.period = pt.period;
  }
  const auto loaded = vibro::LoadScene(path, sets);
  const auto from = vibro::SceneNumber(loaded.text_as_run, key);
  if (!from)
    throw vibro::InputError({key.find('[') == std::string::npos
                                 ? NotANumericKey("--param", key)
                                 : fmt::format("--param {}: not a numeric entry of the scene (give the "
                                               "array in the scene or with --set {}=[...])",
                                               key, key.substr(0, key.find('[')))});
  vibro::ContinuationRequest req;
  req.scene_at = [&](double v) { return SceneWith(path, sets, key, v); };
  req.from = *from;
  req.to = to;
  req.step = step;
  req.max_points = max_points;
  req.orbit = orbit;
  req.stop_requested = &g_stop_requested;
  vibro::cli::Progress progress("continue", json);
  if (progress.active())
    req.progress = [&](size_t points, double value) {
      progress.Update(static_cast<long long>(points), max_points, fmt::format("{} = {:.10g}", key, value));
    };
  const vibro::System sys(loaded.scene);
  std::unique_ptr<vibro::Hdf5Store> store;
  if (!out.empty()) store = vibro::Hdf5Store::Create(out, HeaderOf(loaded, sys));  // fails early
  auto branch = vibro::Continue(req);
  branch.param = key;
  // The file's status and the exit code say the same thing (docs/output.md).
  const vibro::RunStatus status = branch.status == "interrupted" ? vibro::RunStatus::kInterrupted
                                  : branch.status == "ok"        ? vibro::RunStatus::kOk
                                                                 : vibro::RunStatus::kNumericalFailure;
  if (store) {
    const vibro::cli::FinalWrite writing;
    store->WriteBranch(branch);
    vibro::RunResult r;
    r.status = status;
    r.message = branch.end;
    store->Finish(r, vibro::frontend::NoAttractor());  // a branch has no single attractor (the points are in /branch)
    store.reset();
  }
  if (branch.status == "no-orbit")
    fmt::print(stderr, "vibro: try {}--period Q, or --from FILE.h5 --point K to start from a stored branch point\n",
               orbit.kind == vibro::OrbitKind::kSticking   ? "--kind impact or --kind auto, "
               : orbit.kind == vibro::OrbitKind::kImpact ? "--kind sticking or --kind auto, "
                                                         : "--kind sticking|impact, ");
  if (json) {
    fmt::print("{}\n", vibro::BranchJson(branch));
  } else {
    fmt::print("{:>16} {:>12} {:>8} {:>12}  {}\n", key, "SP", "stable", "max|mu|", "events");
    for (const auto& p : branch.points) {
      double lead = 0;
      for (const auto& m : p.multipliers) lead = std::max(lead, std::abs(m));
      fmt::print("{:>16.10g} {:>12.8f} {:>8} {:>12.6g}  {}\n", p.value,
                 p.summary.sticking_fraction.value_or(0.0), p.stable ? "yes" : "no", lead, p.signature);
    }
    for (const auto& b : branch.bifurcations)
      fmt::print("bifurcation  {} at {} = {:.15g}: {}\n", b.kind, key, b.value, b.detail);
    fmt::print("end          {}\n", branch.end);
  }
  return ExitCode(status);
}

struct PartitionArgs {
  std::vector<std::string> params;
  std::vector<double> range1, range2, levels;
  int steps1 = 20, period = 0, threads = 0;
  std::optional<double> from2;
  std::string out;
};

int RunPartition(const std::string& path, const std::vector<std::string>& sets, bool json,
                 const PartitionArgs& a) {
  const auto loaded = vibro::LoadScene(path, sets);
  std::vector<std::string> problems;
  if (a.params.size() != 2) problems.push_back("--params: expected KEY1,KEY2");
  if (a.range1.size() != 2 || !(a.range1[0] < a.range1[1]))
    problems.push_back("--range1: expected A,B with A < B");
  if (a.range2.size() != 2 || !(a.range2[0] < a.range2[1]))
    problems.push_back("--range2: expected C,D with C < D");
  if (a.steps1 < 1) problems.push_back("--steps1: expected N ≥ 1");
  if (a.levels.empty()) problems.push_back("--sticking-fraction: expected S1,S2,... in (0, 1)");
  for (double s : a.levels)
    if (!(s > 0 && s < 1)) problems.push_back(fmt::format("--sticking-fraction {}: not in (0, 1)", s));
  std::optional<double> start2 = a.from2;
  if (a.params.size() == 2) {
    for (const auto& k : a.params)
      if (!vibro::SceneNumber(loaded.text_as_run, k))
        problems.push_back(NotANumericKey("--params", k));
    if (!start2) start2 = vibro::SceneNumber(loaded.text_as_run, a.params[1]);
  }
  if (start2 && a.range2.size() == 2 && !(*start2 >= a.range2[0] && *start2 <= a.range2[1]))
    problems.push_back(fmt::format("--from2 {}: outside --range2", *start2));
  if (!problems.empty()) throw vibro::InputError(problems);
  vibro::PartitionRequest req;
  // Progress: columns started (each column asks for scenes at its own value of KEY1).
  vibro::cli::Progress progress("columns", json);
  std::mutex seen_mutex;
  std::vector<double> seen;
  req.scene_at = [&](double v1, double v2) {
    if (progress.active()) {
      std::lock_guard<std::mutex> lock(seen_mutex);
      if (std::find(seen.begin(), seen.end(), v1) == seen.end()) seen.push_back(v1);
      progress.Update(static_cast<long long>(seen.size()) - 1, a.steps1 + 1LL);
    }
    std::vector<std::string> s = sets;
    s.push_back(fmt::format("{}={:.17g}", a.params[0], v1));
    return SceneWith(path, s, a.params[1], v2);
  };
  for (int i = 0; i <= a.steps1; ++i)
    req.values1.push_back(a.range1[0] + (a.range1[1] - a.range1[0]) * i / a.steps1);
  // The corners of --range1 at the start value must be valid scenes (bad input, exit 2, before
  // anything is written); values of KEY2 outside its valid range just end a column's branch.
  for (double v1 : {a.range1[0], a.range1[1]}) req.scene_at(v1, *start2);
  req.start2 = *start2;
  req.lo2 = a.range2[0];
  req.hi2 = a.range2[1];
  req.levels = a.levels;
  req.orbit.period = a.period;
  req.threads = a.threads;
  req.stop_requested = &g_stop_requested;
  const vibro::System sys(loaded.scene);
  std::unique_ptr<vibro::Hdf5Store> store;
  if (!a.out.empty()) store = vibro::Hdf5Store::Create(a.out, HeaderOf(loaded, sys));  // fails early
  const auto columns = vibro::Partition(req);
  const bool interrupted = g_stop_requested.load();
  if (store) {
    const vibro::cli::FinalWrite writing;
    store->WritePartition(a.params[0], a.params[1], a.levels, columns);
    vibro::RunResult r;
    r.status = interrupted ? vibro::RunStatus::kInterrupted : vibro::RunStatus::kOk;
    store->Finish(r, vibro::frontend::NoAttractor());
    store.reset();
  }
  if (json) {
    fmt::print("{}\n", vibro::PartitionJson(a.params[0], a.params[1], a.levels, columns));
  } else {
    for (const auto& c : columns) {
      fmt::print("{} = {:.10g}: {}\n", a.params[0], c.value1, c.status);
      for (const auto& x : c.crossings)
        fmt::print("  sticking fraction {:<6g} at {} = {:.12g}\n", x.level, a.params[1], x.value);
      for (const auto& b : c.bifurcations)
        fmt::print("  {:<17} at {} = {:.12g}\n", b.kind, a.params[1], b.value);
    }
  }
  return interrupted ? kExitInterrupted : 0;
}

struct StudyArgs {
  std::string x = "x_B", y = "v_B";
  std::vector<double> x_range, y_range;
  std::vector<int> grid{64, 64};
  long long samples = 200;
  unsigned long long seed = 1;
  int threads = 0;
  std::string out;
  bool resume = false;
  bool full_periods = false;
};

int RunStudyCommand(const std::string& path, const std::vector<std::string>& sets, bool json,
                    const StudyArgs& args, bool basin) {
  const auto loaded = vibro::LoadScene(path, sets);
  const vibro::System sys(loaded.scene);
  std::vector<std::string> problems;
  for (const auto& [opt, name] : {std::pair{"--x", args.x}, std::pair{"--y", args.y}})
    if (auto p = vibro::CheckCoordinate(sys, name); !p.empty())
      problems.push_back(fmt::format("{} {}: {}", opt, name, p));
  const auto range = [&](const std::vector<double>& r, const std::string& name, const char* opt) {
    return vibro::frontend::StudyCoordinate(sys, name, r, opt, problems);
  };
  const auto cx = range(args.x_range, args.x, "--x-range");
  const auto cy = range(args.y_range, args.y, "--y-range");
  if (basin && (args.grid.size() != 2 || args.grid[0] < 1 || args.grid[1] < 1))
    problems.push_back("--grid: expected NX,NY with NX, NY ≥ 1");
  else if (basin && static_cast<long long>(args.grid[0]) * args.grid[1] > (1LL << 24))
    problems.push_back(fmt::format("--grid {},{}: at most {} cells (2^24) in one study", args.grid[0],
                                   args.grid[1], 1LL << 24));
  if (!basin && args.samples < 1) problems.push_back("--samples: expected N ≥ 1");
  if (args.resume && args.out.empty()) problems.push_back("--resume needs --out FILE.h5 (the study to continue)");
  if (!problems.empty()) throw vibro::InputError(problems);
  const auto points = basin ? vibro::GridPoints(cx, cy, args.grid[0], args.grid[1])
                            : vibro::RandomPoints(cx, cy, args.samples, args.seed);
  const vibro::Hdf5Store::StudyGrid grid{cx, cy, basin ? args.grid[0] : static_cast<int>(points.size()),
                                         basin ? args.grid[1] : 1, !args.full_periods};

  // Every process of an MPI job gets here; rank 0 alone reads and writes the file and prints.
  const vibro::Distribution dist;
  std::vector<vibro::CellResult> cells(points.size());
  std::unique_ptr<vibro::Hdf5Store> store;
  std::optional<vibro::InputError> file_problem;
  if (dist.root() && !args.out.empty()) {
    try {
      if (args.resume) {
        store = vibro::Hdf5Store::ResumeStudy(args.out, HeaderOf(loaded, sys), grid, cells);
      } else {
        store = vibro::Hdf5Store::Create(args.out, HeaderOf(loaded, sys));
        store->BeginStudy(grid);
      }
    } catch (const vibro::InputError& e) {
      file_problem = e;
    } catch (const std::exception& e) {  // every rank must hear of it (no rank left waiting)
      file_problem = vibro::InputError({fmt::format("{}: cannot write the study: {}", args.out, e.what())});
    }
  }
  if (dist.Any(file_problem.has_value())) {
    if (file_problem) throw *file_problem;
    return kExitBadInput;  // reported by rank 0
  }

  vibro::StudyOptions opt;
  opt.threads = args.threads;
  opt.stop_requested = &g_stop_requested;
  if (args.full_periods) opt.settle_remainder = 0;
  // Stable orbits known before the cells run (a pilot grid, the same on every rank).
  if (!args.full_periods) opt.known = vibro::KnownOrbits(sys, loaded.scene, cx, cy, opt);
  // Progress of the cells (not of the pilot) on rank 0's terminal.
  std::optional<vibro::cli::Progress> progress(std::in_place, "cells", json || !dist.root());
  if (progress->active())
    opt.progress = [&](long long done, long long total) { progress->Update(done, total); };
  vibro::RunPendingCells(sys, loaded.scene, cx, cy, points, cells, opt, dist,
                         [&](const std::vector<size_t>& batch) {
                           if (store) store->WriteCells(batch, cells);
                         });
  opt.progress = nullptr;
  progress.reset();
  const bool interrupted = dist.Any(g_stop_requested.load());
  if (!dist.root()) return interrupted ? kExitInterrupted : 0;
  const auto study = vibro::LabelCells(sys, loaded.scene, points, cells, opt);
  if (store) try {
    const vibro::cli::FinalWrite writing;
    vibro::frontend::FinishStudy(*store, study, grid, interrupted);
    store.reset();
  } catch (const std::runtime_error& e) {  // a resumed file whose damage shows only when written
    fmt::print(stderr, "vibro: cannot write the study to {}: {}; the cells computed are in its /basin/cells\n",
               args.out, e.what());
    return kExitInternal;
  }
  if (json) {
    fmt::print("{}\n", vibro::StudyJson(study, cx, cy));
  } else {
    fmt::print("{} cells over {} ∈ [{}, {}] × {} ∈ [{}, {}]{}\n", study.cells, cx.name, cx.from, cx.to,
               cy.name, cy.from, cy.to, dist.size() > 1 ? fmt::format(" ({} MPI ranks)", dist.size()) : "");
    for (size_t k = 0; k < study.attractors.size(); ++k) {
      const auto& a = study.attractors[k];
      fmt::print("attractor {}: basin fraction {:.4f} ± {:.4f}, example ({}, {}) = ({:.6g}, {:.6g})\n",
                 k, a.basin_fraction, a.basin_fraction_error, cx.name, cy.name, a.example[0], a.example[1]);
      fmt::print("{}", vibro::cli::AttractorText(a.attractor, loaded.scene.restitution, "  "));
      const std::string mu = vibro::cli::FormatMultipliers(a.orbit.multipliers, 4);
      fmt::print("  orbit        {}{}{}{}\n", a.orbit.status,
                 a.orbit.stable ? (*a.orbit.stable ? ", stable" : ", unstable") : "",
                 mu.empty() ? "" : ", multipliers " + mu,
                 a.orbit.merged > 1 ? fmt::format(" ({} cell classes merged)", a.orbit.merged) : "");
    }
    fmt::print("unresolved fraction {:.4f}, inadmissible fraction {:.4f}{}\n", study.unresolved_fraction,
               study.inadmissible_fraction,
               study.pending_fraction > 0 ? fmt::format(", not computed {:.4f}", study.pending_fraction) : "");
  }
  if (interrupted) fmt::print(stderr, "vibro: interrupted; {}\n", args.out.empty() ? "results so far printed" : "continue with --resume");
  return interrupted ? kExitInterrupted : 0;
}

int RunSweep(const std::string& path, const std::vector<std::string>& sets, bool json,
             const std::string& key, double from, double to, int steps, int record, bool one_way,
             const std::string& out) {
  const auto loaded = vibro::LoadScene(path, sets);
  std::vector<std::string> problems;
  if (steps < 1) problems.push_back(fmt::format("--steps {}: expected N ≥ 1", steps));
  if (record < 1) problems.push_back(fmt::format("--record {}: expected K ≥ 1", record));
  if (!problems.empty()) throw vibro::InputError(problems);
  // Both ends must be valid values of the key (bad input before any computation).
  const vibro::frontend::SceneOrigin origin{path, std::nullopt, path, sets};
  for (const auto& [v, option] : {std::pair{from, "--from"}, std::pair{to, "--to"}})
    vibro::frontend::SceneAtOption(origin, key, v, option);
  std::unique_ptr<vibro::Hdf5Store> store;
  if (!out.empty()) store = vibro::Hdf5Store::Create(out, HeaderOf(loaded, vibro::System(loaded.scene)));
  vibro::SweepRequest req;
  // Progress: one scene per run of the sweep, up and (unless --one-way) down.
  vibro::cli::Progress progress("sweep", json);
  const long long runs = (steps + 1LL) * (one_way ? 1 : 2);
  std::atomic<long long> scenes{0};
  req.scene_at = [&](double v) {
    progress.Update(scenes++, runs, fmt::format("{} = {:.8g}", key, v));
    return SceneWith(path, sets, key, v);
  };
  req.from = from;
  req.to = to;
  req.steps = steps;
  req.record = record;
  req.both_ways = !one_way;
  const auto sweep = vibro::Sweep(req, &g_stop_requested);
  const bool interrupted = g_stop_requested.load();
  const auto outcome = vibro::frontend::SweepOutcome(sweep, key, interrupted);
  if (store) {
    const vibro::cli::FinalWrite writing;
    store->WriteSweep(sweep, {key, from, to, steps, record, !one_way});
    store->Finish(outcome, sweep.empty() ? vibro::Attractor{} : sweep.back().attractor);
    store.reset();
  }
  if (json) {
    fmt::print("{}\n", vibro::SweepJson(sweep));
  } else {
    fmt::print("{:>16} {:>5} {:>20} {:>7} {:>12}\n", key, "dir", "attractor", "period", "SP");
    for (const auto& p : sweep)
      fmt::print("{:>16.10g} {:>5} {:>20} {:>7} {:>12.8f}\n", p.value, p.upward ? "up" : "down",
                 p.attractor.kind, p.attractor.period ? std::to_string(*p.attractor.period) : "-",
                 p.attractor.sticking_fraction.value_or(0.0));
  }
  if (outcome.status == vibro::RunStatus::kNumericalFailure || outcome.status == vibro::RunStatus::kUndetermined)
    fmt::print(stderr, "vibro: {}\n", outcome.message);
  return ExitCode(outcome.status);
}

int RunInfo(const std::string& path, bool json) {
  const auto run = vibro::ReadStoredRun(path);
  if (json) {
    fmt::print("{}\n", vibro::StoredRunJson(run));
    return 0;
  }
  fmt::print("file         {}\n", path);
  fmt::print("created      {} by vibro {}{}{}\n", run.created, run.version,
             run.git_commit.empty() ? "" : " (commit " + run.git_commit + ")",
             run.command.empty() ? "" : ", command '" + run.command + "'");
  fmt::print("groups       {}\n", fmt::join(run.groups, ", "));
  for (size_t i = 0; i < run.groups.size(); ++i)  // the results a file holds besides the run
    if (!run.group_notes[i].empty() &&
        !std::set<std::string>{"checkpoint", "attractor", "events", "samples", "section"}.count(run.groups[i]))
      fmt::print("  /{:<13} {}\n", run.groups[i], run.group_notes[i]);
  fmt::print("engine       {}, chatter {}\n", run.engine, run.chatter);
  fmt::print("status       {}{}\n", run.status, run.message.empty() ? "" : ": " + run.message);
  fmt::print("rows         {} events, {} samples, {} section points\n", run.events, run.samples,
             run.sections);
  if (run.checkpoint)
    fmt::print("checkpoint   period {} ({} impacts, {} accumulations, {} sticks, {} releases)\n",
               run.checkpoint->clock.period, run.checkpoint->counts.impacts,
               run.checkpoint->counts.accumulations, run.checkpoint->counts.sticks,
               run.checkpoint->counts.releases);
  if (!run.attractor.kind.empty())
    PrintAttractor(run.attractor);
  else if (std::find(run.groups.begin(), run.groups.end(), "attractor") == run.groups.end())
    fmt::print("attractor    none (a study, branch or partition: see the groups above)\n");
  else
    fmt::print("attractor    (not classified: the run did not finish)\n");
  fmt::print("scene:\n{}", run.scene_text);
  return 0;
}

int RunPlot(const std::string& path, const std::string& prefix, const std::string& overlay,
            const std::string& options) {
  for (const auto* name : {&path, &prefix, &overlay, &options})
    if (name->find('\'') != std::string::npos)
      throw vibro::InputError({"vibro plot: file names with a single quote are not supported"});
  vibro::ReadStoredRun(path);  // a clear error (exit 2) for a file that is not a vibro run
  std::vector<std::string> tried;
  const std::string script = vibro::cli::FindPlotScript(tried);
  if (script.empty()) {
    fmt::print(stderr, "vibro: plotting code not found (looked for {}); reinstall vibro\n",
               fmt::join(tried, " and "));
    return kExitInternal;
  }
  if (script.find('\'') != std::string::npos) {
    fmt::print(stderr, "vibro: cannot run the plotting code from a directory with a single quote: {}\n", script);
    return kExitInternal;
  }
  std::string cmd = fmt::format("'{}' '{}' '{}'", VIBRO_PYTHON, script, path);
  if (!prefix.empty()) cmd += fmt::format(" --out '{}'", prefix);
  if (!overlay.empty()) cmd += fmt::format(" --overlay '{}'", overlay);
  cmd += options;
  const int rc = std::system(cmd.c_str());
  // The script exits with 2 for bad input (an overlay that is not a continuation branch).
  if (WIFEXITED(rc) && WEXITSTATUS(rc) == kExitBadInput) return kExitBadInput;
  if (rc != 0) {
    fmt::print(stderr, "vibro: plotting failed (python exit status {})\n", rc);
    return kExitInternal;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"vibro: harmonically forced impact oscillators with sticking and chattering"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "vibro " VIBRO_VERSION " (commit " VIBRO_GIT_COMMIT ")");

  std::string scene_path;
  std::vector<std::string> sets;
  bool json = false;
  const auto add_scene_options = [&](CLI::App* cmd) {
    cmd->add_option("SCENE", scene_path, "scene file (TOML)")->required();
    cmd->add_option("--set", sets, "override a scene key, KEY=VALUE in TOML syntax (repeatable)")
        ->take_all()
        ->allow_extra_args(false);
    cmd->add_flag("--json", json, "print one JSON object on stdout");
  };

  CLI::App* model = app.add_subcommand("model", "print the structural model derived from a scene");
  add_scene_options(model);
  CLI::App* simulate = app.add_subcommand("simulate", "simulate a scene and summarise its attractor");
  add_scene_options(simulate);
  std::string out_path;
  bool resume = false;
  simulate->add_option("--out", out_path, "write the run to this HDF5 file (docs/output.md)");
  simulate->add_flag("--resume", resume, "continue the interrupted run stored in --out");

  CLI::App* orbit = app.add_subcommand("orbit", "find a periodic orbit and its Floquet multipliers");
  add_scene_options(orbit);
  vibro::OrbitRequest orbit_req;
  std::string orbit_kind = "auto", orbit_guess;
  orbit->add_option("--kind", orbit_kind, "auto | sticking | impact (default auto: the kind of the attractor or of the start state)")
      ->check(CLI::IsMember({"auto", "sticking", "impact"}));
  orbit->add_option("--transient", orbit_req.transient_periods,
                    "periods simulated before Newton (default 200; 0: Newton from the scene's initial state)")
      ->check(CLI::NonNegativeNumber);
  orbit->add_option("--period", orbit_req.period, "period in forcing periods (default: from a transient)")->check(CLI::Range(0, 4096));
  orbit->add_option("--impacts", orbit_req.impacts, "impacts per period of an impact orbit")->check(CLI::Range(0, 1 << 20));
  orbit->add_option("--guess", orbit_guess, "PHASE[,VELOCITY]: start of the transient (ωt, contact velocity)");
  std::string orbit_out;
  orbit->add_option("--out", orbit_out, "write one period of the orbit and its multipliers to HDF5");

  CLI::App* cont = app.add_subcommand("continue", "continue a periodic orbit in one parameter");
  add_scene_options(cont);
  std::string cont_param;
  double cont_to = 0, cont_step = 0;
  int cont_points = 1000, cont_period = 0;
  cont->add_option("--param", cont_param, "the numeric scene key to vary, e.g. excitation.amplitude")->required();
  cont->add_option("--to", cont_to, "end value of the parameter")->check(kFinite)->required();
  cont->add_option("--step", cont_step, "initial arclength step (default |to − from|/50)")->check(kFinite);
  cont->add_option("--max-points", cont_points, "most points on the branch")->check(CLI::Range(1, 1 << 24));
  cont->add_option("--period", cont_period, "period of the orbit (default: from a transient)")->check(CLI::Range(0, 4096));
  std::string cont_kind = "auto", cont_out, cont_from;
  long long cont_point = -1;
  int cont_transient = 200;
  cont->add_option("--out", cont_out, "write the branch and its bifurcations to HDF5");
  cont->add_option("--kind", cont_kind, "auto | sticking | impact (default auto)")
      ->check(CLI::IsMember({"auto", "sticking", "impact"}));
  cont->add_option("--transient", cont_transient, "periods simulated before the first Newton (default 200; 0: from [initial])")
      ->check(CLI::NonNegativeNumber);
  auto* cont_from_opt = cont->add_option("--from", cont_from, "restart from a branch stored by vibro continue --out");
  cont->add_option("--point", cont_point, "the point K (0-based) of --from to restart from")->needs(cont_from_opt);
  StudyArgs study_args;
  CLI::App* attractors = app.add_subcommand("attractors", "find coexisting attractors from random initial states");
  CLI::App* basin = app.add_subcommand("basin", "map basins of attraction over two initial-state coordinates");
  for (CLI::App* cmd : {attractors, basin}) {
    add_scene_options(cmd);
    cmd->add_option("--x", study_args.x, "first coordinate: x_B, v_B, X<i>, V<i> (default x_B)");
    cmd->add_option("--y", study_args.y, "second coordinate (default v_B)");
    cmd->add_option("--x-range", study_args.x_range, "A,B")->check(kFinite)->delimiter(',')->expected(2);
    cmd->add_option("--y-range", study_args.y_range, "C,D")->check(kFinite)->delimiter(',')->expected(2);
    cmd->add_option("--threads", study_args.threads, "worker threads (default: all cores)")->check(CLI::Range(0, 4096));
    cmd->add_flag("--full-periods", study_args.full_periods,
                  "run every cell for run.periods periods (no early stop when it settles)");
  }
  attractors->add_option("--samples", study_args.samples, "random initial states (default 200)")->check(CLI::Range(1LL, 1LL << 24));
  attractors->add_option("--seed", study_args.seed, "seed of the random initial states (default 1)");
  basin->add_option("--grid", study_args.grid, "NX,NY cells (default 64,64)")->check(CLI::Range(1, 1 << 16))->delimiter(',')->expected(2);
  basin->add_option("--out", study_args.out, "write the label map and attractor table to HDF5");
  basin->add_flag("--resume", study_args.resume, "compute only the cells missing from the interrupted study in --out");
  CLI::App* partition = app.add_subcommand(
      "partition", "curves of constant sticking fraction in a parameter plane, and the existence boundaries");
  add_scene_options(partition);
  PartitionArgs part;
  double part_from2 = 0;
  partition->add_option("--params", part.params, "KEY1,KEY2: the two numeric scene keys")->delimiter(',')->required();
  partition->add_option("--range1", part.range1, "A,B: range of KEY1")->check(kFinite)->delimiter(',')->required();
  partition->add_option("--steps1", part.steps1, "steps of KEY1 (default 20: 21 columns)")->check(CLI::Range(1, 1 << 16));
  partition->add_option("--range2", part.range2, "C,D: range of KEY2 (each column is continued in it)")->check(kFinite)
      ->delimiter(',')->required();
  auto* from2_opt = partition->add_option("--from2", part_from2, "where each column's branch starts (default: the scene's KEY2)")->check(kFinite);
  partition->add_option("--sticking-fraction", part.levels, "S1,S2,...: levels to trace")->check(kFinite)->delimiter(',')->required();
  partition->add_option("--period", part.period, "period of the sticking orbits (default: from a transient)")->check(CLI::Range(0, 4096));
  partition->add_option("--threads", part.threads, "threads (default: all cores)")->check(CLI::Range(0, 4096));
  partition->add_option("--out", part.out, "write the partition to HDF5");
  CLI::App* sweep = app.add_subcommand("sweep", "brute-force bifurcation diagram by simulation, up and down");
  add_scene_options(sweep);
  std::string sweep_param;
  double sweep_from = 0, sweep_to = 0;
  int sweep_steps = 50, sweep_record = 16;
  bool sweep_one_way = false;
  sweep->add_option("--param", sweep_param, "numeric scene key to vary")->required();
  sweep->add_option("--from", sweep_from, "first value")->check(kFinite)->required();
  sweep->add_option("--to", sweep_to, "last value")->check(kFinite)->required();
  sweep->add_option("--steps", sweep_steps, "steps between them (default 50)")->check(CLI::Range(1, 1 << 22));
  sweep->add_option("--record", sweep_record, "section points kept per value (default 16)")->check(CLI::Range(1, 1 << 16));
  sweep->add_flag("--one-way", sweep_one_way, "only upwards (default: up, then down)");
  std::string sweep_out;
  sweep->add_option("--out", sweep_out, "write the sweep to HDF5 (/sweep)");
  CLI::App* validate = app.add_subcommand("validate", "confirm or refute, point by point, a branch of orbits from another tool");
  ValidateArgs val;
  std::string val_kind = "auto";
  validate->add_option("SCENE", val.scene, "scene file (TOML)")->required();
  validate->add_option("BRANCH", val.csv, "branch CSV: value,time,displacement_1..n,velocity_1..n[,period,stable,sticking_fraction]")
      ->required();
  validate->add_option("--set", val.sets, "override a scene key, KEY=VALUE in TOML syntax (repeatable)")
      ->take_all()
      ->allow_extra_args(false);
  validate->add_option("--param", val.param, "the numeric scene key the column value sets")->required();
  validate->add_option("--kind", val_kind, "auto | sticking | impact (default auto: any)")
      ->check(CLI::IsMember({"auto", "sticking", "impact"}));
  validate->add_option("--period", val.period, "period of the orbits where a row claims none (default: the first return)");
  validate->add_option("--tolerance", val.tolerance, "largest relative distance from a claimed state to the orbit (default 1e-6)");
  validate->add_option("--sticking-tolerance", val.sticking_tolerance, "largest difference of sticking fractions (default 1e-6)");
  validate->add_flag("--json", val.json, "print one JSON object on stdout");
  validate->add_option("--out", val.out, "write the verdicts and vibro's orbits to HDF5 (/validation)");
  CLI::App* score = app.add_subcommand("score", "score another simulator's events against vibro's run of the scene");
  ScoreArgs sco;
  score->add_option("SCENE", sco.scene, "scene file (TOML)")->required();
  score->add_option("EVENTS", sco.csv, "events CSV: t,kind[,velocity]")->required();
  score->add_option("--set", sco.sets, "override a scene key, KEY=VALUE in TOML syntax (repeatable)")
      ->take_all()
      ->allow_extra_args(false);
  score->add_option("--window", sco.window, "match events at most WINDOW·T apart (default 0.05)");
  score->add_option("--tolerance", sco.tolerance, "a time error above TOLERANCE·T is a divergence (default 1e-6)");
  score->add_flag("--json", sco.json, "print one JSON object on stdout");
  CLI::App* check = app.add_subcommand("check", "cross-check the exact engine, CVODE and the Poincaré solver");
  add_scene_options(check);
  std::string check_precision = "double";
  check->add_option("--precision", check_precision,
                    "quad: add the quad-precision exact engine as a fourth opinion (the reference)")
      ->check(CLI::IsMember({"double", "quad"}));

  std::string file_path, plot_prefix;
  CLI::App* info = app.add_subcommand("info", "print what a vibro HDF5 file holds");
  info->add_option("FILE", file_path, "HDF5 file written by vibro")->required();
  info->add_flag("--json", json, "print one JSON object on stdout");
  CLI::App* plot = app.add_subcommand("plot", "draw pictures (PNG, PDF or SVG) of a vibro HDF5 file");
  plot->add_option("FILE", file_path, "HDF5 file written by vibro")->required();
  plot->add_option("--out", plot_prefix, "prefix of the files (default: FILE without .h5)");
  std::string plot_overlay;
  plot->add_option("--overlay", plot_overlay,
                   "a continuation branch (HDF5 with /branch) drawn over a sweep's plot");
  std::string plot_format = "png", plot_window;
  int plot_dpi = 150;
  plot->add_option("--format", plot_format, "png | pdf | svg (default png)")
      ->check(CLI::IsMember({"png", "pdf", "svg"}));
  plot->add_option("--dpi", plot_dpi, "resolution of PNG files (default 150)")->check(CLI::Range(20, 2400));
  plot->add_option("--time-window", plot_window, "A,B: time plots show A <= t <= B (default: the last 5 periods)");

  bool force = false;
  for (CLI::App* cmd : {simulate, orbit, cont, basin, partition, sweep})
    cmd->add_flag("--force", force, "replace an --out file holding a vibro run of another scene or command");

  vibro::cli::InstallStopHandlers();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : kExitBadInput;
  }
  // Provenance of every file this run writes: the command, its command line and options.
  if (!app.get_subcommands().empty()) {
    const CLI::App* cmd = app.get_subcommands().front();
    std::string line;
    for (int i = 0; i < argc; ++i) line += (i ? " " : "") + ShellQuoted(argv[i]);
    vibro::frontend::SetInvocation({cmd->get_name(), line, cmd->config_to_str(true, false), force});
  }

  try {
    if (*model) return RunModel(scene_path, sets, json);
    if (*simulate) return RunSimulate(scene_path, sets, json, out_path, resume);
    if (*info) return RunInfo(file_path, json);
    if (*orbit) {
      orbit_req.kind = orbit_kind == "impact"     ? vibro::OrbitKind::kImpact
                       : orbit_kind == "sticking" ? vibro::OrbitKind::kSticking
                                                  : vibro::OrbitKind::kAuto;
      if (!orbit_guess.empty()) {
        const auto comma = orbit_guess.find(',');
        try {
          orbit_req.guess_phase = std::stod(orbit_guess.substr(0, comma));
          if (comma != std::string::npos) orbit_req.guess_velocity = std::stod(orbit_guess.substr(comma + 1));
        } catch (const std::exception&) {
          throw vibro::InputError({"--guess " + orbit_guess + ": expected PHASE or PHASE,VELOCITY (numbers)"});
        }
        if (!std::isfinite(*orbit_req.guess_phase) ||
            (orbit_req.guess_velocity && !std::isfinite(*orbit_req.guess_velocity)))
          throw vibro::InputError({"--guess " + orbit_guess + ": expected finite numbers (no nan or inf)"});
      }
      return RunOrbit(scene_path, sets, json, orbit_req, orbit_out);
    }
    if (*plot) {
      if (plot_window.find_first_not_of("0123456789.eE+-,") != std::string::npos)
        throw vibro::InputError({"--time-window " + plot_window + ": expected A,B (two numbers)"});
      return RunPlot(file_path, plot_prefix, plot_overlay,
                     fmt::format(" --format {} --dpi {}{}", plot_format, plot_dpi,
                                 plot_window.empty() ? "" : " --time-window=" + plot_window));
    }
    if (*check) return RunCheck(scene_path, sets, json, check_precision == "quad");
    if (*score) return RunScore(sco);
    if (*validate) {
      val.kind = val_kind == "impact"     ? vibro::OrbitKind::kImpact
                 : val_kind == "sticking" ? vibro::OrbitKind::kSticking
                                          : vibro::OrbitKind::kAuto;
      return RunValidate(val);
    }
    if (*sweep)
      return RunSweep(scene_path, sets, json, sweep_param, sweep_from, sweep_to, sweep_steps,
                      sweep_record, sweep_one_way, sweep_out);
    if (*attractors) return RunStudyCommand(scene_path, sets, json, study_args, false);
    if (*basin) return RunStudyCommand(scene_path, sets, json, study_args, true);
    if (*partition) {
      if (*from2_opt) part.from2 = part_from2;
      return RunPartition(scene_path, sets, json, part);
    }
    if (*cont) {
      vibro::OrbitRequest req;
      req.period = cont_period;
      req.kind = cont_kind == "impact"     ? vibro::OrbitKind::kImpact
                 : cont_kind == "sticking" ? vibro::OrbitKind::kSticking
                                           : vibro::OrbitKind::kAuto;
      req.transient_periods = cont_transient;
      if (!cont_from.empty() && cont_point < 0)
        throw vibro::InputError({"--from " + cont_from + ": give the point to restart from with --point K"});
      return RunContinue(scene_path, sets, json, cont_param, cont_to, cont_step, cont_points, req, cont_out,
                         cont_from, cont_point);
    }
  } catch (const vibro::InputError& e) {
    for (const auto& m : e.messages()) fmt::print(stderr, "{}\n", m);
    fmt::print(stderr, "vibro: {} problem(s) in the input; nothing was computed or written\n",
               e.messages().size());
    return kExitBadInput;
  } catch (const std::exception& e) {
    fmt::print(stderr, "vibro: internal error: {}\n", e.what());
    return kExitInternal;
  }
  return kExitInternal;
}
