// What the command files of src/cli share (main.cpp holds the parsing; CLI11 stays there).
#pragma once

#include <string>
#include <vector>

#include "frontend/frontend.hpp"
#include "vibro/hdf5_store.hpp"
#include "vibro/orbit_from_state.hpp"
#include "vibro/scene_file.hpp"
#include "vibro/system.hpp"

// The header of an HDF5 output file for a scene as run, with the provenance of the invocation.
using vibro::frontend::HeaderOf;

// `vibro validate SCENE BRANCH.csv --param KEY ...` (cmd_validate.cpp).
struct ValidateArgs {
  std::string scene, csv, param, out;
  std::vector<std::string> sets;
  vibro::OrbitKind kind = vibro::OrbitKind::kAuto;
  int period = 0;
  double tolerance = 1e-6, sticking_tolerance = 1e-6;
  bool json = false;
};
int RunValidate(const ValidateArgs& args);  // exit code: 0, 4 when a point disagrees

// `vibro score SCENE EVENTS.csv` (cmd_score.cpp).
struct ScoreArgs {
  std::string scene, csv;
  std::vector<std::string> sets;
  double window = 0.05, tolerance = 1e-6;
  bool json = false;
};
int RunScore(const ScoreArgs& args);
