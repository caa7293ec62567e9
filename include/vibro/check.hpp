// `vibro check`: the exact engine, the CVODE engine and the Poincaré solver on the same scene,
// and a table of their agreement (the way a user comes to trust a result); optionally the
// quad-precision exact engine as a fourth opinion, the reference for the others.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "vibro/poincare.hpp"
#include "vibro/scene.hpp"
#include "vibro/system.hpp"

namespace vibro {

struct CheckRow {
  std::string quantity;
  std::optional<double> exact, cvode, orbit;  // value per method (absent: not applicable)
  double difference = 0;                      // largest |method − exact|
  double tolerance = 0;
  bool ok = true;
  std::string note;
  std::optional<double> quad;  // the quad-precision exact engine (with_quad)
};

struct CheckReport {
  std::vector<CheckRow> rows;
  bool ok = true;
  std::string exact_kind, cvode_kind, orbit_status, quad_kind;  // quad_kind empty: not run
};

// Tolerances: CVODE against exact, 100·rtol^(2/3) (the law of docs/engines.md, "What each rtol buys");
// Poincaré solver against exact, 1e-9; the leading multiplier against the decay rate observed in
// the exact transient, 10 % (+ 0.02); the exact engine against the quad engine (with_quad),
// 1e-9 (the double engine's claimed accuracy on periodic quantities, docs/chattering.md).
CheckReport CrossCheck(const System& system, const Scene& scene, bool with_quad = false);

}  // namespace vibro
