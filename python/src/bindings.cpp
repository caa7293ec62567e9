// The extension module vibro._vibro: the only file that includes pybind11. It runs each command
// with the same library calls as the command line (src/cli/cmd_*.cpp, src/frontend/) and returns
// the same JSON text as `--json` (src/io/summary_json.cpp), which python/vibro/__init__.py turns
// into dicts and numpy arrays.
//
// Every computation releases the GIL. When called from Python's main thread, SIGINT (Ctrl-C) is
// routed to the library's stop flag for the duration of the call: the run stops cleanly at its
// next check, everything is written to the output file, and the result says "interrupted" (the
// Python layer then raises KeyboardInterrupt). Python's own handler is restored afterwards.
#include <signal.h>

#include <atomic>
#include <cmath>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "frontend/commands.hpp"
#include "frontend/frontend.hpp"
#include "vibro/attractor.hpp"
#include "vibro/check.hpp"
#include "vibro/continuation.hpp"
#include "vibro/distribute.hpp"
#include "vibro/hdf5_store.hpp"
#include "vibro/orbit_from_state.hpp"
#include "vibro/poincare.hpp"
#include "vibro/scene_file.hpp"
#include "vibro/simulator.hpp"
#include "vibro/studies.hpp"
#include "vibro/summary_json.hpp"
#include "vibro/system.hpp"

namespace py = pybind11;

namespace {

using vibro::frontend::HeaderOf;
using vibro::frontend::SceneOrigin;

// A scene as loaded: where it came from (to re-derive it with one key changed) and as run.
struct PyScene {
  SceneOrigin origin;
  vibro::LoadedScene loaded;
};

PyScene LoadPyScene(SceneOrigin origin) {
  auto loaded = origin.Load();
  return {std::move(origin), std::move(loaded)};
}

// SIGINT → stop flag while a computation runs (main thread only; see the file comment).
std::atomic<bool> g_sigint{false};
extern "C" void OnSigint(int) { g_sigint.store(true); }

class SigintGuard {
 public:
  explicit SigintGuard(bool install) : installed_(install) {
    if (!installed_) return;
    g_sigint.store(false);
    struct sigaction action = {};
    action.sa_handler = OnSigint;
    sigemptyset(&action.sa_mask);
    sigaction(SIGINT, &action, &previous_);
  }
  ~SigintGuard() {
    if (installed_) sigaction(SIGINT, &previous_, nullptr);
  }
  SigintGuard(const SigintGuard&) = delete;
  SigintGuard& operator=(const SigintGuard&) = delete;

  const std::atomic<bool>* flag() const { return installed_ ? &g_sigint : &never_; }
  bool interrupted() const { return installed_ && g_sigint.load(); }

 private:
  bool installed_;
  struct sigaction previous_ = {};
  std::atomic<bool> never_{false};
};

// Events, dense samples and section points of a run, kept in memory for numpy.
class Recorder final : public vibro::Observer {
 public:
  explicit Recorder(int dof) : dof_(dof) {}
  void OnEvent(const vibro::Event& e) override {
    event_t.push_back(e.t);
    event_kind.push_back(static_cast<std::int8_t>(e.kind));
    event_x_B.push_back(e.x_B);
    event_v_before.push_back(e.v_before);
    event_v_after.push_back(e.v_after);
  }
  void OnSample(const vibro::Sample& s) override { samples.Add(s); }
  void OnSection(const vibro::Sample& s) override { section.Add(s); }

