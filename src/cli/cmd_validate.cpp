// `vibro validate SCENE BRANCH.csv --param KEY`: confirm or refute, point by point, a branch of
// periodic orbits computed by another tool (docs/validation.md).
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

#include <fmt/format.h>

#include "cli/cli_common.hpp"
#include "vibro/branch_check.hpp"
#include "vibro/branch_csv.hpp"
#include "vibro/summary_json.hpp"

namespace {


vibro::H5Table ValidationTable(const std::vector<vibro::ClaimedPoint>& claims,
                               const std::vector<vibro::PointCheck>& checks) {
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  const size_t N = checks.size();
  size_t m = 1, n = 1;
  for (const auto& c : checks) {
    m = std::max(m, c.orbit.multipliers.size());
    n = std::max(n, static_cast<size_t>(c.orbit.X.size()));
  }
  std::vector<double> value, distance, period, stable, sp, sim, t0, cp, cs, csp;
  std::vector<double> mu(N * m * 2, kNaN), X(N * n, kNaN), V(N * n, kNaN);
  std::vector<std::string> verdict, detail;
  for (size_t i = 0; i < N; ++i) {
    const auto& c = checks[i];
    const auto& o = c.orbit;
    const bool ok = o.status == "converged";
    value.push_back(c.value);
    verdict.push_back(c.verdict);
    detail.push_back(c.detail);
    distance.push_back(c.distance.value_or(kNaN));
    period.push_back(ok ? o.summary.period.value_or(o.period) : kNaN);
    stable.push_back(ok ? (o.stable ? 1 : 0) : kNaN);
    sp.push_back(ok ? o.summary.sticking_fraction.value_or(kNaN) : kNaN);
    sim.push_back(c.simulated_distance.value_or(kNaN));
    t0.push_back(ok ? o.section_time : kNaN);
    for (size_t k = 0; k < o.multipliers.size(); ++k) {
      mu[(i * m + k) * 2] = o.multipliers[k].real();
      mu[(i * m + k) * 2 + 1] = o.multipliers[k].imag();
    }
    for (Eigen::Index k = 0; ok && k < o.X.size(); ++k) {
      X[i * n + static_cast<size_t>(k)] = o.X[k];
      V[i * n + static_cast<size_t>(k)] = o.V[k];
    }
    cp.push_back(claims[i].period ? *claims[i].period : kNaN);
    cs.push_back(claims[i].stable ? (*claims[i].stable ? 1.0 : 0.0) : kNaN);
    csp.push_back(claims[i].sticking_fraction.value_or(kNaN));
  }
  vibro::H5Table t;
  const auto col = [&](const char* name, const std::vector<double>& v) { t.arrays.push_back({name, {v.size()}, v}); };
  col("value", value);
  col("distance", distance);
  col("period", period);
  col("stable", stable);
  col("sticking_fraction", sp);
  col("simulated_distance", sim);
  col("section_time", t0);
  col("claimed_period", cp);
  col("claimed_stable", cs);
  col("claimed_sticking_fraction", csp);
  t.arrays.push_back({"multipliers", {N, m, 2}, mu});
  t.arrays.push_back({"X", {N, n}, X});
  t.arrays.push_back({"V", {N, n}, V});
  t.strings = {{"verdict", verdict}, {"detail", detail}};
  return t;
}

}  // namespace

