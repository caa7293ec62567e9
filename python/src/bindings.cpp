// The extension module vibro._vibro: the only file that includes pybind11. It runs each command
// with the same library calls as the command line (src/cli/cmd_*.cpp, src/frontend/) and returns
// the same JSON text as `--json` (src/io/summary_json.cpp), which python/vibro/__init__.py turns
// into dicts and numpy arrays.
//
// Every computation and every HDF5 call releases the GIL (a file's calls are serialised by the
// library, src/io, and must never wait for the GIL). When called from Python's main thread, SIGINT
// (Ctrl-C) and SIGTERM are routed to the library's stop flag for the duration of the call, also as the process's
// stop flag (vibro/stop_request.hpp) that every run polls, those deep inside an orbit solve or a
// cross-check too: the run stops cleanly at its next check, everything is written to the output
// file, and the result says "interrupted" (the Python layer then raises KeyboardInterrupt).
// Python's own handler is restored afterwards.
//
// Arguments are checked as the command line checks its options (frontend/limits.hpp: the same
// limits, named as Python's keyword arguments); tables may be given as columns of numbers instead
// of CSV files (frontend/tables.hpp).
#include <signal.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <map>
#include <memory>
#include <mutex>
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
#include "frontend/curves.hpp"
#include "vibro/curve_output.hpp"
#include "frontend/frontend.hpp"
#include "frontend/limits.hpp"
#include "frontend/run_budget.hpp"
#include "frontend/run_output.hpp"
#include "frontend/rigid_model.hpp"
#include "frontend/switching.hpp"
#include "frontend/diagram.hpp"
#include "frontend/tables.hpp"
#include "vibro/attractor.hpp"
#include "vibro/rigid_model.hpp"
#include "vibro/check.hpp"
#include "vibro/continuation.hpp"
#include "vibro/distribute.hpp"
#include "vibro/hdf5_branch.hpp"
#include "vibro/hdf5_store.hpp"
#include "vibro/loads.hpp"
#include "vibro/lyapunov.hpp"
#include "vibro/orbit_from_state.hpp"
#include "vibro/poincare.hpp"
#include "vibro/prove.hpp"
#include "vibro/scene_file.hpp"
#include "vibro/simulator.hpp"
#include "vibro/stop_request.hpp"
#include "vibro/studies.hpp"
#include "vibro/summary_json.hpp"
#include "vibro/system.hpp"

namespace py = pybind11;

namespace {

using vibro::frontend::HeaderOf;
using vibro::frontend::SceneOrigin;
constexpr auto kPython = vibro::frontend::Naming::kPython;

// File names of the arguments: refused with a NUL (frontend::CheckPath).
void CheckPaths(std::initializer_list<std::pair<const char*, const std::string*>> paths) {
  std::vector<std::string> problems;
  for (const auto& [name, path] : paths) vibro::frontend::CheckPath(kPython, name, *path, problems);
  vibro::frontend::ThrowIfAny(problems);
}

// Creates the output file `out` (nothing when empty) without the GIL.
std::unique_ptr<vibro::Hdf5Store> CreateStore(const std::string& out, const vibro::StoreHeader& header) {
  if (out.empty()) return nullptr;
  CheckPaths({{"out", &out}});
  py::gil_scoped_release release;
  return vibro::Hdf5Store::Create(out, header);
}

// A scene as loaded: where it came from (to re-derive it with one key changed) and as run.
struct PyScene {
  SceneOrigin origin;
  vibro::LoadedScene loaded;
};

PyScene LoadPyScene(SceneOrigin origin) {
  auto loaded = origin.Load();
  return {std::move(origin), std::move(loaded)};
}

// The entry check of a command on a scene (frontend/rigid_model.hpp, as on the command line):
// the analyses built on the rigid model refuse a compliant stop (ValueError) before computing
// anything. `command` is the command line's name of the function.
template <typename R, typename... A>
auto Entry(const char* command, R (*f)(const PyScene&, A...)) {
  return [command, f](const PyScene& s, A... a) -> R {
    vibro::frontend::CheckSceneModel(command, s.loaded, s.origin.source.empty() ? s.origin.path : s.origin.source,
                                     kPython);
    return f(s, std::forward<A>(a)...);
  };
}

// SIGINT and SIGTERM → stop flag while a computation runs (main thread only; see the file comment).
std::atomic<bool> g_sigint{false};
std::atomic<int> g_stop_signal{0};  // the signal that stopped the computation
extern "C" void OnStopSignal(int sig) {
  g_stop_signal.store(sig);
  g_sigint.store(true);
}

// Constructed with the GIL held (before the computation releases it): a signal that came before
// the handler was installed (while the scene was read or the output file created) went to
// Python's handler and is found by PyErr_CheckSignals, after the installation, so none is lost.
// SIGTERM stops the computation as Ctrl-C does (the Python layer raises KeyboardInterrupt, the
// files keep what was computed), unless it is ignored (then it stays ignored); when the program
// had set a handler of its own for it (signal.signal), the signal is raised again once that
// handler is back, so that the handler runs as it would have.
class SigintGuard {
 public:
  explicit SigintGuard(bool install) : installed_(install) {
    if (!installed_) return;
    g_sigint.store(false);
    g_stop_signal.store(0);
    struct sigaction action = {};
    action.sa_handler = OnStopSignal;
    sigemptyset(&action.sa_mask);
    sigaction(SIGINT, &action, &previous_);
    sigaction(SIGTERM, nullptr, &previous_term_);
    term_routed_ = (previous_term_.sa_flags & SA_SIGINFO) != 0 || previous_term_.sa_handler != SIG_IGN;
    if (term_routed_) sigaction(SIGTERM, &action, nullptr);
    previous_flag_ = vibro::ProcessStopFlag();
    vibro::SetProcessStopFlag(&g_sigint);
    if (PyErr_CheckSignals() != 0) {  // raised by Python's handler: a stop request, reported as one
      PyErr_Clear();
      g_sigint.store(true);
    }
  }
  ~SigintGuard() {
    if (!installed_) return;
    vibro::SetProcessStopFlag(previous_flag_);
    sigaction(SIGINT, &previous_, nullptr);
    if (term_routed_) {
      sigaction(SIGTERM, &previous_term_, nullptr);
      const bool has_handler = (previous_term_.sa_flags & SA_SIGINFO) != 0 || previous_term_.sa_handler != SIG_DFL;
      if (g_stop_signal.load() == SIGTERM && has_handler) raise(SIGTERM);
    }
  }
  SigintGuard(const SigintGuard&) = delete;
  SigintGuard& operator=(const SigintGuard&) = delete;

