// What the command files of src/cli share. main.cpp holds the parsing (CLI11 stays there: it
// costs seconds of compile time per including file) and calls one Run<Command> per subcommand,
// each in its cmd_<command>.cpp, with plain values and option structs.
//
// Exit codes: 0 success · 1 internal error · 2 bad input · 3 numerical failure · 4 disagreement
// (check, validate) or not proven (prove) · 130 interrupted.
#pragma once

#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "frontend/commands.hpp"
#include "frontend/curves.hpp"
#include "frontend/diagram.hpp"
#include "frontend/frontend.hpp"
#include "vibro/attractor.hpp"
#include "vibro/loads.hpp"
#include "vibro/poincare.hpp"
#include "vibro/rigid_model.hpp"
#include "vibro/simulator.hpp"
#include "vibro/hdf5_store.hpp"
#include "vibro/lyapunov.hpp"
#include "vibro/orbit_from_state.hpp"
#include "vibro/prove.hpp"
#include "vibro/scene_file.hpp"
#include "vibro/system.hpp"

inline constexpr int kExitInternal = 1;
inline constexpr int kExitBadInput = 2;
inline constexpr int kExitNumerical = 3;
inline constexpr int kExitDisagree = 4;  // check, validate, score: the methods, claims or runs disagree
inline constexpr int kExitInterrupted = 130;

// The exit code of a run's status.
int ExitCode(vibro::RunStatus s);
// Prints an attractor's summary; restitution NaN when unknown (then the velocities after impact
// are not printed); `named`: each event names its contact (cli/text_format.hpp).
void PrintAttractor(const vibro::Attractor& a, double restitution = std::nan(""), bool named = false);
// Prints the contact loads of a run per contact, with their intervals (docs/loads.md).
void PrintLoads(const vibro::LoadsSummary& s);
// Prints the Lyapunov exponents of a run with their 95 % intervals, and whether it is chaotic.
void PrintLyapunov(const vibro::LyapunovSpectrum& s);
// The message for a --param KEY the scene has no number at, with the nearest known key.
using vibro::frontend::NotANumericKey;

// `vibro model SCENE` (cmd_model.cpp).
int RunModel(const std::string& path, const std::vector<std::string>& sets, bool json);

// `vibro simulate SCENE [--out FILE [--resume | --extend N]]` (cmd_simulate.cpp); extend 0: none;
// time_limit: seconds for the whole run (0: none), see frontend/run_budget.hpp.
// The rigid model beside a compliant scene (docs/compliant.md).
void PrintRigidComparison(const vibro::RigidComparison& c);
// `vibro orbit` on a compliant scene: the rigid model's orbit beside it (docs/compliant.md).
void PrintRigidOrbitComparison(const vibro::RigidOrbitComparison& c);
int RunSimulate(const std::string& path, const std::vector<std::string>& sets, bool json,
                const std::string& out, bool resume, long long extend, int blocks = 10,
                double time_limit = 86400.0, bool rigid_beside = false);

// `vibro orbit SCENE` (cmd_orbit.cpp).
int RunOrbit(const std::string& path, const std::vector<std::string>& sets, bool json,
             const vibro::OrbitRequest& req, const std::string& out);

// `vibro check SCENE [--precision quad]` (cmd_check.cpp). Exit 4 when the methods disagree.
int RunCheck(const std::string& path, const std::vector<std::string>& sets, bool json, bool with_quad);

// `vibro continue SCENE --param KEY --to B` (cmd_continue.cpp); restart_file/restart_point:
// --from FILE --point K ("" and -1 for none); switch_side: with --switch, "above" or "below" (which
// half of a pitchfork's new branch, by its x_B at the section), "" without (docs/orbits.md).
int RunContinue(const std::string& path, std::vector<std::string> sets, bool json,
                const std::string& key, double to, double step, int max_points,
                vibro::OrbitRequest orbit, const std::string& out, const std::string& restart_file,
                long long restart_point, const std::string& switch_side = "");

// `vibro partition SCENE --params KEY1,KEY2 ...` (cmd_partition.cpp).
struct PartitionArgs {
  vibro::frontend::PartitionSpec spec;  // the checks and the request: frontend/commands.hpp
  std::string out;
};
int RunPartition(const std::string& path, const std::vector<std::string>& sets, bool json,
                 const PartitionArgs& a);

// `vibro curve SCENE --param KEY1,KEY2 ...` (cmd_curve.cpp): two-parameter curves.
struct CurveArgs {
  vibro::frontend::CurveSpec spec;  // the checks and the request: frontend/curves.hpp
  std::string out;
};
int RunCurve(const std::string& path, const std::vector<std::string>& sets, bool json, const CurveArgs& a);

// `vibro attractors SCENE` and `vibro basin SCENE` (cmd_study.cpp).
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
                    const StudyArgs& args, bool basin);

// `vibro sweep SCENE --param KEY --from A --to B` (cmd_sweep.cpp).
int RunSweep(const std::string& path, const std::vector<std::string>& sets, bool json,
             const std::string& key, double from, double to, int steps, int record, bool one_way,
             const std::string& out);

// `vibro diagram SCENE --param KEY --from A --to B` (cmd_diagram.cpp).
int RunDiagram(const std::string& path, const std::vector<std::string>& sets, bool json,
               const vibro::frontend::DiagramSpec& spec, const std::string& out);

// `vibro info FILE` (cmd_info.cpp).
int RunInfo(const std::string& path, bool json);

// `vibro plot FILE` (cmd_plot.cpp); options: the script's further options (--format ...).
int RunPlot(const std::string& path, const std::string& prefix, const std::string& overlay,
            const std::vector<std::string>& options);

// `vibro validate SCENE BRANCH.csv --param KEY ...` (cmd_validate.cpp).
struct ValidateArgs {
  std::string scene, csv, param, out;
  std::vector<std::string> sets;
  vibro::OrbitKind kind = vibro::OrbitKind::kAuto;
  int period = 0;
  double tolerance = 1e-6, sticking_tolerance = 1e-6;
  bool json = false;
};
int RunValidate(const ValidateArgs& args);  // exit code: 0, 4 when a point is not confirmed

// `vibro score SCENE EVENTS.csv` (cmd_score.cpp).
struct ScoreArgs {
  std::string scene, csv;
  std::vector<std::string> sets;
  double window = 0.05, tolerance = 1e-6;
  bool json = false;
};
int RunScore(const ScoreArgs& args);  // exit code: 0, 4 when the runs diverge beyond --tolerance

// `vibro prove SCENE` (cmd_prove.cpp). Exit 0 proven, 4 not proven.
struct ProveArgs {
  vibro::ProofRequest request;
  std::string from;    // --from ORBIT.h5 ("" for none)
  std::string branch;  // --branch FILE.h5: every point of a stored branch ("" for none)
  // --bifurcation BRANCH.h5 (with --point K: its bifurcation K) or KIND:KEY=VALUE ("" for none)
  std::string bifurcation;
  long long point = 0;
  std::string out;   // --out CERT.json
};
int RunProve(const std::string& path, const std::vector<std::string>& sets, bool json, const ProveArgs& args);