  struct Rows {
    std::vector<double> t, X, V, x_B;
    std::vector<std::int8_t> mode;
    void Add(const vibro::Sample& s) {
      t.push_back(s.t);
      X.insert(X.end(), s.X.data(), s.X.data() + s.X.size());
      V.insert(V.end(), s.V.data(), s.V.data() + s.V.size());
      x_B.push_back(s.x_B);
      mode.push_back(static_cast<std::int8_t>(s.mode));
    }
  };
  int dof_;
  std::vector<double> event_t, event_x_B, event_v_before, event_v_after;
  std::vector<std::int8_t> event_kind;
  Rows samples, section;
};

template <typename T>
py::array_t<T> Array(const std::vector<T>& v) {
  return py::array_t<T>(static_cast<py::ssize_t>(v.size()), v.data());
}

template <typename T>
py::array_t<T> Matrix(const std::vector<T>& v, int columns) {
  const auto rows = columns > 0 ? static_cast<py::ssize_t>(v.size()) / columns : 0;
  return py::array_t<T>(std::vector<py::ssize_t>{rows, columns}, v.data());
}

py::dict RowsDict(const Recorder::Rows& r, int dof) {
  py::dict d;
  d["t"] = Array(r.t);
  d["X"] = Matrix(r.X, dof);
  d["V"] = Matrix(r.V, dof);
  d["x_B"] = Array(r.x_B);
  d["mode"] = Array(r.mode);
  return d;
}

std::string Model(const PyScene& s) {
  const vibro::System sys(s.loaded.scene);
  return vibro::ModelJson(sys);
}

py::dict SimulateScene(const PyScene& s, const std::string& out, bool handle_sigint) {
  const auto& loaded = s.loaded;
  const vibro::System sys(loaded.scene);
  vibro::AttractorRecorder attractor_recorder(sys, loaded.scene);
  std::optional<vibro::LyapunovObserver> lyapunov;
  if (loaded.scene.run.lyapunov) lyapunov.emplace(sys, loaded.scene);
  Recorder recorder(sys.dof());
  std::unique_ptr<vibro::Hdf5Store> store;
  if (!out.empty()) store = vibro::Hdf5Store::Create(out, HeaderOf(loaded, sys));
  std::string json;
  bool interrupted = false;
  {
    py::gil_scoped_release release;
    SigintGuard guard(handle_sigint);
    vibro::SimulationOptions options;
    options.observers = {&attractor_recorder, &recorder};
    if (lyapunov) options.observers.push_back(&*lyapunov);
    if (store) options.observers.push_back(store.get());
    options.stop_requested = guard.flag();
    const auto result = vibro::Simulate(sys, loaded.scene, options);
    const auto attractor = attractor_recorder.Classify();
    if (store) store->Finish(result, attractor);
    std::optional<vibro::LyapunovSpectrum> spectrum;
    if (lyapunov) spectrum = lyapunov->Spectrum();
    json = vibro::SimulationJson(loaded.scene, result, attractor, spectrum ? &*spectrum : nullptr);
    interrupted = result.status == vibro::RunStatus::kInterrupted;
  }
  py::dict d;
  d["json"] = json;
  d["interrupted"] = interrupted;
  py::dict events;
  events["t"] = Array(recorder.event_t);
  events["kind"] = Array(recorder.event_kind);
  events["x_B"] = Array(recorder.event_x_B);
  events["v_before"] = Array(recorder.event_v_before);
  events["v_after"] = Array(recorder.event_v_after);
  d["events"] = events;
  d["samples"] = RowsDict(recorder.samples, sys.dof());
  d["section"] = RowsDict(recorder.section, sys.dof());
  return d;
}

vibro::OrbitKind KindOf(const std::string& kind) {
  if (kind == "auto") return vibro::OrbitKind::kAuto;
  if (kind == "sticking") return vibro::OrbitKind::kSticking;
  if (kind == "impact") return vibro::OrbitKind::kImpact;
  throw vibro::InputError({fmt::format("kind {}: expected \"auto\", \"sticking\" or \"impact\"", kind)});
}

std::string Orbit(const PyScene& s, const std::string& kind, int period, int impacts,
                  std::optional<double> guess_phase, std::optional<double> guess_velocity,
                  const std::string& out, int transient) {
  vibro::OrbitRequest req;
  req.kind = KindOf(kind);
  req.transient_periods = transient;
  req.period = period;
  req.impacts = impacts;
  req.guess_phase = guess_phase;
  req.guess_velocity = guess_velocity;
  const vibro::System sys(s.loaded.scene);
  if (!out.empty()) vibro::Hdf5Store::Create(out, HeaderOf(s.loaded, sys)).reset();  // fail early
  py::gil_scoped_release release;
  const auto orbit = vibro::SolveOrbit(sys, s.loaded.scene, req);
  // As the CLI: a failed solve still ends the file, with its status and message (never "running").
  if (!out.empty() && orbit.status == "converged") vibro::frontend::WriteOrbit(out, s.loaded, sys, orbit);
  else if (!out.empty()) vibro::frontend::WriteOrbitFailure(out, s.loaded, sys, orbit);
  return vibro::OrbitJson(orbit, req.kind);
}

std::pair<std::string, bool> ContinueBranch(const PyScene& s, const std::string& key, double to,
                                            double step, int max_points, int period,
                                            const std::string& kind, const std::string& out,
                                            bool handle_sigint) {
  const auto from = vibro::SceneNumber(s.loaded.text_as_run, key);
  if (!from)
    throw vibro::InputError({fmt::format("param {}: not a numeric key of the scene (give it in the "
                                         "scene or with set={{\"{}\": VALUE}})",
                                         key, key)});
  vibro::ContinuationRequest req;
  req.scene_at = [&](double v) { return vibro::frontend::SceneWith(s.origin, key, v); };
  req.from = *from;
  req.to = to;
  req.step = step;
  req.max_points = max_points;
  req.orbit.period = period;
  req.orbit.kind = KindOf(kind);
  const vibro::System sys(s.loaded.scene);
  std::unique_ptr<vibro::Hdf5Store> store;
  if (!out.empty()) store = vibro::Hdf5Store::Create(out, HeaderOf(s.loaded, sys));  // fails early
  py::gil_scoped_release release;
  SigintGuard guard(handle_sigint);
  req.stop_requested = guard.flag();
  auto branch = vibro::Continue(req);
  branch.param = key;
  if (store) {
    store->WriteBranch(branch);
    vibro::RunResult r;
    r.status = branch.status == "interrupted" ? vibro::RunStatus::kInterrupted : vibro::RunStatus::kOk;
    r.message = branch.end;
    store->Finish(r, vibro::frontend::NoAttractor());  // a branch has no single attractor (the points are in /branch)
  }
  return {vibro::BranchJson(branch), branch.status == "interrupted"};
}

py::dict Study(const PyScene& s, bool basin, const std::string& x, const std::string& y,
               const std::vector<double>& x_range, const std::vector<double>& y_range,
               const std::vector<int>& grid, long long samples, unsigned long long seed, int threads,
               bool full_periods, const std::string& out, bool handle_sigint) {
  const auto& loaded = s.loaded;
  const vibro::System sys(loaded.scene);
  std::vector<std::string> problems;
  for (const auto& [opt, name] : {std::pair{"x", x}, std::pair{"y", y}})
    if (auto p = vibro::CheckCoordinate(sys, name); !p.empty())
      problems.push_back(fmt::format("{} {}: {}", opt, name, p));
  const auto cx = vibro::frontend::StudyCoordinate(sys, x, x_range, "x_range", problems);
  const auto cy = vibro::frontend::StudyCoordinate(sys, y, y_range, "y_range", problems);
  if (basin && (grid.size() != 2 || grid[0] < 1 || grid[1] < 1))
    problems.push_back("grid: expected (NX, NY) with NX, NY ≥ 1");
  if (!basin && samples < 1) problems.push_back("samples: expected N ≥ 1");
  if (!problems.empty()) throw vibro::InputError(problems);
  const auto points = basin ? vibro::GridPoints(cx, cy, grid[0], grid[1])
                            : vibro::RandomPoints(cx, cy, samples, seed);
  const vibro::Hdf5Store::StudyGrid study_grid{cx, cy, basin ? grid[0] : static_cast<int>(points.size()),
                                               basin ? grid[1] : 1, !full_periods};
  std::vector<vibro::CellResult> cells(points.size());
  std::unique_ptr<vibro::Hdf5Store> store;
  if (!out.empty()) {
    store = vibro::Hdf5Store::Create(out, HeaderOf(loaded, sys));
    store->BeginStudy(study_grid);
  }
  vibro::StudyResult study;
  bool interrupted = false;
  {
    py::gil_scoped_release release;
    SigintGuard guard(handle_sigint);
    vibro::StudyOptions opt;
    opt.threads = threads;
    opt.stop_requested = guard.flag();
    if (full_periods) opt.settle_remainder = 0;
    if (!full_periods) opt.known = vibro::KnownOrbits(sys, loaded.scene, cx, cy, opt);
    const vibro::Distribution dist;  // one process (not started by mpirun)
    vibro::RunPendingCells(sys, loaded.scene, cx, cy, points, cells, opt, dist,
                           [&](const std::vector<size_t>& batch) {
                             if (store) store->WriteCells(batch, cells);
                           });
    interrupted = guard.interrupted();
    study = vibro::LabelCells(sys, loaded.scene, points, cells, opt);
    if (store) {
      vibro::frontend::FinishStudy(*store, study, study_grid, interrupted);
    }
  }
  py::dict d;
  d["json"] = vibro::StudyJson(study, cx, cy);
  d["interrupted"] = interrupted;
  d["labels"] = Array(study.labels);
  d["nx"] = study_grid.nx;
  d["ny"] = study_grid.ny;
  std::vector<double> px, py_;
  for (const auto& [a, b] : points) {
    px.push_back(a);
    py_.push_back(b);
  }
  d["x"] = Array(px);
  d["y"] = Array(py_);
  d["x_range"] = py::make_tuple(cx.from, cx.to);
  d["y_range"] = py::make_tuple(cy.from, cy.to);
  return d;
}

std::pair<std::string, bool> SweepScene(const PyScene& s, const std::string& key, double from, double to,
                                        int steps, int record, bool one_way, const std::string& out,
                                        bool handle_sigint) {
  std::vector<std::string> problems;
  if (steps < 1) problems.push_back(fmt::format("steps {}: expected N ≥ 1", steps));
  if (record < 1) problems.push_back(fmt::format("record {}: expected K ≥ 1", record));
  if (!problems.empty()) throw vibro::InputError(problems);
  for (double v : {from, to}) vibro::frontend::SceneWith(s.origin, key, v);
  std::unique_ptr<vibro::Hdf5Store> store;
  if (!out.empty())
    store = vibro::Hdf5Store::Create(out, HeaderOf(s.loaded, vibro::System(s.loaded.scene)));
  vibro::SweepRequest req;
  req.scene_at = [&](double v) { return vibro::frontend::SceneWith(s.origin, key, v); };
  req.from = from;
  req.to = to;
  req.steps = steps;
  req.record = record;
  req.both_ways = !one_way;
  py::gil_scoped_release release;
  SigintGuard guard(handle_sigint);
  const auto sweep = vibro::Sweep(req, guard.flag());
  const bool interrupted = guard.interrupted();
  if (store) {
    store->WriteSweep(sweep, {key, from, to, steps, record, !one_way});
    store->Finish(vibro::frontend::SweepOutcome(sweep, key, interrupted),
                  sweep.empty() ? vibro::Attractor{} : sweep.back().attractor);
  }
  return {vibro::SweepJson(sweep), interrupted};
}

std::string Check(const PyScene& s) {
  const vibro::System sys(s.loaded.scene);
  py::gil_scoped_release release;
  return vibro::CheckJson(vibro::CrossCheck(sys, s.loaded.scene));
}

std::string Info(const std::string& path) { return vibro::StoredRunJson(vibro::ReadStoredRun(path)); }

// vibro validate: a branch from another tool, point by point (frontend/commands.hpp).
std::pair<std::string, bool> Validate(const PyScene& s, const std::string& csv, const std::string& param,
                                      const std::string& kind, int period, double tolerance,
                                      double sticking_tolerance, const std::string& out, bool handle_sigint) {
  const vibro::frontend::ValidationSpec spec{csv, param, KindOf(kind), period, tolerance, sticking_tolerance};
  const auto job = vibro::frontend::PrepareValidation(s.origin, s.loaded, spec, vibro::frontend::Naming::kPython);
  std::unique_ptr<vibro::Hdf5Store> store;
  if (!out.empty()) store = vibro::Hdf5Store::Create(out, HeaderOf(s.loaded, vibro::System(s.loaded.scene)));
  py::gil_scoped_release release;
  SigintGuard guard(handle_sigint);
  const auto result = vibro::frontend::RunValidation(job, spec, guard.flag());
  if (store) vibro::frontend::FinishValidation(*store, job, result);
  return {vibro::ValidationJson(result.checks), result.interrupted};
}

// vibro score: another simulator's events against vibro's run (frontend/commands.hpp). Returns
// the JSON, whether it was interrupted, and vibro's own run status and message.
std::tuple<std::string, bool, std::string, std::string> Score(const PyScene& s, const std::string& csv,
                                                              double window, double tolerance, bool handle_sigint) {
  py::gil_scoped_release release;
  SigintGuard guard(handle_sigint);
  const auto r = vibro::frontend::ScoreEventsCsv(s.loaded, csv, window, tolerance, guard.flag(),
                                                 vibro::frontend::Naming::kPython);
  return {vibro::ScoreJson(r.report, r.scene), r.run.status == vibro::RunStatus::kInterrupted,
          vibro::ToString(r.run.status), r.run.message};
}

// vibro partition: curves of constant sticking fraction in a parameter plane.
std::pair<std::string, bool> PartitionPlane(const PyScene& s, const std::vector<std::string>& params,
                                            const std::vector<double>& range1, const std::vector<double>& range2,
                                            const std::vector<double>& levels, int steps1,
                                            std::optional<double> from2, int period, int threads,
                                            const std::string& out, bool handle_sigint) {
  vibro::frontend::PartitionSpec spec;
  spec.params = params;
  spec.range1 = range1;
  spec.range2 = range2;
  spec.levels = levels;
  spec.steps1 = steps1;
  spec.from2 = from2;
  spec.period = period;
  spec.threads = threads;
  auto req = vibro::frontend::PartitionRequestFor(s.origin, s.loaded, spec, vibro::frontend::Naming::kPython);
  std::unique_ptr<vibro::Hdf5Store> store;
  if (!out.empty()) store = vibro::Hdf5Store::Create(out, HeaderOf(s.loaded, vibro::System(s.loaded.scene)));
  py::gil_scoped_release release;
  SigintGuard guard(handle_sigint);
  req.stop_requested = guard.flag();
  const auto columns = vibro::Partition(req);
  const bool interrupted = guard.interrupted();
  if (store) vibro::frontend::FinishPartition(*store, spec, columns, interrupted);
  return {vibro::PartitionJson(params[0], params[1], levels, columns), interrupted};
}

}  // namespace

