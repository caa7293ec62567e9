// The `vibro` command (docs/cli.md; exit codes and JSON in docs/output.md): the options of
// every subcommand, parsed with CLI11 (the only file that includes it), and the call of the
// command's Run<Command> (cmd_<command>.cpp, declared in cli_common.hpp).
//
// Exit codes: 0 success · 1 internal error · 2 bad input · 3 numerical failure · 4 disagreement ·
// 130 interrupted.
#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstddef>
#include <cstdlib>
#include <exception>
#include <iterator>
#include <new>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "cli/cli_common.hpp"
#include "cli/stop_signals.hpp"
#include "frontend/frontend.hpp"
#include "frontend/limits.hpp"
#include "frontend/rigid_model.hpp"
#include "frontend/run_budget.hpp"
#include "vibro/child_process.hpp"
#include "vibro/hdf5_store.hpp"
#include "vibro/poincare.hpp"
#include "vibro/scene_file.hpp"

namespace {

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

// A count (periods, an index) ≥ 0. CLI::NonNegativeNumber refused `x` with its range written out
// to DBL_MAX, a line of 330 characters.
const CLI::Validator kNonNegativeInteger(
    [](std::string& text) -> std::string {
      char* end = nullptr;
      errno = 0;
      const long long v = std::strtoll(text.c_str(), &end, 10);
      if (end == text.c_str() || *end != '\0' || errno == ERANGE || v < 0)
        return "expected an integer ≥ 0, got " + text;
      return {};
    },
    "INT>=0");

// Every subcommand with its one-line description, in the order `vibro --help` lists them: the one
// list main declares them from, and takes each one's CLI::App from (CommandIndex).
struct CommandEntry {
  std::string_view name;
  const char* description;
};
constexpr CommandEntry kCommands[] = {
    {"model", "print the structural model derived from a scene"},
    {"simulate", "simulate a scene and summarise its attractor"},
    {"orbit", "find a periodic orbit and its Floquet multipliers"},
    {"prove", "prove a periodic orbit with interval arithmetic and write a certificate"},
    {"continue", "continue a periodic orbit in one parameter"},
    {"diagram", "the whole one-parameter bifurcation diagram: sweep, continuation, branch switching, coverage"},
    {"attractors", "find coexisting attractors from random initial states"},
    {"basin", "map basins of attraction over two initial-state coordinates"},
    {"partition", "curves of constant sticking fraction in a parameter plane, and the existence boundaries"},
    {"curve", "trace a fold, flip, Neimark-Sacker, branch point or non-smooth bifurcation in two parameters"},
    {"sweep", "brute-force bifurcation diagram by simulation, up and down"},
    {"validate", "confirm or refute, point by point, a branch of orbits from another tool"},
    {"score", "score another simulator's events against vibro's run of the scene"},
    {"check", "cross-check the exact engine, CVODE and the Poincaré solver"},
    {"info", "print what a vibro HDF5 file holds"},
    {"plot", "draw pictures (PNG, PDF or SVG) of a vibro HDF5 file"},
};
constexpr std::size_t kCommandCount = std::size(kCommands);

// The index of the subcommand NAME in kCommands; a name not in it does not compile.
consteval std::size_t CommandIndex(std::string_view name) {
  for (std::size_t i = 0; i < kCommandCount; ++i)
    if (kCommands[i].name == name) return i;
  throw "not a subcommand of kCommands";
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

// An integer option's range (frontend/limits.hpp: the same limits Python's arguments are held to).
CLI::Range InRange(vibro::frontend::IntLimit limit) { return CLI::Range(limit.lo, limit.hi); }

// A message on one line: control characters that came with the input (a newline inside a --set
// value or a file name) are shown escaped.
std::string OneLine(const std::string& m) {
  std::string out;
  for (const char c : m) {
    if (c == '\n') out += "\\n";
    else if (c == '\r') out += "\\r";
    else if (c == '\t') out += "\\t";
    else if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) out += fmt::format("\\x{:02x}", static_cast<unsigned char>(c));
    else out += c;
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  // First: a stop request that arrives while the options are being set up is honoured too.
  vibro::cli::InstallStopHandlers();
  CLI::App app{"vibro: harmonically forced impact oscillators with sticking and chattering"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "vibro " VIBRO_VERSION " (commit " VIBRO_GIT_COMMIT ")");

  // Only the invoked subcommand gets its options (the first argument that is not an option names
  // it): CLI11 builds each option at a cost, and building all of them was a third of what
  // `vibro --version` executed (docs/performance.md, "Start-up"). When that argument names a
  // subcommand, only that one is declared too (each costs CLI11 about 17 000 instructions, its own
  // help option among them; 0.2 M for all 16); otherwise (none named, `vibro --help`, a wrong name)
  // every one is, so `vibro --help` lists them and a wrong name is refused as before.
  std::string invoked;
  for (int i = 1; i < argc && invoked.empty(); ++i)
    if (argv[i][0] != '-') invoked = argv[i];
  const bool only_invoked = std::any_of(std::begin(kCommands), std::end(kCommands),
                                        [&](const CommandEntry& c) { return c.name == invoked; });
  CLI::App undeclared{"a subcommand not declared in this process: never parsed", "(undeclared)"};
  std::array<CLI::App*, kCommandCount> declared{};
  for (std::size_t i = 0; i < kCommandCount; ++i)
    declared[i] = !only_invoked || invoked == kCommands[i].name
                      ? app.add_subcommand(std::string(kCommands[i].name), kCommands[i].description)
                      : &undeclared;
  const auto Wanted = [&](const CLI::App* cmd) { return cmd != &undeclared && cmd->get_name() == invoked; };

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

  CLI::App* model = declared[CommandIndex("model")];
  if (Wanted(model)) add_scene_options(model);

  CLI::App* simulate = declared[CommandIndex("simulate")];
  std::string out_path;
  bool resume = false;
  long long extend = 0;
  int blocks = 10;
  bool rigid_beside = false;
  double simulate_time_limit = vibro::frontend::RunBudget::kDefaultTimeLimit;
  if (Wanted(simulate)) {
    add_scene_options(simulate);
    simulate->add_option("--out", out_path, "write the run to this HDF5 file (docs/output.md)");
    simulate->add_flag("--resume", resume, "continue the interrupted run stored in --out");
    simulate->add_option("--extend", extend, "continue the run stored in --out (finished or interrupted) for N more periods")
        ->check(CLI::Range(1LL, 1LL << 53));
    simulate->add_option("--blocks", blocks,
                         "batch means of the contact loads over N blocks of periods (docs/loads.md; default 10)")
        ->check(CLI::Range(2, 100000));
    simulate->add_flag("--rigid-beside", rigid_beside,
                       "compliant stops: also run the scene with each made rigid, of the restitution its damping "
                       "gives under its separation rule, and report the distance between the two trajectories "
                       "and loads (docs/compliant.md)");
    simulate->add_option("--time-limit", simulate_time_limit,
                         "seconds for the whole run (default 86400, one day; 0: none): a run whose event rate "
                         "would take it past the limit, or past its disk's free space with --out, ends at once "
                         "with exit 3")
        ->check(CLI::Range(0.0, 1e12));
  }

  CLI::App* orbit = declared[CommandIndex("orbit")];
  vibro::OrbitRequest orbit_req;
  std::string orbit_kind = "auto", orbit_guess, orbit_out;
  if (Wanted(orbit)) {
    add_scene_options(orbit);
    orbit->add_option("--kind", orbit_kind, "auto | sticking | impact (default auto: the kind of the attractor or of the start state)")
        ->check(CLI::IsMember({"auto", "sticking", "impact"}));
    orbit->add_option("--transient", orbit_req.transient_periods,
                      "periods simulated before Newton (default 200; 0: Newton from the scene's initial state)")
        ->check(kNonNegativeInteger);
    orbit->add_option("--period", orbit_req.period, "period in forcing periods (default: from a transient)")
        ->check(InRange(vibro::frontend::kPeriodLimit));
    orbit->add_option("--impacts", orbit_req.impacts, "impacts per period of an impact orbit")
        ->check(InRange(vibro::frontend::kImpactsLimit));
    orbit->add_option("--guess", orbit_guess,
                      "PHASE[,VELOCITY]: Newton starts on the stop leaving at ωt = PHASE with contact velocity VELOCITY (with --transient N: after N periods from there)");
    orbit->add_option("--out", orbit_out, "write one period of the orbit and its multipliers to HDF5");
  }

  CLI::App* prove = declared[CommandIndex("prove")];
  ProveArgs prove_args;
  std::string prove_kind = "auto";
  if (Wanted(prove)) {
    add_scene_options(prove);
    prove->add_option("--kind", prove_kind, "auto | sticking | impact (default auto: the kind of the orbit found)")
        ->check(CLI::IsMember({"auto", "sticking", "impact"}));
    prove->add_option("--period", prove_args.request.period, "period in forcing periods (default: the orbit's own)")
        ->check(InRange(vibro::frontend::kPeriodLimit));
    CLI::Option* from = prove->add_option("--from", prove_args.from, "start from the orbit stored by `vibro orbit --out ORBIT.h5`");
    prove->add_option("--transient", prove_args.request.transient_periods, "periods simulated before the orbit search (default 200)")
        ->check(kNonNegativeInteger)
        ->excludes(from);
    CLI::Option* branch_opt =
        prove->add_option("--branch", prove_args.branch, "prove every point of the branch stored by `vibro continue --out FILE.h5`")
            ->excludes(from);
    CLI::Option* bif = prove->add_option(
        "--bifurcation", prove_args.bifurcation,
        "prove the bifurcation point stored by `vibro continue --out BRANCH.h5` (BRANCH.h5, with --point K: its "
        "bifurcation K, default 0) or given as KIND:KEY=VALUE (e.g. branch-point:excitation.amplitude=3.286): its "
        "parameter enclosed in an interval <= 1e-10 wide, one point in it, crossed transversally (the pitchfork "
        "and the fold of the symmetric two-sided 1-DOF oscillator, and grazings; a grazing given as KIND:KEY=VALUE "
        "takes its orbit from --from BRANCH.h5)")
        ->excludes(branch_opt);
    prove->add_option("--point", prove_args.point, "with --bifurcation BRANCH.h5: the bifurcation K (0-based, in the "
                      "order `vibro continue` lists them)")
        ->check(kNonNegativeInteger)
        ->needs(bif);
    prove->add_option("--out", prove_args.out, "write the certificate (JSON) to this file (with --branch: all of them)");
    prove->add_option("--time-limit", prove_args.request.time_limit,
                      "seconds for the whole command: the transient, the orbit search and the proof (with --branch: "
                      "every point and segment); past it: not proven, exit 4 (default 60)")
        ->check(CLI::Range(0.001, 1e6));
  }

  CLI::App* cont = declared[CommandIndex("continue")];
  std::string cont_param, cont_kind = "auto", cont_out, cont_from, cont_side = "above";
  double cont_to = 0, cont_step = 0;
  int cont_points = 1000, cont_period = 0, cont_transient = 200;
  long long cont_point = -1;
  bool cont_switch = false;
  if (Wanted(cont)) {
    add_scene_options(cont);
    cont->add_option("--param", cont_param, "the numeric scene key to vary, e.g. excitation.amplitude")->required();
    cont->add_option("--to", cont_to, "end value of the parameter")->check(kFinite)->required();
    cont->add_option("--step", cont_step, "initial arclength step (default |to − from|/50)")->check(kFinite);
    cont->add_option("--max-points", cont_points, "most points on the branch")->check(InRange(vibro::frontend::kMaxPointsLimit));
    cont->add_option("--period", cont_period, "period of the orbit (default: from a transient)")
        ->check(InRange(vibro::frontend::kPeriodLimit));
    cont->add_option("--out", cont_out, "write the branch and its bifurcations to HDF5");
    cont->add_option("--kind", cont_kind, "auto | sticking | impact (default auto)")
        ->check(CLI::IsMember({"auto", "sticking", "impact"}));
    cont->add_option("--transient", cont_transient, "periods simulated before the first Newton (default 200; 0: from [initial])")
        ->check(kNonNegativeInteger);
    CLI::Option* from = cont->add_option("--from", cont_from, "restart from a branch stored by vibro continue --out");
    CLI::Option* point =
        cont->add_option("--point", cont_point, "the point K (0-based) of --from to restart from")->needs(from);
    CLI::Option* to_switch = cont->add_flag("--switch", cont_switch,
                                            "follow the other branch through the branch-point or flip of --from next to "
                                            "point K (the period-doubled branch at a flip)")
                                 ->needs(point);
    cont->add_option("--side", cont_side,
                     "with --switch at a pitchfork whose two halves both head for --to: the half whose x_B at the "
                     "section lies above (default) or below the old branch's")
        ->check(CLI::IsMember({"above", "below"}))
        ->needs(to_switch);
  }

  CLI::App* diagram = declared[CommandIndex("diagram")];
  vibro::frontend::DiagramSpec dia;
  std::string dia_out;
  if (Wanted(diagram)) {
    add_scene_options(diagram);
    diagram->add_option("--param", dia.key, "numeric scene key to vary")->required();
    diagram->add_option("--from", dia.from, "one end of the range")->check(kFinite)->required();
    diagram->add_option("--to", dia.to, "the other end")->check(kFinite)->required();
    using DD = vibro::DiagramDefaults;
    diagram->add_option("--steps", dia.steps, fmt::format("steps of the sweep between them (default {})", DD::sweep_steps));
    diagram->add_option("--record", dia.record, fmt::format("section points kept per sweep value (default {})", DD::record));
    diagram->add_option("--searches", dia.searches,
                        fmt::format("attractor searches at this many values (default {}; 0: none)", DD::searches));
    diagram->add_option("--grid", dia.grid,
                        fmt::format("each search: a GRID × GRID grid of (x_B, v_B) starts (default {})", DD::search_grid));
    diagram->add_option("--max-period", dia.max_period,
                        fmt::format("longest period switched to at a flip or branch point (default {}; every periodic "
                                    "attractor found is continued, whatever its period)",
                                    DD::max_period));
    diagram->add_option("--max-branches", dia.max_branches,
                        fmt::format("branches stored at most, a hard bound that keeps room for every seed's branch "
                                    "before switched ones; what it left out is listed (default {})",
                                    DD::max_branches));
    diagram->add_option("--max-points", dia.max_points,
                        fmt::format("points per continuation at most (default {})", DD::max_points));
    diagram->add_option("--coverage-tolerance", dia.coverage_tolerance,
                        fmt::format("relative distance (impact phases, speeds) within which a sweep attractor lies on "
                                    "a branch (default {:g})",
                                    DD::coverage_tolerance));
    diagram->add_option("--threads", dia.threads,
                        fmt::format("threads of the searches (default {}: all cores)", DD::threads));
    diagram->add_option("--out", dia_out, "write the sweep, every branch and the coverage to HDF5");
  }

  CLI::App* attractors = declared[CommandIndex("attractors")];
  CLI::App* basin = declared[CommandIndex("basin")];
  StudyArgs study_args;
  for (CLI::App* cmd : {attractors, basin}) {
    if (!Wanted(cmd)) continue;
    add_scene_options(cmd);
    cmd->add_option("--x", study_args.x, "first coordinate: x_B, v_B, X<i>, V<i> (default x_B)");
    cmd->add_option("--y", study_args.y, "second coordinate (default v_B)");
    cmd->add_option("--x-range", study_args.x_range, "A,B")->check(kFinite)->delimiter(',')->expected(2);
    cmd->add_option("--y-range", study_args.y_range, "C,D")->check(kFinite)->delimiter(',')->expected(2);
    cmd->add_option("--threads", study_args.threads, "worker threads (default: all cores)")->check(InRange(vibro::frontend::kThreadsLimit));
    cmd->add_flag("--full-periods", study_args.full_periods,
                  "run every cell for run.periods periods (no early stop when it settles)");
  }
  if (Wanted(attractors)) {
    attractors->add_option("--samples", study_args.samples, "random initial states (default 200)")
        ->check(InRange(vibro::frontend::kSamplesLimit));
    attractors->add_option("--seed", study_args.seed, "seed of the random initial states (default 1)");
  }
  if (Wanted(basin)) {
    basin->add_option("--grid", study_args.grid, "NX,NY cells (default 64,64)")
        ->check(InRange(vibro::frontend::kGridLimit))
        ->delimiter(',')
        ->expected(2);
    basin->add_option("--out", study_args.out, "write the label map and attractor table to HDF5");
    basin->add_flag("--resume", study_args.resume, "compute only the cells missing from the interrupted study in --out");
  }

  CLI::App* partition = declared[CommandIndex("partition")];
  PartitionArgs part;
  double part_from2 = 0;
  CLI::Option* from2_opt = nullptr;
  if (Wanted(partition)) {
    add_scene_options(partition);
    partition->add_option("--params", part.spec.params, "KEY1,KEY2: the two numeric scene keys")->delimiter(',')->required();
    partition->add_option("--range1", part.spec.range1, "A,B: range of KEY1")->check(kFinite)->delimiter(',')->required();
    partition->add_option("--steps1", part.spec.steps1, "steps of KEY1 (default 20: 21 columns)")
        ->check(InRange(vibro::frontend::kSteps1Limit));
    partition->add_option("--range2", part.spec.range2, "C,D: range of KEY2 (each column is continued in it)")
        ->check(kFinite)
        ->delimiter(',')
        ->required();
    from2_opt = partition->add_option("--from2", part_from2, "where each column's branch starts (default: the scene's KEY2)")
                    ->check(kFinite);
    partition->add_option("--sticking-fraction", part.spec.levels, "S1,S2,...: levels to trace")
        ->check(kFinite)
        ->delimiter(',')
        ->required();
    partition->add_option("--period", part.spec.period, "period of the sticking orbits (default: from a transient)")
        ->check(InRange(vibro::frontend::kPeriodLimit));
    partition->add_option("--threads", part.spec.threads, "threads (default: all cores)")->check(InRange(vibro::frontend::kThreadsLimit));
    partition->add_option("--out", part.out, "write the partition to HDF5");
  }

  CLI::App* curve = declared[CommandIndex("curve")];
  CurveArgs crv;
  if (Wanted(curve)) {
    add_scene_options(curve);
    curve->add_option("--param", crv.spec.params, "KEY1,KEY2: the two numeric scene keys")->delimiter(',')->required();
    curve->add_option("--kind", crv.spec.kinds,
                      "K1,K2,...: fold, flip, neimark-sacker, branch-point, grazing, sticking-lost, sticking-entry, "
                      "rising, simultaneous (with --from: default the stored bifurcation's kind)")
        ->delimiter(',');
    curve->add_option("--contact", crv.spec.contact, "several contacts: follow the non-smooth kind on this contact only");
    curve->add_option("--range1", crv.spec.range1, "A,B: range of KEY1 (the curve ends where it leaves the box)")
        ->check(kFinite)->delimiter(',')->required();
    curve->add_option("--range2", crv.spec.range2, "C,D: range of KEY2")->check(kFinite)->delimiter(',')->required();
    CLI::Option* toward = curve->add_option("--toward", crv.spec.toward,
                                            "A,B: start from the first such bifurcation met on the segment from the "
                                            "scene's (KEY1, KEY2) to (A, B); A1,B1,A2,B2,...: one end per kind")
                              ->check(kFinite)
                              ->delimiter(',');
    CLI::Option* cfrom = curve->add_option("--from", crv.spec.from, "or start from a bifurcation stored by vibro continue --out")
                             ->excludes(toward);
    curve->add_option("--point", crv.spec.point, "with --from: the bifurcation K (0-based, in the order vibro continue lists them)")
        ->needs(cfrom);
    curve->add_option("--step", crv.spec.step, "first step, in units of the box scaled to (0,1)x(0,1) (default 0.02)")->check(kFinite);
    curve->add_option("--max-step", crv.spec.max_step, "largest step, same units (default 0.1)")->check(kFinite);
    curve->add_option("--max-points", crv.spec.max_points, "most points each way from the start (default 200)");
    curve->add_option("--period", crv.spec.period, "with --toward: period of the orbit (default: from a transient)");
    curve->add_option("--transient", crv.spec.transient, "with --toward: periods simulated before the first Newton (default 200)");
    curve->add_option("--orbit", crv.spec.orbit, "with --toward: the start orbit, auto | sticking | impact (default auto)")
        ->check(CLI::IsMember({"auto", "sticking", "impact"}));
    curve->add_option("--out", crv.out, "write the curves to HDF5 (/curves)");
  }

  CLI::App* sweep = declared[CommandIndex("sweep")];
  std::string sweep_param, sweep_out;
  double sweep_from = 0, sweep_to = 0;
  int sweep_steps = 50, sweep_record = 16;
  bool sweep_one_way = false;
  if (Wanted(sweep)) {
    add_scene_options(sweep);
    sweep->add_option("--param", sweep_param, "numeric scene key to vary")->required();
    sweep->add_option("--from", sweep_from, "first value")->check(kFinite)->required();
    sweep->add_option("--to", sweep_to, "last value")->check(kFinite)->required();
    sweep->add_option("--steps", sweep_steps, "steps between them (default 50)")->check(InRange(vibro::frontend::kSweepStepsLimit));
    sweep->add_option("--record", sweep_record, "section points kept per value (default 16)")->check(InRange(vibro::frontend::kRecordLimit));
    sweep->add_flag("--one-way", sweep_one_way, "only upwards (default: up, then down)");
    sweep->add_option("--out", sweep_out, "write the sweep to HDF5 (/sweep)");
  }

  CLI::App* validate = declared[CommandIndex("validate")];
  ValidateArgs val;
  std::string val_kind = "auto";
  if (Wanted(validate)) {
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
  }

  CLI::App* score = declared[CommandIndex("score")];
  ScoreArgs sco;
  if (Wanted(score)) {
    score->add_option("SCENE", sco.scene, "scene file (TOML)")->required();
    score->add_option("EVENTS", sco.csv, "events CSV: t,kind[,velocity]")->required();
    score->add_option("--set", sco.sets, "override a scene key, KEY=VALUE in TOML syntax (repeatable)")
        ->take_all()
        ->allow_extra_args(false);
    score->add_option("--window", sco.window, "match events at most WINDOW·T apart (default 0.05)");
    score->add_option("--tolerance", sco.tolerance, "a time error above TOLERANCE·T is a divergence (default 1e-6)");
    score->add_flag("--json", sco.json, "print one JSON object on stdout");
  }

  CLI::App* check = declared[CommandIndex("check")];
  std::string check_precision = "double";
  if (Wanted(check)) {
    add_scene_options(check);
    check->add_option("--precision", check_precision, "quad: add the quad-precision exact engine as a fourth opinion (the reference)")
        ->check(CLI::IsMember({"double", "quad"}));
  }

  std::string file_path, plot_prefix;
  CLI::App* info = declared[CommandIndex("info")];
  if (Wanted(info)) {
    info->add_option("FILE", file_path, "HDF5 file written by vibro")->required();
    info->add_flag("--json", json, "print one JSON object on stdout");
  }

  CLI::App* plot = declared[CommandIndex("plot")];
  std::string plot_overlay, plot_format = "png", plot_window, plot_size, plot_coordinate = "x_B";
  std::optional<std::string> plot_title;
  int plot_dpi = 150;
  double plot_font_size = 10;
  if (Wanted(plot)) {
    plot->add_option("FILE", file_path, "HDF5 file written by vibro")->required();
    plot->add_option("--out", plot_prefix, "prefix of the files (default: FILE without .h5)");
    plot->add_option("--overlay", plot_overlay, "a continuation branch (HDF5 with /branch) drawn over a sweep's plot");
    plot->add_option("--format", plot_format, "png | pdf | svg (default png)")->check(CLI::IsMember({"png", "pdf", "svg"}));
    plot->add_option("--dpi", plot_dpi, "resolution of PNG files (default 150)")->check(CLI::Range(20, 2400));
    plot->add_option("--time-window", plot_window, "A,B: time plots show A <= t <= B (default: the last 5 periods)");
    plot->add_option("--title", plot_title,
                     "title of every picture ('' for none; default: the scene's title, values and what is drawn)");
    plot->add_option("--size", plot_size,
                     "W,H of every picture in inches, or W,H with cm (8.5cm,6cm) (default: each picture's own)");
    plot->add_option("--font-size", plot_font_size, "font size in points (default 10)")->check(CLI::Range(1.0, 72.0));
    plot->add_option("--coordinate", plot_coordinate,
                     "x_B | X1..Xn (modal) | q0..q(N-1) (physical, when the file stores mode shapes): "
                     "drawn by the time plot, phase portrait and section (default x_B)");
  }

  // --time-limit, the same for every command (docs/cli.md "Time limits"): the whole command, from
  // the reading of its input to its last write, transients included; past it the command ends as
  // on a stop request, keeps what it computed and exits 3. simulate adds its pace check to it
  // (frontend/run_budget.hpp); prove has its own, whose end is the verdict "not proven" (exit 4).
  double time_limit = vibro::frontend::RunBudget::kDefaultTimeLimit;
  for (CLI::App* cmd : {model, orbit, cont, curve, diagram, attractors, basin, partition, sweep, validate, score, check, info, plot})
    if (Wanted(cmd))
      cmd->add_option("--time-limit", time_limit,
                      "seconds for the whole command, transients included (default 86400, one day; 0: none): past "
                      "it the command stops as on Ctrl-C, keeps what it computed and exits 3")
          ->check(CLI::Range(0.0, 1e12));

  bool force = false;
  for (CLI::App* cmd : {simulate, orbit, cont, curve, basin, partition, sweep, diagram})
    if (Wanted(cmd)) cmd->add_flag("--force", force, "replace an --out file holding a vibro run of another scene or command");

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

  if (*simulate) time_limit = simulate_time_limit;
  if (!*prove) vibro::cli::ArmTimeLimit(time_limit, "--time-limit");
  const auto dispatch = [&]() -> int {
    try {
      // The analyses built on the rigid model's saltations refuse a compliant stop before anything
      // is computed (frontend/rigid_model.hpp, the one place of the rule).
      // (validate and score keep their scene and overrides in their own arguments.)
      const std::string command = app.get_subcommands().empty() ? ""
                                  : *check && check_precision == "quad"
                                      ? "check --precision quad"
                                      : app.get_subcommands().front()->get_name();
      const std::string& scene = *validate ? val.scene : *score ? sco.scene : scene_path;
      if (!scene.empty() && !vibro::frontend::TakesCompliantStops(command))
        vibro::frontend::CheckSceneModel(command,
                                         vibro::LoadScene(scene, *validate ? val.sets : *score ? sco.sets : sets),
                                         scene, vibro::frontend::Naming::kCli);
      if (*model) return RunModel(scene_path, sets, json);
      if (*simulate) return RunSimulate(scene_path, sets, json, out_path, resume, extend, blocks,
                                          simulate_time_limit, rigid_beside);
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
          // A guess is where Newton starts: no transient unless one is asked for.
          if (orbit->count("--transient") == 0) orbit_req.transient_periods = 0;
        }
        return RunOrbit(scene_path, sets, json, orbit_req, orbit_out);
      }
      if (*prove) {
        prove_args.request.kind = prove_kind == "impact"     ? vibro::OrbitKind::kImpact
                                  : prove_kind == "sticking" ? vibro::OrbitKind::kSticking
                                                             : vibro::OrbitKind::kAuto;
        return RunProve(scene_path, sets, json, prove_args);
      }
      if (*plot) {
        if (plot_window.find_first_not_of("0123456789.eE+-,") != std::string::npos)
          throw vibro::InputError({"--time-window " + plot_window + ": expected A,B (two numbers)"});
        std::vector<std::string> options{"--format", plot_format, "--dpi", std::to_string(plot_dpi)};
        if (!plot_window.empty()) options.push_back("--time-window=" + plot_window);
        if (plot_title) options.push_back("--title=" + *plot_title);
        if (!plot_size.empty()) options.push_back("--size=" + plot_size);
        options.insert(options.end(), {"--font-size", fmt::format("{}", plot_font_size), "--coordinate=" + plot_coordinate});
        return RunPlot(file_path, plot_prefix, plot_overlay, options);
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
      if (*curve) return RunCurve(scene_path, sets, json, crv);
      if (*diagram) return RunDiagram(scene_path, sets, json, dia, dia_out);
      if (*attractors) return RunStudyCommand(scene_path, sets, json, study_args, false);
      if (*basin) return RunStudyCommand(scene_path, sets, json, study_args, true);
      if (*partition) {
        if (*from2_opt) part.spec.from2 = part_from2;
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
                           cont_from, cont_point, cont_switch ? cont_side : std::string());
      }
    } catch (const vibro::InputError& e) {
      for (const auto& m : e.messages()) fmt::print(stderr, "{}\n", OneLine(m));
      fmt::print(stderr, "vibro: {} problem(s) in the input; nothing was computed or written\n",
                 e.messages().size());
      // Out at once, as after a failed write: an output file that could not be made on a full disk
      // leaves HDF5 handles that its clean-up at exit must not touch (it crashed doing so).
      std::fflush(nullptr);
      std::_Exit(kExitBadInput);
    } catch (const vibro::WriteError& e) {  // full disk, I/O error: the file keeps its last flush
      fmt::print(stderr, "vibro: {}; the file keeps what was written up to its last flush\n", OneLine(e.what()));
      // Out at once: the HDF5 library's clean-up at exit would close the failed file's handles,
      // which vibro leaves open on purpose (and it has crashed doing so).
      std::fflush(nullptr);
      std::_Exit(kExitNumerical);
    } catch (const vibro::Interrupted& e) {  // a stop request during a child's wait (a file's test read)
      fmt::print(stderr, "vibro: {}; nothing was written\n", OneLine(e.what()));
      return kExitInterrupted;
    } catch (const vibro::frontend::LimitError& e) {  // an event rate past the run's limits
      fmt::print(stderr, "vibro: {}\n", OneLine(e.what()));
      return kExitNumerical;
    } catch (const std::bad_alloc&) {  // no input gives exit 1: memory is a limit like time
      fmt::print(stderr, "vibro: out of memory (the system refused an allocation); what was written is kept\n");
      return kExitNumerical;
    } catch (const std::exception& e) {
      // A worker thread the system refused (TBB's "pthread_create has failed" under ulimit -v or
      // a process limit): a resource limit like memory, exit 3.
      if (std::string(e.what()).rfind("pthread_create", 0) == 0) {
        fmt::print(stderr, "vibro: out of resources (the system refused a worker thread: {}); what was written is "
                   "kept\n", OneLine(e.what()));
        return kExitNumerical;
      }
      fmt::print(stderr, "vibro: internal error: {}\n", OneLine(e.what()));
      return kExitInternal;
    }
    return kExitInternal;
  };
  const int code = dispatch();
  // The time limit ended the command as a stop request would: exit 3, what it computed kept.
  if (code == kExitInterrupted && vibro::cli::TimeLimitReached()) {
    fmt::print(stderr, "{}vibro: the command stopped there and kept what it computed (as after Ctrl-C)\n",
               vibro::cli::TimeLimitMessage());
    return kExitNumerical;
  }
  return code;
}
