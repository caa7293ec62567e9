// Scoring another simulator's events (see include/vibro/score.hpp).
#include "vibro/score.hpp"

#include <algorithm>
#include <cmath>
#include <map>

#include <fmt/format.h>

namespace vibro {

ScoreReport ScoreEvents(const std::vector<Event>& ours, const std::vector<TheirEvent>& theirs, double T,
                        const ScoreOptions& opt) {
  ScoreReport rep;
  rep.period = T;
  const double t_last = theirs.empty() ? 0.0 : theirs.back().t + opt.window * T;
  std::map<EventKind, std::vector<const Event*>> by_kind;
  double v_scale = 0;
  for (const auto& e : ours) {
    if (e.t > t_last) break;
    by_kind[e.kind].push_back(&e);
    if (e.kind == EventKind::kImpact) v_scale = std::max(v_scale, std::abs(e.v_before));
  }
  std::map<EventKind, std::vector<const TheirEvent*>> their_kind;
  for (const auto& e : theirs) their_kind[e.kind].push_back(&e);

  // Per kind, in order (the n-th impact of a chattering sequence with the n-th, even where the
  // impacts are closer together than the time error): the two lists are walked together, a pair
  // within window·T matches, otherwise the earlier event is left unmatched.
  std::map<const TheirEvent*, const Event*> match;
  for (auto& [kind, list] : their_kind) {
    const auto& mine = by_kind[kind];
    size_t i = 0, j = 0;
    while (i < list.size() && j < mine.size()) {
      if (std::abs(mine[j]->t - list[i]->t) <= opt.window * T) {
        match[list[i++]] = mine[j++];
      } else if (list[i]->t < mine[j]->t) {
        ++i;
      } else {
        ++j;
      }
    }
  }
  // vibro's accumulation intervals: from the last impact it resolved to the accumulation point.
  std::vector<std::pair<double, double>> tails;
  double last_impact = -1e300;
  for (const auto& e : ours) {
    if (e.kind == EventKind::kImpact) last_impact = e.t;
    if (e.kind == EventKind::kAccumulation) tails.emplace_back(last_impact, e.t);
  }
  const auto in_tail = [&](double t) {
    for (const auto& [a, b] : tails)
      if (t > a && t <= b + opt.tolerance * T) return true;  // (the point itself is known to ±tolerance)
    return false;
  };
  std::map<EventKind, KindScore> score;
  for (const auto& [kind, list] : by_kind) {
    score[kind].kind = kind;
    score[kind].ours = static_cast<long long>(list.size());
  }
  for (const auto& e : theirs) {
    KindScore& s = score[e.kind];
    s.kind = e.kind;
    ++s.theirs;
    const auto it = match.find(&e);
    const Event* m = it == match.end() ? nullptr : it->second;
    double err = 0;
    if (m) {
      ++s.matched;
      err = std::abs(e.t - m->t) / T;
      s.max_time_error = std::max(s.max_time_error, err);
      s.mean_time_error += err;
      rep.max_time_error = std::max(rep.max_time_error, err);
      if (e.velocity && v_scale > 0) {
        const double dv = std::abs(*e.velocity - m->v_before) / v_scale;
        s.max_velocity_error = std::max(s.max_velocity_error.value_or(0.0), dv);
        rep.max_velocity_error = std::max(rep.max_velocity_error.value_or(0.0), dv);
      }
    }
    if (!m && e.kind == EventKind::kImpact && in_tail(e.t)) {
      ++s.in_accumulation;
      continue;
    }
    if (!rep.divergence && (!m || err > opt.tolerance)) {
      rep.divergence = Divergence{e.t, e.kind, m ? fmt::format("time error {:.3g} T", err) : "unmatched",
                                  m ? std::optional<double>(m->t) : std::nullopt};
    }
  }
  for (auto& [kind, s] : score) {
    if (s.matched > 0) s.mean_time_error /= static_cast<double>(s.matched);
    rep.kinds.push_back(s);
  }
  return rep;
}

}  // namespace vibro
