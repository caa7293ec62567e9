// Two-parameter curves for the command line and Python (see curves.hpp).
#include "frontend/curves.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "frontend/commands.hpp"
#include "vibro/hdf5_branch.hpp"
#include "vibro/orbit_from_state.hpp"

namespace vibro::frontend {

CurvePlan PlanCurves(const SceneOrigin& origin, const LoadedScene& loaded, const CurveSpec& a, Naming naming) {
  const auto opt = [&](const char* o) { return OptionName(naming, o); };
  std::vector<std::string> problems;
  if (a.params.size() != 2 || a.params[0] == a.params[1])
    problems.push_back(opt("--param") + ": expected KEY1,KEY2 (two different keys)");
  if (a.range1.size() != 2 || !(a.range1[0] < a.range1[1])) problems.push_back(opt("--range1") + ": expected A,B with A < B");
  if (a.range2.size() != 2 || !(a.range2[0] < a.range2[1])) problems.push_back(opt("--range2") + ": expected C,D with C < D");
  for (const auto& k : a.kinds)
    if (std::find(CurveKinds().begin(), CurveKinds().end(), k) == CurveKinds().end())
      problems.push_back(fmt::format("{} {}: expected one of {}", opt("--kind"), k, fmt::join(CurveKinds(), ", ")));
  const bool stored = !a.from.empty();
  if (stored == !a.toward.empty())
    problems.push_back(fmt::format("give the start: {} BRANCH.h5 {} K, or {} A,B", opt("--from"), opt("--point"), opt("--toward")));
  if (!stored && !a.toward.empty() && a.toward.size() != 2 && a.toward.size() != 2 * a.kinds.size())
    problems.push_back(opt("--toward") + ": expected A,B (a point of the plane), or one point per kind");
  if (!stored && a.kinds.empty()) problems.push_back(opt("--kind") + ": give the kind(s) of bifurcation to follow");
  if (stored && a.point < 0) problems.push_back(fmt::format("{} {}: give the bifurcation with {} K", opt("--from"), a.from, opt("--point")));
  if (!(a.step > 0 && a.step <= 1)) problems.push_back(fmt::format("{} {}: expected a number in (0, 1]", opt("--step"), a.step));
  if (!(a.max_step >= a.step && a.max_step <= 1))
    problems.push_back(fmt::format("{} {}: expected a number in [{}, 1]", opt("--max-step"), a.max_step, opt("--step")));
  CheckInteger(naming, "--max-points", a.max_points, {1, 1 << 20}, problems);
  CheckInteger(naming, "--period", a.period, kPeriodLimit, problems);
  CheckInteger(naming, "--transient", a.transient, kTransientLimit, problems);
  CheckInteger(naming, "--contact", a.contact, {-1, 4096}, problems);
  std::optional<double> v1, v2;
  if (a.params.size() == 2) {
    for (const auto& k : a.params)
      if (!SceneNumber(loaded.text_as_run, k)) problems.push_back(NotANumericKey(opt("--param"), k));
    v1 = SceneNumber(loaded.text_as_run, a.params[0]);
    v2 = SceneNumber(loaded.text_as_run, a.params[1]);
  }
  ThrowIfAny(problems);
  const auto scene_at = [origin, key1 = a.params[0], key2 = a.params[1]](double x, double y) {
    SceneOrigin at = origin;
    at.sets.push_back(Assignment(key1, x));
    return SceneWith(at, key2, y);
  };
  CurveRequest req;
  req.scene_at = scene_at;
  req.lo1 = a.range1[0];
  req.hi1 = a.range1[1];
  req.lo2 = a.range2[0];
  req.hi2 = a.range2[1];
  req.step = a.step;
  req.max_step = a.max_step;
  req.max_points = static_cast<int>(a.max_points);
  req.contact = static_cast<int>(a.contact);
  std::vector<std::string> kinds = a.kinds;
  if (stored) {
    // The stored bifurcation: the branch point nearest to it (not on it) is the start, and the
    // search runs along the branch's key, past the bifurcation.
    const auto bifs = ReadBranchBifurcations(a.from);
    if (a.point >= static_cast<long long>(bifs.size()))
      throw InputError({fmt::format("{} {}: {} {}: the branch has {} bifurcation(s)", opt("--from"), a.from, opt("--point"),
                                    a.point, bifs.size())});
    const Bifurcation& b = bifs[static_cast<size_t>(a.point)];
    if (kinds.empty()) kinds = {b.kind};
    if (std::find(CurveKinds().begin(), CurveKinds().end(), b.kind) == CurveKinds().end())
      throw InputError({fmt::format("{} {} {} {}: a {} has no curve to follow (kinds: {})", opt("--from"), a.from,
                                    opt("--point"), a.point, b.kind, fmt::join(CurveKinds(), ", "))});
    const auto first = ReadBranchPoint(a.from, 0);
    const int axis = first.param == a.params[0] ? 0 : first.param == a.params[1] ? 1 : -1;
    if (axis < 0)
      throw InputError({fmt::format("{} {}: the branch varies {}, not {} or {}", opt("--from"), a.from, first.param,
                                    a.params[0], a.params[1])});
    // The nearest point at least half a step (of the box) away: the line from it to the
    // bifurcation is then long enough for continuation to pass it as it did (a point within
    // rounding of a fold would have the corrector crawl round the turn).
    const double width = axis == 0 ? a.range1[1] - a.range1[0] : a.range2[1] - a.range2[0];
    const double away = 0.5 * a.step * width, tol = 1e-9 * (1.0 + std::abs(b.value));
    std::optional<StoredBranchPoint> best, fallback;
    for (long long k = 0; k < first.points; ++k) {
      auto p = ReadBranchPoint(a.from, k);
      const double dist = std::abs(p.value - b.value);
      if (dist <= tol) continue;
      auto& slot = dist >= away ? best : fallback;
      if (!slot || dist < std::abs(slot->value - b.value)) slot = std::move(p);
    }
    if (!best) best = std::move(fallback);
    if (!best) throw InputError({fmt::format("{} {}: no stored point next to bifurcation {}", opt("--from"), a.from, a.point)});
    req.start1 = axis == 0 ? best->value : *v1;
    req.start2 = axis == 1 ? best->value : *v2;
    req.period = best->period;
    req.section_time = best->section_time;
    req.X = best->X;
    req.V = best->V;
    const double delta = 2.0 * (b.value - best->value);
    req.dir1 = axis == 0 ? delta : 0.0;
    req.dir2 = axis == 1 ? delta : 0.0;
  } else {
    const Scene scene = scene_at(*v1, *v2);
    const System sys(scene);
    OrbitRequest oreq;
    oreq.kind = OrbitKind::kAuto;
    oreq.period = static_cast<int>(a.period);
    oreq.transient_periods = static_cast<int>(a.transient);
    const OrbitResult o = SolveOrbit(sys, scene, oreq);
    if (o.status != "converged")
      throw InputError({fmt::format("no periodic orbit at the scene's ({}, {}) = ({}, {}) to start from: {}", a.params[0],
                                    a.params[1], *v1, *v2, o.message)});
    req.start1 = *v1;
    req.start2 = *v2;
    req.period = o.period;
    req.section_time = o.section_time;
    req.X = o.X;
    req.V = o.V;
    req.dir1 = a.toward[0] - *v1;
    req.dir2 = a.toward[1] - *v2;
  }
  std::vector<std::pair<double, double>> directions;
  for (size_t i = 0; i < kinds.size(); ++i)
    directions.emplace_back(!stored && a.toward.size() > 2 ? a.toward[2 * i] - *v1 : req.dir1,
                            !stored && a.toward.size() > 2 ? a.toward[2 * i + 1] - *v2 : req.dir2);
  return CurvePlan{req, kinds, directions, a.params[0], a.params[1]};
}

std::vector<Curve> TraceCurves(const CurvePlan& plan, const std::atomic<bool>* stop,
                               const std::function<void(size_t, size_t, double, double)>& on_point) {
  std::vector<Curve> curves;
  CurveRequest req = plan.request;
  req.stop_requested = stop;
  for (size_t i = 0; i < plan.kinds.size(); ++i) {
    if (stop && stop->load()) break;
    req.kind = plan.kinds[i];
    req.dir1 = plan.directions[i].first;
    req.dir2 = plan.directions[i].second;
    req.progress = [&, i](size_t n, double x, double y) {
      if (on_point) on_point(i, n, x, y);
    };
    Curve c = TraceCurve(req);
    c.param1 = plan.param1;
    c.param2 = plan.param2;
    curves.push_back(std::move(c));
  }
  return curves;
}

}  // namespace vibro::frontend
