// Branch switching from a stored branch (see switching.hpp).
#include "frontend/switching.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include <fmt/format.h>

#include "vibro/child_process.hpp"
#include "vibro/scene_file.hpp"

namespace vibro::frontend {

SwitchedStart SwitchAtStoredPoint(const std::function<Scene(double)>& scene_at, const std::string& key, double to,
                                  const std::string& file, long long k, const StoredBranchPoint& pt,
                                  const std::string& side, Naming naming, const std::atomic<bool>* stop) {
  const std::string switch_option = OptionName(naming, "--switch"), to_option = OptionName(naming, "--to");
  // The bifurcations of the stored branch between points k − 1 and k + 1: the one nearest to k.
  double lo = pt.value, hi = pt.value;
  for (long long j : {k - 1, k + 1})
    if (j >= 0 && j < pt.points) {
      const double v = ReadBranchPoint(file, j).value;
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
  const auto all = ReadBranchBifurcations(file);
  const Bifurcation* best = nullptr;
  std::string listed;
  for (const auto& b : all) {
    if (b.kind != "branch-point" && b.kind != "flip") continue;
    listed += fmt::format("{}{} at {:.12g}", listed.empty() ? "" : ", ", b.kind, b.value);
    const double slack = 1e-9 * std::max(1.0, std::abs(b.value));
    if (b.value < lo - slack || b.value > hi + slack) continue;
    if (!best || std::abs(b.value - pt.value) < std::abs(best->value - pt.value)) best = &b;
  }
  if (!best)
    throw InputError({fmt::format("{}: no branch-point or flip of {} lies between points {} and {} "
                                  "({} = {:.12g} to {:.12g}); the branch has {}",
                                  switch_option, file, std::max(0LL, k - 1), std::min(pt.points - 1, k + 1), key, lo,
                                  hi, listed.empty() ? "none" : listed)});
  SwitchRequest req;
  req.scene_at = scene_at;
  req.kind = best->kind;
  req.value = best->value;
  req.from_value = pt.value;
  req.section_time = pt.section_time;
  req.X = pt.X;
  req.V = pt.V;
  req.period = pt.period;
  req.stop_requested = stop;
  const auto r = SwitchBranch(req);
  if (stop && stop->load()) throw Interrupted("interrupted while switching branches");
  if (!r.ok)
    throw SwitchFailed(fmt::format("{} at the {} at {} = {:.15g}: {}", switch_option, best->kind, key, best->value,
                                   r.message));
  std::vector<const SwitchStart*> toward;
  const int heading = to >= r.located ? 1 : -1;
  for (const auto& s : r.starts)
    if (s.direction == heading) toward.push_back(&s);
  if (toward.empty())
    throw InputError({fmt::format("{} {}: the new branch through the {} at {} = {:.15g} leaves it towards {} {} "
                                  "{:.15g} only; give {} on that side",
                                  to_option, to, best->kind, key, r.located, key, heading > 0 ? "<" : ">", r.located,
                                  to_option)});
  const SwitchStart* chosen = toward.front();
  for (const auto* s : toward)
    if (side == "below" ? s->x_B_offset < chosen->x_B_offset : s->x_B_offset > chosen->x_B_offset) chosen = s;
  SwitchedStart out;
  static_cast<SwitchStart&>(out) = *chosen;
  out.kind = best->kind;
  out.at = r.located;
  out.half = toward.size() > 1 ? fmt::format("the half {} the old branch (x_B at the section {:+.3e} from it)",
                                             chosen->x_B_offset > 0 ? "above" : "below", chosen->x_B_offset)
                               : fmt::format("x_B at the section {:+.3e} from the old branch", chosen->x_B_offset);
  return out;
}

}  // namespace vibro::frontend
