// What the command line (src/cli/main.cpp) and the Python module (python/src/bindings.cpp) share,
// so that both run a command the same way: where a scene comes from and the scene with one key
// changed, the header of an HDF5 output, the default ranges of a study and one period of an
// orbit written to a file.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "vibro/hdf5_store.hpp"
#include "vibro/poincare.hpp"
#include "vibro/scene_file.hpp"
#include "vibro/studies.hpp"
#include "vibro/system.hpp"

namespace vibro::frontend {

// A scene file (`path`), or TOML text named `source` in messages, with `--set` overrides.
struct SceneOrigin {
  std::string path;
  std::optional<std::string> text;  // when set, parsed instead of reading `path`
  std::string source;
  std::vector<std::string> sets;

  LoadedScene Load(const std::vector<std::string>& more_sets = {}) const;
};

// The override "KEY=VALUE" with VALUE in its shortest round-trip form ("2.8", not
// "2.7999999999999998"; ".0" added to integral values, which TOML would read as integers): the
// value is exactly `value`, and the scene stored in an output reads as the user would write it.
std::string Assignment(const std::string& key, double value);

// The scene of `origin` with KEY=VALUE on top (continuation, partitions and sweeps). The scalar
// keys of the excitation and the stop, and contact[i].position and contact[i].restitution, are set
// in a copy of the scene parsed once per thread, and validated (a value outside a key's range
// throws as a parse would); other keys re-parse the scene with the override.
Scene SceneWith(const SceneOrigin& origin, const std::string& key, double value);
// Same for a scene file and overrides.
Scene SceneWith(const std::string& path, const std::vector<std::string>& sets, const std::string& key,
                double value);

// SceneWith for a value given by a command-line option (`--from`, `--to`): a value outside the
// key's range is refused with the option named, e.g. "--from 1e+308 (--param KEY): ...".
Scene SceneAtOption(const SceneOrigin& origin, const std::string& key, double value, const char* option);

// How the current command was invoked, stored as provenance in every output file written on
// this thread afterwards: `command` ("simulate", "basin", ...), the full command line (or the
// Python call), the command's options with their values (defaults included) and whether an
// existing vibro file of another scene or command may be replaced (--force).
struct Invocation {
  std::string command, command_line, options;
  bool force = false;
};
void SetInvocation(Invocation invocation);

// The header of an HDF5 output of a run of `loaded`: the scene as run, the model (with mode shapes
// and DOF labels for the physical form) and the provenance (the invocation, and the scene with
// every default resolved).
StoreHeader HeaderOf(const LoadedScene& loaded, const System& system);

// The scene of a run stored in `path` (vibro simulate --out) extended by `more` periods: `given`
// with run.periods = the stored run's periods + more (what the store's Resume with `extend`
// takes). InputError, naming `option` ("--extend" or "extend"), when the file cannot be read, its
// scene differs from `given` in anything but run.periods, it holds no checkpoint or its run ended
// in a numerical failure (an extension would meet it again).
LoadedScene ExtendedScene(const LoadedScene& given, const std::string& path, long long more, const char* option);

// A study's coordinate over `range` (A,B with A < B), or its default range when `range` is empty:
// x_B from the stop over two stop distances, velocities over ±2 ω_1 max(1, |x0|). Problems are
// appended to `problems` with `option` (e.g. "--x-range") named.
Coordinate StudyCoordinate(const System& system, const std::string& name, const std::vector<double>& range,
                           const char* option, std::vector<std::string>& problems);

// What Hdf5Store::Finish takes for a study, branch or partition: no single attractor (the file
// then has no /attractor group).
inline Attractor NoAttractor() {
  Attractor a;
  a.kind.clear();
  return a;
}

// Writes a finished (or interrupted) study to `store` and closes its run: /basin or /attractors,
// status and, when interrupted, how many cells are done and how to resume.
void FinishStudy(Hdf5Store& store, const StudyResult& study, const Hdf5Store::StudyGrid& grid, bool interrupted);

// The status of a sweep as a whole: interrupted, the status of its last point when that run
// failed (numerical failure or undetermined, with `key` and the value named), else ok.
RunResult SweepOutcome(const std::vector<SweepPoint>& sweep, const std::string& key, bool interrupted);

// Closes the `out` file of an orbit search that found no orbit: status numerical-failure with the
// search's status and message (the file exit 3 leaves behind agrees with it).
void WriteOrbitFailure(const std::string& out, const LoadedScene& loaded, const System& system,
                       const OrbitResult& orbit);

// Writes one period of a converged orbit, densely sampled, and its multipliers (/orbit) to `out`.
void WriteOrbit(const std::string& out, const LoadedScene& loaded, const System& system,
                const OrbitResult& orbit);

}  // namespace vibro::frontend
