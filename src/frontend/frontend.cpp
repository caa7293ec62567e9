// The pieces of running a command that the command line and the Python module share.
#include "frontend/frontend.hpp"

#include <algorithm>
#include <cmath>
#include <string_view>
#include <utility>

#include <fmt/format.h>

#include "frontend/limits.hpp"
#include "vibro/scene_toml.hpp"
#include "vibro/simulator.hpp"

namespace vibro::frontend {

LoadedScene SceneOrigin::Load(const std::vector<std::string>& more_sets) const {
  if (!text) {
    std::vector<std::string> problems;
    CheckPath(Naming::kCli, "scene", path, problems);
    ThrowIfAny(problems);
  }
  std::vector<std::string> all = sets;
  all.insert(all.end(), more_sets.begin(), more_sets.end());
  return text ? ParseScene(*text, source, all) : LoadScene(path, all);
}

std::string Assignment(const std::string& key, double value) {
  std::string text = fmt::format("{}", value);  // fmt: the shortest form that reads back exactly
  if (text.find_first_of(".eEn") == std::string::npos) text += ".0";  // "n": nan/inf (refused later)
  return key + "=" + text;
}

namespace {

// contact[i].position and contact[i].restitution (docs/contacts.md): the field of ContactSpec and
// i, or nullptr.
double ContactSpec::*ContactField(const std::string& key, size_t& index) {
  constexpr std::string_view kPrefix = "contact[";
  if (key.rfind(kPrefix, 0) != 0) return nullptr;
  const auto close = key.find("].", kPrefix.size());
  const std::string digits = key.substr(kPrefix.size(), close == std::string::npos ? 0 : close - kPrefix.size());
  if (digits.empty() || digits.size() > 9 || digits.find_first_not_of("0123456789") != std::string::npos)
    return nullptr;
  index = static_cast<size_t>(std::stoul(digits));
  const std::string leaf = key.substr(close + 2);
  return leaf == "position" ? &ContactSpec::position : leaf == "restitution" ? &ContactSpec::restitution : nullptr;
}

}  // namespace

Scene SceneWith(const SceneOrigin& origin, const std::string& key, double value) {
  static thread_local std::string cached_key;
  static thread_local Scene cached;
  double Scene::*field = key == "excitation.amplitude"   ? &Scene::amplitude
                         : key == "excitation.frequency" ? &Scene::frequency
                         : key == "stop.position"        ? &Scene::stop_position
                         : key == "stop.restitution"     ? &Scene::restitution
                                                         : nullptr;
  size_t contact = 0;
  double ContactSpec::*contact_field = field ? nullptr : ContactField(key, contact);
  if (field || contact_field) {
    std::string joined = origin.path + '\n' + origin.text.value_or("") + '\n' + origin.source + '\n';
    for (const auto& x : origin.sets) joined += x + '\n';
    if (cached_key != joined) {
      cached = origin.Load().scene;
      cached_key = joined;
    }
    Scene s = cached;
    bool set = true;
    if (field) {
      s.*field = value;
    } else if (contact < s.contacts.size()) {
      s.contacts[contact].*contact_field = value;
    } else if (contact == 0 && s.contacts.empty()) {  // a [stop] is contact[0]
      (contact_field == &ContactSpec::position ? s.stop_position : s.restitution) = value;
    } else {
      set = false;  // no such contact: the parse below says so
    }
    if (set && Validate(s).empty()) return s;
  }
  return origin.Load({Assignment(key, value)}).scene;
}

Scene SceneWith(const std::string& path, const std::vector<std::string>& sets, const std::string& key,
                double value) {
  return SceneWith(SceneOrigin{path, std::nullopt, path, sets}, key, value);
}

Scene SceneAtOption(const SceneOrigin& origin, const std::string& key, double value, const char* option) {
  try {
    return SceneWith(origin, key, value);
  } catch (const InputError& e) {
    std::vector<std::string> located;
    for (const auto& m : e.messages()) located.push_back(fmt::format("{} {} (--param {}): {}", option, value, key, m));
    throw InputError(located);
  }
}

namespace {
thread_local Invocation g_invocation;
}  // namespace

void SetInvocation(Invocation invocation) { g_invocation = std::move(invocation); }

StoreHeader HeaderOf(const LoadedScene& loaded, const System& sys) {
  const auto& sc = loaded.scene;
  StoreHeader h;
  h.scene_text = loaded.text_as_run;
  h.engine = ToString(sc.run.engine);
  h.chatter = ToString(sc.run.chatter);
  h.method = ToString(sc.run.method);
  h.rtol = sc.run.rtol;
  h.atol = sc.run.atol;
  h.dof = sys.dof();
  h.samples_per_period = sc.run.samples_per_period;
  h.periods = sc.run.periods;
  h.period = sys.period();
  h.initial_time = sc.initial_time;
  h.max_period = sc.run.max_period;
  h.frequencies = sys.omega();
  h.forcing = sys.forcing();
  h.contact = sys.contact();
  h.contact_shape = sys.contact_shape();
  h.damping_ratios = sys.damping();
  h.constrained_frequencies = sys.constrained().frequencies;
  h.s_A = sys.s_A();
  h.s_B = sys.s_B();
  h.stop = sys.stop();
  h.restitution = sys.restitution();
  h.amplitude = sys.amplitude();
  h.frequency = sys.frequency();
  if (sys.harmonic_sum()) {
    const auto& hs = sys.harmonics();
    const Eigen::Index H = static_cast<Eigen::Index>(hs.size());
    h.harmonic_amplitudes.resize(H);
    h.harmonic_frequencies.resize(H);
    h.harmonic_phases.resize(H);
    h.harmonic_forcing.resize(H, sys.omega().size());
    for (Eigen::Index k = 0; k < H; ++k) {
      const Harmonic& one = hs[static_cast<size_t>(k)];
      h.harmonic_amplitudes[k] = one.amplitude;
      h.harmonic_frequencies[k] = one.frequency;
      h.harmonic_phases[k] = one.phase;
      h.harmonic_forcing.row(k) = one.forcing.transpose();
    }
  }
  if (sys.physical() && loaded.scene.physical) {
    h.mode_shapes = sys.mode_shapes();
    for (Eigen::Index i = 0; i < h.mode_shapes.rows(); ++i) {
      const auto dof = static_cast<int>(i);
      const bool a = dof == loaded.scene.physical->forcing_dof, b = dof == loaded.scene.physical->contact_dof;
      h.dof_labels.push_back(fmt::format("dof {}{}", dof, a && b ? " (A, B)" : a ? " (A)" : b ? " (B)" : ""));
    }
  }
  h.command = g_invocation.command;
  h.force = g_invocation.force;
  h.provenance = {{"command_line", g_invocation.command_line},
                  {"options", g_invocation.options},
                  {"scene_resolved", ResolvedSceneToml(loaded.scene)}};
  return h;
}

LoadedScene ExtendedScene(const LoadedScene& given, const std::string& path, long long more, const char* option) {
  const StoredRun stored = ReadStoredRun(path);
  const auto refuse = [&](const std::string& why) {
    return InputError({fmt::format("{}: cannot extend ({} {}): {}", path, option, more, why)});
  };
  if (!stored.checkpoint) throw refuse("the file holds no checkpoint (not a run of vibro simulate --out)");
  if (stored.status == ToString(RunStatus::kNumericalFailure) || stored.status == ToString(RunStatus::kUndetermined))
    throw refuse(fmt::format("its run ended with status {} ({}); a continuation would meet the same end",
                             stored.status, stored.message));
  long long held = 0;
  try {
    held = ParseScene(stored.scene_text, path + " (attribute scene)").scene.run.periods;
  } catch (const InputError& e) {
    throw refuse("the scene it holds does not parse: " + e.messages().front());
  }
  constexpr long long kMostPeriods = 1LL << 53;  // the range of run.periods (docs/scenes.md)
  if (more < 1 || more > kMostPeriods - held)
    throw refuse(fmt::format("expected 1 ≤ N ≤ {} (the run holds {} periods; run.periods ≤ 2^53)",
                             kMostPeriods - held, held));
  // The given scene with run.periods = the new total; the store checks that nothing else differs.
  LoadedScene total = ParseScene(given.text_as_run, given.source, {fmt::format("run.periods={}", held + more)});
  return total;
}

Coordinate StudyCoordinate(const System& sys, const std::string& name, const std::vector<double>& r,
                           const char* option, std::vector<std::string>& problems) {
  if (r.size() == 2) {
    // The bound on a scene's initial coordinates (docs/reliability.md): a start beyond it has a
    // square the engines cannot represent.
    constexpr double kHuge = 1e100;
    if (!(std::abs(r[0]) <= kHuge && std::abs(r[1]) <= kHuge))
      problems.push_back(fmt::format("{} {},{}: expected |A|, |B| ≤ {:g} (a start of the study is an initial "
                                     "state, whose square must be representable)",
                                     option, r[0], r[1], kHuge));
    else if (!(r[1] > r[0]))
      problems.push_back(fmt::format("{} {},{}: expected A,B with A < B", option, r[0], r[1]));
    return Coordinate{name, r[0], r[1]};
  }
  if (!r.empty()) problems.push_back(fmt::format("{}: expected two numbers A,B", option));
  // Defaults: x_B from the stop over two stop distances, velocities over ±2 ω_1 max(1, |x0|).
  const double scale = std::max(1.0, std::abs(sys.stop()));
  if (name == "x_B") return Coordinate{name, sys.stop(), sys.stop() + 2 * scale};
  return Coordinate{name, -2 * scale * sys.omega()[0], 2 * scale * sys.omega()[0]};
}

void WriteOrbit(const std::string& out, const LoadedScene& loaded, const System& sys,
                const OrbitResult& orbit) {
  Scene sc = loaded.scene;
  sc.initial_time = orbit.section_time;
  sc.run.periods = orbit.period;
  sc.run.samples_per_period = std::max(sc.run.samples_per_period, 256);
  auto store = Hdf5Store::Create(out, HeaderOf(loaded, sys));
  const InitialOverride start{orbit.section_time, orbit.X, orbit.V};
  SimulationOptions opt;
  opt.initial = &start;
  opt.observers = {store.get()};
  const auto result = Simulate(sys, sc, opt);
  store->WriteOrbit(orbit);
  store->Finish(result, orbit.summary);
}

void WriteOrbitFailure(const std::string& out, const LoadedScene& loaded, const System& sys,
                       const OrbitResult& orbit) {
  auto store = Hdf5Store::Create(out, HeaderOf(loaded, sys));
  RunResult r;
  r.status = RunStatus::kNumericalFailure;
  r.message = fmt::format("no orbit ({}){}", orbit.status, orbit.message.empty() ? "" : ": " + orbit.message);
  store->Finish(r, NoAttractor());
}

void FinishStudy(Hdf5Store& store, const StudyResult& study, const Hdf5Store::StudyGrid& grid, bool interrupted) {
  store.WriteStudy(study, grid);
  RunResult r;
  r.status = interrupted ? RunStatus::kInterrupted : RunStatus::kOk;
  if (interrupted)
    r.message = fmt::format("interrupted with {} of {} cells done; everything so far is kept, "
                            "continue with --resume",
                            study.cells - std::llround(study.pending_fraction * static_cast<double>(study.cells)),
                            study.cells);
  store.Finish(r, NoAttractor());  // a study has no single attractor (they are in /attractors)
}

RunResult SweepOutcome(const std::vector<SweepPoint>& sweep, const std::string& key, bool interrupted) {
  RunResult r;
  if (interrupted) {
    r.status = RunStatus::kInterrupted;
    r.message = fmt::format("interrupted after {} of the sweep's runs", sweep.size());
  } else if (!sweep.empty() && sweep.back().status != "ok") {
    const SweepPoint& p = sweep.back();
    r.status = p.status == ToString(RunStatus::kUndetermined) ? RunStatus::kUndetermined
                                                              : RunStatus::kNumericalFailure;
    r.message = fmt::format("the sweep ended at {} = {}: {}", key, p.value, p.message);
  }
  return r;
}

}  // namespace vibro::frontend
