// Continuation branches in HDF5 (docs/validation.md): /branch carries the whole orbit of every
// point, so that a branch can be checked, restarted (`vibro continue --from FILE --point K`) or
// turned into another tool's format after it is computed. Written through Hdf5Store::WriteBranch.
//
// /branch (one row per point; N points, n modes, N_dof physical DOFs, m multipliers, k sticking
// phases at most):
//   value (N), sticking_fraction (N, NaN for none), stable (N) uint8, x_B (N), section_phase (N),
//   max_multiplier (N), events (N) strings, multipliers (N, m, 2) [re, im] NaN-padded,
//   section_time (N), X, V (N, n) modal state at the section, q, q_dot (N, N_dof) physical state
//   (physical form only), stick_phases (N, k, 2) [start, end] as ωt mod 2π·period NaN-padded,
//   stick_phase_count (N) int64, impact_offsets (N + 1) int64: the impacts of point i are rows
//   impact_offsets[i] .. impact_offsets[i+1] − 1 of impact_phase, impact_v_before, impact_v_after
//   (contact velocity just before and after);
//   sequence (N) strings, the contact sequence of each point (several contacts; empty for one
//   contact; absent in files written before it was stored);
//   attributes param, period, end, status.
// /bifurcations: value, kind, detail, bracket.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Dense>

#include "vibro/continuation.hpp"

namespace vibro {

// One stored branch point, enough to restart Newton on its orbit.
struct StoredBranchPoint {
  std::string param;
  int period = 0;
  long long points = 0;  // points on the stored branch
  double value = 0, section_time = 0;
  Eigen::VectorXd X, V;  // modal state at the section
  // Several contacts: the point's contact sequence (/branch/sequence; empty when the file has no
  // such dataset, or for one contact).
  std::string sequence;
};

// Point k (0-based) of the branch stored in `path`. Throws InputError naming the file when it
// holds no branch, a branch without orbit states (written before they were stored), or fewer
// than k + 1 points.
StoredBranchPoint ReadBranchPoint(const std::string& path, long long k);

// The stored point of the branch in `path` nearest `value` among those at least `apart` from it
// (the nearest of all when none is): e.g. the orbit just before a grazing, where it clears the
// contact plainly. With `before` ≥ 0, a bifurcation's point (Bifurcation::point, the branch's
// point before it): that point, or the first one back along the branch from it that is at least
// `apart` from `value` (a branch that goes on through a grazing or round a loop passes the same
// value again on other orbits). Throws as ReadBranchPoint.
StoredBranchPoint NearestBranchPoint(const std::string& path, double value, double apart, long long before = -1);

// The point before the stored bifurcation of `kind` nearest `value` (Bifurcation::point), among
// those within `within` of it; −1 when there is none or the file does not say. For a bifurcation
// named by its value (`vibro prove --bifurcation KIND:KEY=VALUE --from BRANCH.h5`).
long long BifurcationPointNear(const std::string& path, const std::string& kind, double value, double within);

// The bifurcations stored with the branch in `path` (/bifurcations: kind, value, bracket; detail
// and contact are not read). Throws InputError naming the file and dataset when they are missing
// or malformed.
std::vector<Bifurcation> ReadBranchBifurcations(const std::string& path);

}  // namespace vibro