  const std::atomic<bool>* flag() const { return installed_ ? &g_sigint : &local_; }
  bool interrupted() const { return flag()->load(); }
  // Stops the computation as a Ctrl-C would (a progress callback that raised: ProgressRelay).
  void RequestStop() { (installed_ ? g_sigint : local_).store(true); }

 private:
  bool installed_;
  struct sigaction previous_ = {}, previous_term_ = {};
  bool term_routed_ = false;
  const std::atomic<bool>* previous_flag_ = nullptr;
  std::atomic<bool> local_{false};  // the stop flag off the main thread (no SIGINT routed)
};

// Progress reported to a Python callable progress(done, total) from any thread of a computation
// (the GIL released): kInterval seconds or more after the end of the previous call (never a call
// due at once when a slow one returns: the work goes on between calls), the GIL taken for the call, the calls of
// several threads serialised (a thread finding another one calling skips its report). An
// exception raised by the callable stops the computation (as Ctrl-C does) and is raised again by
// Finish(), after one last report of the state reached, with the GIL held.
class ProgressRelay {
 public:
  static constexpr double kInterval = 0.1;  // at least this long between two calls

  ProgressRelay(py::object callback, SigintGuard& guard) : callback_(std::move(callback)), guard_(guard) {}
  ProgressRelay(const ProgressRelay&) = delete;
  ProgressRelay& operator=(const ProgressRelay&) = delete;

  bool active() const { return !callback_.is_none(); }

  // done of total units; called without the GIL. The state reached is kept even when this report
  // is skipped (another thread calling), so that Finish() reports it.
  void Update(long long done, long long total) {
    if (!active()) return;
    {
      std::lock_guard state(state_mutex_);
      if (total != reached_total_) {
        reached_total_ = total;
        reached_ = done;
      } else {
        reached_ = std::max(reached_, done);  // never backwards
      }
    }
    std::unique_lock lock(mutex_, std::try_to_lock);
    if (!lock.owns_lock()) return;
    if (!Take()) return;
    if (failed_ || std::chrono::duration<double>(Clock::now() - last_).count() < kInterval) return;
    Call();
    // The interval counts from the end of the call: a callback slower than kInterval gets fewer
    // calls, and the computation still has kInterval of every kInterval + (the call's duration).
    last_ = Clock::now();
  }

  // The last report (the state reached), with the GIL held; raises the callback's exception.
  void Finish() {
    if (!active()) return;
    if (!failed_) {
      py::gil_scoped_release release;  // Call() takes it, as from a worker thread
      std::lock_guard lock(mutex_);
      Take();
      if (done_ >= 0) Call();
    }
    if (error_) {
      std::shared_ptr<py::error_already_set> error = std::move(error_);
      throw *error;
    }
  }

 private:
  using Clock = std::chrono::steady_clock;
  // mutex_ held: the state reached into done_, total_; false when it is not new.
  bool Take() {
    std::lock_guard state(state_mutex_);
    if (reached_ <= done_ && reached_total_ == total_) return false;
    done_ = reached_;
    total_ = reached_total_;
    return true;
  }
  // mutex_ held, GIL not held.
  void Call() {
    py::gil_scoped_acquire gil;
    try {
      callback_(done_, total_);
    } catch (py::error_already_set& e) {
      error_ = std::make_shared<py::error_already_set>(std::move(e));
      failed_ = true;
      guard_.RequestStop();
    }
  }
  py::object callback_;
  SigintGuard& guard_;
  std::mutex mutex_;        // held while reporting (the Python call)
  long long done_ = -1, total_ = 0;  // the state last reported
  std::mutex state_mutex_;  // held for a few instructions: the state reached
  long long reached_ = -1, reached_total_ = 0;
  Clock::time_point last_ = Clock::now();
  bool failed_ = false;
  std::shared_ptr<py::error_already_set> error_;
};

// Period-by-period progress of one run (the section is reached once a period): the section's
// period of the run's `periods` (a resumed run starts at its checkpoint's).
class PeriodRelay final : public vibro::Observer {
 public:
  PeriodRelay(ProgressRelay& relay, long long periods) : relay_(relay), periods_(periods) {}
  void OnSection(const vibro::Sample& sample) override { relay_.Update(sample.clock.period, periods_); }