int RunValidate(const ValidateArgs& a) {
  const auto loaded = vibro::LoadScene(a.scene, a.sets);
  if (!vibro::SceneNumber(loaded.text_as_run, a.param))
    throw vibro::InputError({fmt::format("--param {}: not a numeric key of the scene (give it in the scene "
                                         "or with --set {})",
                                         a.param, a.param.find('[') == std::string::npos
                                                      ? a.param + "=VALUE"
                                                      : a.param.substr(0, a.param.find('[')) + "=[...] (the whole array)")});
  std::vector<std::string> problems;
  if (!(a.tolerance > 0)) problems.push_back(fmt::format("--tolerance {}: expected a positive number", a.tolerance));
  if (a.period < 0) problems.push_back(fmt::format("--period {}: expected Q ≥ 1", a.period));
  if (!problems.empty()) throw vibro::InputError(problems);
  const int n = loaded.scene.physical ? static_cast<int>(loaded.scene.physical->mass.rows())
                                      : static_cast<int>(loaded.scene.modal->frequencies.size());
  const auto claims = vibro::ReadBranchCsv(a.csv, n);

  // Every row's scene and state before anything is computed or written (bad input: exit 2).
  std::vector<vibro::Scene> scenes;
  for (const auto& p : claims) {
    auto sets = a.sets;
    sets.push_back(fmt::format("{}={:.17g}", a.param, p.value));
    try {
      scenes.push_back(vibro::LoadScene(a.scene, sets).scene);
    } catch (const vibro::InputError& e) {
      for (const auto& m : e.messages())
        problems.push_back(fmt::format("{}:{}: value {}: {}", a.csv, p.line, p.value, m));
      continue;
    }
    std::string why;
    vibro::ClaimedStart(vibro::System(scenes.back()), scenes.back(), p, why);
    if (!why.empty()) problems.push_back(fmt::format("{}:{}: {}", a.csv, p.line, why));
  }
  if (!problems.empty()) throw vibro::InputError(problems);
  std::unique_ptr<vibro::Hdf5Store> store;
  if (!a.out.empty()) store = vibro::Hdf5Store::Create(a.out, vibro::frontend::HeaderOf(loaded, vibro::System(loaded.scene)));

  vibro::CheckTolerances tol;
  tol.distance = a.tolerance;
  tol.sticking_fraction = a.sticking_tolerance;
  std::vector<vibro::PointCheck> checks;
  int disagreements = 0;
  for (size_t i = 0; i < claims.size(); ++i) {
    checks.push_back(vibro::CheckPoint(scenes[i], claims[i], a.kind, a.period, tol));
    if (checks.back().verdict != "confirmed") ++disagreements;
    if (!a.json) fmt::print(stderr, "\r{} of {} points", i + 1, claims.size());
  }
  if (!a.json) fmt::print(stderr, "\n");

  if (store) {
    store->WriteTable("/validation", ValidationTable(claims, checks));
    vibro::RunResult r;
    r.message = fmt::format("{} of {} points disagree", disagreements, checks.size());
    store->Finish(r, vibro::Attractor{});
  }
  if (a.json) {
    fmt::print("{}\n", vibro::ValidationJson(checks));
  } else {
    fmt::print("{:>16} {:>26} {:>10} {:>6} {:>8} {:>12} {:>12}  {}\n", a.param, "verdict", "distance", "period",
               "stable", "max|mu|", "SP", "detail");
    for (const auto& c : checks) {
      const auto& o = c.orbit;
      const bool ok = o.status == "converged";
      double lead = 0;
      for (const auto& m : o.multipliers) lead = std::max(lead, std::abs(m));
      fmt::print("{:>16.10g} {:>26} {:>10} {:>6} {:>8} {:>12} {:>12}  {}\n", c.value, c.verdict,
                 c.distance ? fmt::format("{:.2e}", *c.distance) : "-",
                 ok ? std::to_string(o.summary.period.value_or(o.period)) : "-",
                 ok ? (o.stable ? "yes" : "no") : "-", ok ? fmt::format("{:.6g}", lead) : "-",
                 ok && o.summary.sticking_fraction ? fmt::format("{:.8f}", *o.summary.sticking_fraction) : "-",
                 c.detail);
    }
    fmt::print("{} of {} points confirmed{}\n", checks.size() - static_cast<size_t>(disagreements), checks.size(),
               disagreements ? fmt::format(", {} disagree", disagreements) : "");
  }
  return disagreements > 0 ? kExitDisagree : 0;
}