PYBIND11_MODULE(_vibro, m) {
  m.doc() = "vibro's C++ core; use the package `vibro`, not this module";
  m.attr("version") = VIBRO_VERSION;
  m.attr("git_commit") = VIBRO_GIT_COMMIT;

  // Bad input (scene, option, file): ValueError with every located message, one per line.
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const vibro::InputError& e) {
      std::string text;
      for (const auto& msg : e.messages()) text += (text.empty() ? "" : "\n") + msg;
      PyErr_SetString(PyExc_ValueError, text.c_str());
    }
  });

  py::class_<PyScene>(m, "_Scene")
      .def_property_readonly("text", [](const PyScene& s) { return s.loaded.text_as_run; })
      .def_property_readonly("source", [](const PyScene& s) { return s.loaded.source; })
      .def_property_readonly("title", [](const PyScene& s) { return s.loaded.scene.title; });
  m.def("load_scene", [](const std::string& path, const std::vector<std::string>& sets) {
    return LoadPyScene(SceneOrigin{path, std::nullopt, path, sets});
  });
  m.def("parse_scene", [](const std::string& text, const std::string& source,
                          const std::vector<std::string>& sets) {
    return LoadPyScene(SceneOrigin{"", text, source, sets});
  });
  m.def("set_invocation", [](const std::string& command, const std::string& call,
                             const std::string& options, bool force) {
    vibro::frontend::SetInvocation({command, call, options, force});
  });
  m.def("model", &Model);
  m.def("simulate", &SimulateScene);
  m.def("orbit", &Orbit);
  m.def("continue_branch", &ContinueBranch);
  m.def("study", &Study);
  m.def("sweep", &SweepScene);
  m.def("check", &Check);
  m.def("info", &Info);
  m.def("validate", &Validate);
  m.def("score", &Score);
  m.def("partition", &PartitionPlane);
}