 private:
  ProgressRelay& relay_;
  long long periods_;
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
    event_contact.push_back(static_cast<std::int32_t>(e.contact));
    event_simultaneous.push_back(e.simultaneous ? 1 : 0);
    event_impulse.push_back(e.impulse);
    event_energy.push_back(e.energy_dissipated);
    event_stick_duration.push_back(e.stick_duration);
    event_reaction_integral.push_back(e.reaction_integral);
    event_reaction_max.push_back(e.reaction_max);
    event_peak_time.push_back(e.peak_time);
    event_penetration_max.push_back(e.penetration_max);
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
  std::vector<std::int32_t> event_contact;  // the [[contact]] index (docs/contacts.md)
  std::vector<std::uint8_t> event_simultaneous;
  // What the contacts endure (docs/loads.md).
  std::vector<double> event_impulse, event_energy, event_stick_duration, event_reaction_integral,
      event_reaction_max;
  // A compliant contact phase's peak instant and largest penetration (docs/compliant.md).
  std::vector<double> event_peak_time, event_penetration_max;
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

// vibro simulate [--out FILE [--resume | --extend N]] (src/cli/cmd_simulate.cpp): the scene, the
// output and its checks are the command line's (frontend/run_output.hpp).
py::dict SimulateScene(const PyScene& s, const std::string& out, bool resume, std::optional<long long> extend,
                       const py::object& progress, bool handle_sigint, int blocks, double time_limit) {
  if (!out.empty()) CheckPaths({{"out", &out}});
  if (!(time_limit >= 0) || !(time_limit <= 1e12))
    throw vibro::InputError({fmt::format("time_limit {}: expected seconds in [0, 1e12] (0: none)", time_limit)});
  const vibro::frontend::RunContinuation how{resume, extend};
  const auto loaded = [&] {
    py::gil_scoped_release release;  // an extension reads the file
    return vibro::frontend::SceneToRun(s.loaded, out, how, kPython);
  }();
  const vibro::System sys(loaded.scene);
  vibro::AttractorRecorder attractor_recorder(sys, loaded.scene);
  std::optional<vibro::LyapunovObserver> lyapunov;
  Recorder recorder(sys.dof());
  vibro::SimulationOptions options;
  // Contact loads (docs/loads.md), the first tenth of the periods left out, as the command line.
  vibro::LoadsRecorder loads(sys, loaded.scene.run.periods / 10);
  options.observers = {&attractor_recorder, &recorder, &loads};
  if (loaded.scene.run.lyapunov && !vibro::HasCompliantContact(loaded.scene))  // as `vibro simulate`
    options.observers.push_back(&lyapunov.emplace(sys, loaded.scene));
  std::optional<vibro::frontend::RunOutput> output;
  {
    py::gil_scoped_release release;
    output.emplace(out, loaded, sys, how, attractor_recorder, &loads, options, kPython);
  }
  std::string json;
  bool interrupted = false;
  SigintGuard guard(handle_sigint);
  ProgressRelay relay(progress, guard);
  PeriodRelay periods(relay, loaded.scene.run.periods);
  if (relay.active()) options.observers.push_back(&periods);
  // The time and disk limits against the run's event rate, as `vibro simulate --time-limit`:
  // vibro.LimitError, the output file keeping what was written up to its last flush.
  vibro::frontend::RunBudget budget(sys, loaded.scene, time_limit, out, "time_limit");
  options.observers.push_back(&budget);
  {
    py::gil_scoped_release release;
    options.stop_requested = guard.flag();
    auto result = vibro::Simulate(sys, loaded.scene, options);
    output->NoteInterruption(result, kPython);
    const auto attractor = attractor_recorder.Classify();
    output->Finish(result, attractor);
    output.reset();  // closed without the GIL
    std::optional<vibro::LyapunovSpectrum> spectrum;
    if (lyapunov) spectrum = lyapunov->Spectrum();
    const vibro::LoadsSummary load_summary = loads.Summary(blocks);
    json = vibro::SimulationJson(loaded.scene, result, attractor, spectrum ? &*spectrum : nullptr, &load_summary);
    interrupted = result.status == vibro::RunStatus::kInterrupted;
  }
  relay.Finish();
  py::dict d;
  d["json"] = json;
  d["interrupted"] = interrupted;
  d["periods"] = loaded.scene.run.periods;  // the run's total (an extension's new total)
  py::dict events;
  events["t"] = Array(recorder.event_t);
  events["kind"] = Array(recorder.event_kind);
  events["x_B"] = Array(recorder.event_x_B);
  events["v_before"] = Array(recorder.event_v_before);
  events["v_after"] = Array(recorder.event_v_after);
  events["contact"] = Array(recorder.event_contact);
  events["simultaneous"] = Array(recorder.event_simultaneous);
  events["impulse"] = Array(recorder.event_impulse);
  events["energy_dissipated"] = Array(recorder.event_energy);
  events["stick_duration"] = Array(recorder.event_stick_duration);
  events["reaction_integral"] = Array(recorder.event_reaction_integral);
  events["reaction_max"] = Array(recorder.event_reaction_max);
  events["peak_time"] = Array(recorder.event_peak_time);
  events["penetration_max"] = Array(recorder.event_penetration_max);
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

// The JSON of the orbit, and whether a stop request cut the solve short (then `out` is removed, as
// the command line removes it: an orbit is found whole or not at all).
std::pair<std::string, bool> Orbit(const PyScene& s, const std::string& kind, long long period, long long impacts,
                                   std::optional<double> guess_phase, std::optional<double> guess_velocity,
                                   const std::string& out, long long transient, bool handle_sigint) {
  vibro::frontend::CheckOrbitOptions(kPython, period, impacts, transient, guess_phase, guess_velocity);
  vibro::OrbitRequest req;
  req.kind = KindOf(kind);
  req.transient_periods = static_cast<int>(transient);
  req.period = static_cast<int>(period);
  req.impacts = static_cast<int>(impacts);
  req.guess_phase = guess_phase;
  req.guess_velocity = guess_velocity;
  const vibro::System sys(s.loaded.scene);
  CreateStore(out, HeaderOf(s.loaded, sys)).reset();  // fail early
  SigintGuard guard(handle_sigint);
  py::gil_scoped_release release;
  auto orbit = vibro::SolveOrbit(sys, s.loaded.scene, req);
  // As the CLI: reported from the start of its contact sequence's canonical rotation (docs/orbits.md).
  vibro::StartAtCanonicalRotation(sys, s.loaded.scene, req, orbit);
  if (guard.interrupted()) {
    if (!out.empty()) std::remove(out.c_str());
    return {"", true};
  }
  // As the CLI: a failed solve still ends the file, with its status and message (never "running").
  if (!out.empty() && orbit.status == "converged") vibro::frontend::WriteOrbit(out, s.loaded, sys, orbit);
  else if (!out.empty()) vibro::frontend::WriteOrbitFailure(out, s.loaded, sys, orbit);
  // The orbit's exact per-period contact loads (docs/loads.md), as `vibro orbit --json`.
  const bool converged = orbit.status == "converged";
  const vibro::LoadsSummary loads = converged ? vibro::OrbitLoads(sys, s.loaded.scene, orbit) : vibro::LoadsSummary{};
  std::string text = vibro::OrbitJson(orbit, req.kind, converged ? &loads : nullptr);
  // A compliant stop (docs/compliant.md, "Periodic orbits"): the rigid model's orbit beside it, as the CLI.
  if (converged && vibro::HasCompliantContact(s.loaded.scene))
    text = text.substr(0, text.rfind('}')) + ",\"rigid_model\":" +
           vibro::RigidOrbitJson(vibro::CompareOrbitWithRigid(s.loaded.scene, sys, orbit, req)) + "}";
  return {text, false};
}

// vibro.prove: the summary and the certificate of `vibro prove` (docs/prove.md), as JSON texts,
// and whether a stop request (Ctrl-C) ended it (then nothing is proven and the caller raises).
std::tuple<std::string, std::string, bool> Prove(const PyScene& s, const std::string& kind, long long period,
                                                 long long transient, const std::string& from, double time_limit,
                                                 bool handle_sigint) {
  vibro::frontend::CheckOrbitOptions(kPython, period, 0, transient, std::nullopt, std::nullopt);
  if (!(time_limit > 0) || !std::isfinite(time_limit))
    throw vibro::InputError({fmt::format("time_limit {}: expected a positive number of seconds", time_limit)});
  vibro::ProofRequest req;
  req.kind = KindOf(kind);
  req.period = static_cast<int>(period);
  req.transient_periods = static_cast<int>(transient);
  req.time_limit = time_limit;
  const vibro::System sys(s.loaded.scene);
  if (!from.empty()) {
    req.start = vibro::ReadOrbitSection(from);
    if (req.start->X.size() != sys.dof())
      throw vibro::InputError({fmt::format("from {}: an orbit of {} modes, the scene has {}", from,
                                           req.start->X.size(), sys.dof())});
  }
  SigintGuard guard(handle_sigint);
  py::gil_scoped_release release;
  req.stop_requested = guard.flag();
  const auto r = vibro::ProveOrbit(sys, s.loaded.scene, req);
  if (r.interrupted || guard.interrupted()) return {"", "", true};
  return {r.summary_json, r.certificate_json, false};
}

// vibro.prove_bifurcation: `vibro prove --bifurcation KIND:KEY=VALUE` (docs/prove.md "Bifurcation
// points"): the summary and the certificate as JSON texts, and whether a stop request ended it.
std::tuple<std::string, std::string, bool> ProveBifurcationPoint(const PyScene& s, const std::string& kind,
                                                                 const std::string& key, double value,
                                                                 double time_limit, bool handle_sigint,
                                                                 const std::string& branch) {
  if (!(time_limit > 0) || !std::isfinite(time_limit))
    throw vibro::InputError({fmt::format("time_limit {}: expected a positive number of seconds", time_limit)});
  if (!std::isfinite(value)) throw vibro::InputError({fmt::format("value {}: expected a finite number", value)});
  vibro::BifurcationRequest req;
  req.kind = kind;
  req.parameter = key;
  req.value = value;
  req.time_limit = time_limit;
  if (!branch.empty()) {  // a grazing's orbit: the stored point nearest it, as `prove --from BRANCH.h5`
    // (the point before the branch's bifurcation of this kind at this value, when it stores one:
    // a branch through a grazing may pass the same value again on other orbits)
    const double apart = 1e-6 * (1 + std::abs(value));
    const auto near = vibro::NearestBranchPoint(branch, value, apart, vibro::BifurcationPointNear(branch, kind, value, apart));
    if (near.param != key)
      throw vibro::InputError({fmt::format("branch {}: a branch in {}, not {}", branch, near.param, key)});
    req.start = vibro::InitialOverride{near.section_time, near.X, near.V};
    req.period = near.period;
    req.start_value = near.value;
  }
  const vibro::Scene scene = vibro::frontend::SceneWith(s.origin, key, value);
  const vibro::System sys(scene);
  SigintGuard guard(handle_sigint);
  py::gil_scoped_release release;
  req.stop_requested = guard.flag();
  const auto r = vibro::ProveBifurcation(sys, scene, req);
  if (r.interrupted || guard.interrupted()) return {"", "", true};
  return {r.summary_json, r.certificate_json, false};
}

// vibro.prove_segment: the segment of `vibro prove --branch` between two parameter values of a
// branch (docs/prove.md "Along a branch"): every orbit for every value of [lo, hi] at once, halved
// as the CLI does. Each end's orbit is the branch's stored point nearest it (within 1e-9 relative),
// or without a branch the one the scene's start reaches. The summaries and the certificates of the
// pieces as JSON lists, and whether a stop request ended it.
std::tuple<std::string, std::string, bool> ProveSegment(const PyScene& s, const std::string& key, double lo, double hi,
                                                        const std::string& branch, double time_limit,
                                                        bool handle_sigint) {
  if (!(time_limit > 0) || !std::isfinite(time_limit))
    throw vibro::InputError({fmt::format("time_limit {}: expected a positive number of seconds", time_limit)});
  if (!std::isfinite(lo) || !std::isfinite(hi) || !(lo < hi))
    throw vibro::InputError({fmt::format("lo {}, hi {}: expected two finite numbers, lo < hi", lo, hi)});
  std::array<vibro::Scene, 2> scenes{vibro::frontend::SceneWith(s.origin, key, lo),
                                     vibro::frontend::SceneWith(s.origin, key, hi)};
  std::array<vibro::ProofRequest, 2> reqs;
  for (int e = 0; e < 2; ++e) {
    reqs[e].time_limit = time_limit;
    if (branch.empty()) continue;
    const double v = e ? hi : lo;
    const auto near = vibro::NearestBranchPoint(branch, v, 1e-9 * (1 + std::abs(v)));
    if (near.param != key)
      throw vibro::InputError({fmt::format("branch {}: a branch in {}, not {}", branch, near.param, key)});
    if (std::abs(near.value - v) > 1e-9 * (1 + std::abs(v)))
      throw vibro::InputError({fmt::format("branch {}: no stored point at {} = {} (the nearest is at {})", branch,
                                           key, v, near.value)});
    reqs[e].start = vibro::InitialOverride{near.section_time, near.X, near.V};
    reqs[e].period = near.period;
  }
  const vibro::System lo_sys(scenes[0]), hi_sys(scenes[1]);
  SigintGuard guard(handle_sigint);
  py::gil_scoped_release release;
  for (auto& r : reqs) r.stop_requested = guard.flag();
  const auto pieces = vibro::ProveOrbitOverInterval(lo_sys, scenes[0], reqs[0], hi_sys, scenes[1], reqs[1]);
  if (pieces.front().interrupted || guard.interrupted()) return {"", "", true};
  std::string summaries = "[", certificates = "[";
  for (const auto& piece : pieces) {
    summaries += (summaries.size() > 1 ? ", " : "") + piece.summary_json;
    if (!piece.certificate_json.empty()) certificates += (certificates.size() > 1 ? ", " : "") + piece.certificate_json;
  }
  return {summaries + "]", certificates + "]", false};
}

std::pair<std::string, bool> ContinueBranch(const PyScene& s, const std::string& key, double to,
                                            double step, long long max_points, long long period,
                                            const std::string& kind, const std::string& out,
                                            bool handle_sigint, const std::string& restart_file,
                                            long long restart_point, const std::string& switch_side) {
  std::optional<vibro::frontend::SwitchedStart> switched;  // the switch, for the JSON
  vibro::frontend::CheckContinuationOptions(kPython, to, step, max_points, period, 0);
  const auto from = vibro::SceneNumber(s.loaded.text_as_run, key);
  if (!from)
    throw vibro::InputError({fmt::format("param {}: not a numeric key of the scene (give it in the "
                                         "scene or with set={{\"{}\": VALUE}})",
                                         key, key)});
  vibro::ContinuationRequest req;
  req.scene_at = [&](double v) { return vibro::frontend::SceneWith(s.origin, key, v); };
  req.from = *from;
  // from_=FILE, point=K: Newton from the stored point's orbit (no transient); with switch=True the
  // first orbit of the other branch through the branch-point or flip next to it (docs/orbits.md).
  if (!restart_file.empty()) {
    const auto pt = vibro::ReadBranchPoint(restart_file, restart_point);
    if (pt.param != key)
      throw vibro::InputError({fmt::format("from_ {}: the branch varies {}, not param {}", restart_file, pt.param, key)});
    if (pt.X.size() != vibro::System(s.loaded.scene).dof())
      throw vibro::InputError({fmt::format("from_ {}: /branch/X has {} columns (modal coordinates), the scene has "
                                           "{} mode(s): a branch of another scene",
                                           restart_file, pt.X.size(), vibro::System(s.loaded.scene).dof())});
    req.from = pt.value;
    req.orbit.start = vibro::InitialOverride{pt.section_time, pt.X, pt.V};
    req.orbit.transient_periods = 0;
    period = pt.period;
    if (!switch_side.empty()) {
      vibro::frontend::SwitchedStart sw;
      {
        SigintGuard guard(handle_sigint);
        py::gil_scoped_release release;
        sw = vibro::frontend::SwitchAtStoredPoint(req.scene_at, key, to, restart_file, restart_point, pt, switch_side,
                                                  kPython, guard.flag());
      }
      switched = sw;
      req.from = sw.value;
      req.orbit.start = vibro::InitialOverride{sw.section_time, sw.X, sw.V};
      period = sw.period;
    }
  }
  req.to = to;
  req.step = step;
  req.max_points = static_cast<int>(max_points);
  req.orbit.period = static_cast<int>(period);
  req.orbit.kind = KindOf(kind);
  const vibro::System sys(s.loaded.scene);
  auto store = CreateStore(out, HeaderOf(s.loaded, sys));  // fails early
  SigintGuard guard(handle_sigint);
  py::gil_scoped_release release;
  req.stop_requested = guard.flag();
  auto branch = vibro::Continue(req);
  branch.param = key;
  // A compliant stop: the rigid model's orbit beside every point (docs/compliant.md).
  if (vibro::HasCompliantContact(s.loaded.scene))
    vibro::AddRigidModelAlongBranch(branch, req.scene_at, req.orbit, guard.flag());
  if (store) {
    store->WriteBranch(branch);
    vibro::RunResult r;
    r.status = branch.status == "interrupted" ? vibro::RunStatus::kInterrupted : vibro::RunStatus::kOk;
    r.message = branch.end;
    store->Finish(r, vibro::frontend::NoAttractor());  // a branch has no single attractor (the points are in /branch)
    store.reset();  // closed without the GIL
  }
  if (switched)
    return {vibro::BranchJson(branch, {switched->kind, switched->at, switched->value, switched->period,
                                       switched->direction, switched->half, switched->x_B_offset, switched->distance}),
            branch.status == "interrupted"};
  return {vibro::BranchJson(branch), branch.status == "interrupted"};
}

py::dict Study(const PyScene& s, bool basin, const std::string& x, const std::string& y,
               const std::vector<double>& x_range, const std::vector<double>& y_range,
               const std::vector<long long>& grid, long long samples, unsigned long long seed, long long threads,
               bool full_periods, const std::string& out, bool resume, const py::object& progress,
               bool handle_sigint) {
  const auto& loaded = s.loaded;
  vibro::frontend::CheckStudyResume(out, resume, kPython);
  const vibro::System sys(loaded.scene);
  vibro::frontend::StudySpec spec;
  spec.x = x;
  spec.y = y;
  spec.x_range = x_range;
  spec.y_range = y_range;
  spec.grid = grid;
  spec.samples = samples;
  spec.threads = threads;
  const auto axes = vibro::frontend::CheckStudyOptions(sys, spec, basin, kPython);
  const vibro::Coordinate& cx = axes.x;
  const vibro::Coordinate& cy = axes.y;
  const int nx = basin ? static_cast<int>(grid[0]) : 0, ny = basin ? static_cast<int>(grid[1]) : 0;
  const auto points = basin ? vibro::GridPoints(cx, cy, nx, ny) : vibro::RandomPoints(cx, cy, samples, seed);
  const vibro::Hdf5Store::StudyGrid study_grid{cx, cy, basin ? nx : static_cast<int>(points.size()),
                                               basin ? ny : 1, !full_periods};
  std::vector<vibro::CellResult> cells(points.size());
  if (!out.empty()) CheckPaths({{"out", &out}});
  std::unique_ptr<vibro::Hdf5Store> store;
  {
    const auto header = HeaderOf(loaded, sys);
    py::gil_scoped_release release;
    store = vibro::frontend::OpenStudyOutput(out, header, study_grid, resume, cells, kPython);
  }
  vibro::StudyResult study;
  bool interrupted = false;
  SigintGuard guard(handle_sigint);
  ProgressRelay relay(progress, guard);
  {
    py::gil_scoped_release release;
    vibro::StudyOptions opt;
    opt.threads = static_cast<int>(threads);
    opt.stop_requested = guard.flag();
    if (relay.active()) opt.progress = [&relay](long long done, long long total) { relay.Update(done, total); };
    if (full_periods) opt.settle_remainder = 0;
    if (!full_periods) opt.known = vibro::KnownOrbits(sys, loaded.scene, cx, cy, opt);
    const vibro::Distribution dist;  // one process (not started by mpirun)
    vibro::RunPendingCells(sys, loaded.scene, cx, cy, points, cells, opt, dist,
                           [&](const std::vector<size_t>& batch) {
                             if (store) store->WriteCells(batch, cells);
                           });
    interrupted = guard.interrupted();
    opt.progress = nullptr;
    study = vibro::LabelCells(sys, loaded.scene, points, cells, opt);
    if (store) {
      vibro::frontend::FinishStudy(*store, study, study_grid, interrupted);
      store.reset();  // closed without the GIL
    }
  }
  relay.Finish();
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
                                        long long steps, long long record, bool one_way, const std::string& out,
                                        const py::object& progress, bool handle_sigint) {
  vibro::frontend::CheckSweepOptions(kPython, from, to, steps, record);
  for (double v : {from, to}) vibro::frontend::SceneWith(s.origin, key, v);
  auto store = CreateStore(out, HeaderOf(s.loaded, vibro::System(s.loaded.scene)));
  vibro::SweepRequest req;
  SigintGuard guard(handle_sigint);
  ProgressRelay relay(progress, guard);
  // Progress: one scene per run of the sweep, up and (unless one_way) down, as the command line.
  const long long runs = steps + 1LL + (one_way ? 0 : steps);  // the way back skips the top
  long long scenes = 0;
  req.scene_at = [&](double v) {
    relay.Update(scenes++, runs);
    return vibro::frontend::SceneWith(s.origin, key, v);
  };
  req.from = from;
  req.to = to;
  req.steps = static_cast<int>(steps);
  req.record = static_cast<int>(record);
  req.both_ways = !one_way;
  std::string json;
  bool interrupted = false;
  {
    py::gil_scoped_release release;
    const auto sweep = vibro::Sweep(req, guard.flag());
    interrupted = guard.interrupted();
    relay.Update(static_cast<long long>(sweep.size()), runs);
    if (store) {
      store->WriteSweep(sweep, {key, from, to, req.steps, req.record, !one_way});
      store->Finish(vibro::frontend::SweepOutcome(sweep, key, interrupted),
                    sweep.empty() ? vibro::Attractor{} : sweep.back().attractor);
      store.reset();  // closed without the GIL
    }
    json = vibro::SweepJson(sweep);
  }
  relay.Finish();
  return {json, interrupted};
}

// `vibro.diagram` (docs/diagram.md): the JSON of the diagram, and whether a stop request cut it
// short (the branches finished so far are in it, and in `out`).
std::pair<std::string, bool> DiagramScene(const PyScene& s, const std::string& key, double from, double to,
                                          long long steps, long long record, long long searches, long long grid,
                                          long long max_period, long long max_branches, long long max_points,
                                          double coverage_tolerance, long long threads, const std::string& out,
                                          bool handle_sigint) {
  vibro::frontend::DiagramSpec spec;
  spec.key = key;
  spec.from = from;
  spec.to = to;
  spec.steps = steps;
  spec.record = record;
  spec.searches = searches;
  spec.grid = grid;
  spec.max_period = max_period;
  spec.max_branches = max_branches;
  spec.max_points = max_points;
  spec.coverage_tolerance = coverage_tolerance;
  spec.threads = threads;
  auto req = vibro::frontend::PrepareDiagram(s.origin, spec, kPython);
  auto store = CreateStore(out, HeaderOf(s.loaded, vibro::System(s.loaded.scene)));  // after the checks
  SigintGuard guard(handle_sigint);
  std::string json;
  bool interrupted = false;
  {
    py::gil_scoped_release release;
    req.stop_requested = guard.flag();
    const auto d = vibro::Diagram(req);
    interrupted = guard.interrupted() || d.status == "interrupted";
    if (store) {
      store->WriteDiagram(d, {key, from, to, static_cast<int>(steps), static_cast<int>(record), true});
      vibro::RunResult r;
      r.status = interrupted ? vibro::RunStatus::kInterrupted : vibro::RunStatus::kOk;
      r.message = interrupted ? "interrupted: the branches finished so far are kept" : "";
      store->Finish(r, vibro::frontend::NoAttractor());
      store.reset();  // closed without the GIL
    }
    json = vibro::DiagramJson(d);
  }
  return {json, interrupted};
}

// The JSON of the cross-check, and whether a stop request cut it short (nothing to keep).
std::pair<std::string, bool> Check(const PyScene& s, bool handle_sigint) {
  const vibro::System sys(s.loaded.scene);
  SigintGuard guard(handle_sigint);
  py::gil_scoped_release release;
  const auto report = vibro::CrossCheck(sys, s.loaded.scene);
  if (guard.interrupted()) return {"", true};
  return {vibro::CheckJson(report), false};
}

std::string Info(const std::string& path) {
  CheckPaths({{"path", &path}});
  py::gil_scoped_release release;
  return vibro::StoredRunJson(vibro::ReadStoredRun(path));
}

// vibro validate: a branch from another tool, point by point (frontend/commands.hpp).
// The branch is the CSV file `csv`, or `columns` (frontend/tables.hpp) when given.
using Columns = std::map<std::string, std::vector<double>>;
std::pair<std::string, bool> Validate(const PyScene& s, const std::string& csv, const std::optional<Columns>& columns,
                                      const std::optional<std::vector<std::string>>& sequences,
                                      const std::string& param, const std::string& kind, long long period,
                                      double tolerance, double sticking_tolerance, const std::string& out,
                                      const py::object& progress, bool handle_sigint) {
  if (!columns) CheckPaths({{"branch", &csv}});
  std::vector<std::string> problems;  // before it is an int (PrepareValidation checks it again)
  vibro::frontend::CheckInteger(kPython, "--period", period, vibro::frontend::kPeriodLimit, problems);
  vibro::frontend::ThrowIfAny(problems);
  const vibro::frontend::ValidationSpec spec{csv,      param, KindOf(kind), static_cast<int>(period), tolerance,
                                             sticking_tolerance};
  const auto job =
      columns ? vibro::frontend::PrepareValidationTable(
                    s.origin, s.loaded, spec,
                    vibro::frontend::BranchTable(*columns, vibro::frontend::ClaimedStateSize(s.loaded), sequences),
                    [](const vibro::ClaimedPoint& p) { return fmt::format("branch row {}", p.line); }, kPython)
              : vibro::frontend::PrepareValidation(s.origin, s.loaded, spec, kPython);
  auto store = CreateStore(out, HeaderOf(s.loaded, vibro::System(s.loaded.scene)));
  SigintGuard guard(handle_sigint);
  ProgressRelay relay(progress, guard);
  vibro::frontend::Validation result;
  {
    py::gil_scoped_release release;
    result = vibro::frontend::RunValidation(job, spec, guard.flag(), [&relay](size_t done, size_t total) {
      relay.Update(static_cast<long long>(done), static_cast<long long>(total));
    });
    if (store) vibro::frontend::FinishValidation(*store, job, result);
    store.reset();  // closed without the GIL
  }
  relay.Finish();
  return {vibro::ValidationJson(result.checks), result.interrupted};
}

// vibro score: another simulator's events against vibro's run (frontend/commands.hpp). Returns
// the JSON, whether it was interrupted, and vibro's own run status and message.
// The events are the CSV file `csv`, or the columns t, kind and velocity (frontend/tables.hpp)
// when `t` is given.
std::tuple<std::string, bool, std::string, std::string> Score(
    const PyScene& s, const std::string& csv, const std::optional<std::vector<double>>& t,
    const std::vector<std::string>& kind, const std::optional<std::vector<double>>& velocity,
    const std::optional<std::vector<double>>& contact, double window,
    double tolerance, bool handle_sigint) {
  if (!t) CheckPaths({{"events", &csv}});
  std::optional<std::vector<vibro::TheirEvent>> table;
  if (t) table = vibro::frontend::EventTable(*t, kind, velocity, contact);
  SigintGuard guard(handle_sigint);
  py::gil_scoped_release release;
  const auto r = table ? vibro::frontend::ScoreEventTable(
                             s.loaded, *table,
                             [](const vibro::TheirEvent& e) { return fmt::format("events row {}", e.line); }, window,
                             tolerance, guard.flag(), kPython)
                       : vibro::frontend::ScoreEventsCsv(s.loaded, csv, window, tolerance, guard.flag(), kPython);
  return {vibro::ScoreJson(r.report, r.scene), r.run.status == vibro::RunStatus::kInterrupted,
          vibro::ToString(r.run.status), r.run.message};
}

// vibro partition: curves of constant sticking fraction in a parameter plane.
std::pair<std::string, bool> PartitionPlane(const PyScene& s, const std::vector<std::string>& params,
                                            const std::vector<double>& range1, const std::vector<double>& range2,
                                            const std::vector<double>& levels, long long steps1,
                                            std::optional<double> from2, long long period, long long threads,
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
  auto req = vibro::frontend::PartitionRequestFor(s.origin, s.loaded, spec, kPython);
  auto store = CreateStore(out, HeaderOf(s.loaded, vibro::System(s.loaded.scene)));
  SigintGuard guard(handle_sigint);
  py::gil_scoped_release release;
  req.stop_requested = guard.flag();
  const auto columns = vibro::Partition(req);
  const bool interrupted = guard.interrupted();
  if (store) vibro::frontend::FinishPartition(*store, spec, columns, interrupted);
  store.reset();  // closed without the GIL
  return {vibro::PartitionJson(params[0], params[1], levels, columns), interrupted};
}

// vibro curve: two-parameter curves of bifurcations.
std::pair<std::string, bool> TraceCurvesPy(const PyScene& s, const std::vector<std::string>& params,
                                           const std::vector<double>& range1, const std::vector<double>& range2,
                                           const std::vector<std::string>& kinds, const std::vector<double>& toward,
                                           const std::string& from, long long point, long long contact, double step,
                                           double max_step, long long max_points, long long period,
                                           long long transient, const std::string& orbit, const std::string& out,
                                           bool handle_sigint) {
  vibro::frontend::CurveSpec spec;
  spec.params = params;
  spec.range1 = range1;
  spec.range2 = range2;
  spec.kinds = kinds;
  spec.toward = toward;
  spec.from = from;
  spec.point = point;
  spec.contact = contact;
  spec.step = step;
  spec.max_step = max_step;
  spec.max_points = max_points;
  spec.period = period;
  spec.transient = transient;
  spec.orbit = orbit;
  CheckPaths({{"from_", &spec.from}});
  const auto plan = vibro::frontend::PlanCurves(s.origin, s.loaded, spec, kPython);
  auto store = CreateStore(out, HeaderOf(s.loaded, vibro::System(s.loaded.scene)));
  SigintGuard guard(handle_sigint);
  py::gil_scoped_release release;
  const auto curves = vibro::frontend::TraceCurves(plan, guard.flag());
  const bool interrupted = guard.interrupted();
  if (store) {
    vibro::WriteCurves(*store, params[0], params[1], curves);
    vibro::RunResult r;
    bool found = false;
    for (const auto& c : curves) found = found || c.status != "no-start";
    r.status = interrupted ? vibro::RunStatus::kInterrupted : found ? vibro::RunStatus::kOk : vibro::RunStatus::kNumericalFailure;
    r.message = interrupted ? "interrupted" : found ? "ok" : "no curve was started";
    store->Finish(r, vibro::frontend::NoAttractor());
  }
  store.reset();  // closed without the GIL
  return {vibro::CurvesJson(params[0], params[1], curves), interrupted};
}

}  // namespace

PYBIND11_MODULE(_vibro, m) {
  m.doc() = "vibro's C++ core; use the package `vibro`, not this module";
  m.attr("version") = VIBRO_VERSION;
  m.attr("git_commit") = VIBRO_GIT_COMMIT;

  // A run ended by its limits (`vibro simulate` exits 3): vibro.LimitError.
  py::register_exception<vibro::frontend::LimitError>(m, "LimitError", PyExc_RuntimeError);
  // Bad input (scene, option, file): ValueError with every located message, on one line ("; ").
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const vibro::InputError& e) {
      std::string text;
      for (const auto& msg : e.messages()) text += (text.empty() ? "" : "; ") + msg;
      PyErr_SetString(PyExc_ValueError, text.c_str());
    } catch (const std::runtime_error& e) {
      // A worker thread the system refused (TBB: "pthread_create has failed"): MemoryError, as
      // for a refused allocation; anything else goes on to pybind11's translation.
      if (std::string(e.what()).rfind("pthread_create", 0) != 0) throw;
      PyErr_SetString(PyExc_MemoryError, (std::string("the system refused a worker thread: ") + e.what()).c_str());
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
  // The rigid model beside a compliant scene (docs/compliant.md): its comparison as JSON.
  m.def("rigid_beside", [](const PyScene& s, int blocks) {
    if (!vibro::HasCompliantContact(s.loaded.scene))
      throw vibro::InputError({"rigid_beside: the scene has no compliant stop (give a stop a stiffness, docs/compliant.md)"});
    py::gil_scoped_release release;
    return vibro::RigidComparisonJson(vibro::CompareWithRigid(s.loaded.scene, blocks));
  });
  m.def("orbit", Entry("orbit", &Orbit));
  m.def("prove", Entry("prove", &Prove));
  m.def("prove_bifurcation", Entry("prove", &ProveBifurcationPoint));
  m.def("prove_segment", Entry("prove", &ProveSegment));
  m.def("continue_branch", Entry("continue", &ContinueBranch));
  m.def("study", Entry("basin", &Study));
  m.def("sweep", Entry("sweep", &SweepScene));
  m.def("diagram", Entry("diagram", &DiagramScene));
  // The defaults of `vibro.diagram`, the library's and `vibro diagram`'s (include/vibro/diagram.hpp).
  m.def("diagram_defaults", [] {
    using D = vibro::DiagramDefaults;
    py::dict d;
    d["steps"] = D::sweep_steps;
    d["record"] = D::record;
    d["searches"] = D::searches;
    d["grid"] = D::search_grid;
    d["max_period"] = D::max_period;
    d["max_branches"] = D::max_branches;
    d["max_points"] = D::max_points;
    d["coverage_tolerance"] = D::coverage_tolerance;
    d["threads"] = D::threads;
    return d;
  });
  m.def("check", Entry("check", &Check));
  m.def("info", &Info);
  m.def("validate", Entry("validate", &Validate));
  m.def("score", Entry("score", &Score));
  m.def("partition", Entry("partition", &PartitionPlane));
  m.def("curve", Entry("curve", &TraceCurvesPy));
}
