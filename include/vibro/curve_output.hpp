// Two-parameter curves (two_parameter.hpp) in HDF5 and JSON (docs/output.md, "/curves").
//
// /curves: attributes param1, param2, count; one group per curve, /curves/000, /curves/001, …:
//   attributes kind, contact (int64, −1: any/one contact), period, status, end_start, end_finish,
//   corrections (corrector lines run);
//   value1, value2 (N): the curve's points in order; bracket (N): location uncertainty along the
//   corrector line (scaled box units); orbit1, orbit2 (N): where the orbit next to each point is;
//   section_time (N), X, V (N, n): that orbit's section state; stable (N) uint8,
//   max_multiplier (N), multipliers (N, m, 2) [re, im] NaN-padded; rotation_number (N, NaN but
//   for Neimark–Sacker); events, sequence, detail (N) strings;
//   special/ (codimension-two points): kind, detail (strings), value1, value2, bracket, after
//   (int64: between points after and after + 1).
#pragma once

#include <string>
#include <vector>

#include "vibro/hdf5_store.hpp"
#include "vibro/two_parameter.hpp"

namespace vibro {

void WriteCurves(Hdf5Store& store, const std::string& param1, const std::string& param2,
                 const std::vector<Curve>& curves);

// {"params": [K1, K2], "curves": [{"kind", "contact", "period", "status", "end_start",
//  "end_finish", "corrections", "points": [{"value1", "value2", "bracket", "stable",
//  "max_multiplier", "events", "sequence", "rotation_number"?}], "special": [{"kind", "value1",
//  "value2", "bracket", "after", "detail"}]}]}
std::string CurvesJson(const std::string& param1, const std::string& param2, const std::vector<Curve>& curves);

}  // namespace vibro
