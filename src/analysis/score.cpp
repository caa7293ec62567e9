// Scoring another simulator's events (see include/vibro/score.hpp).
#include "vibro/score.hpp"

#include <algorithm>
#include <cmath>
#include <map>

#include <fmt/format.h>

namespace vibro {
namespace {

// (last impact before each accumulation point, accumulation point + slack]: the tails of the
// chattering sequences a list sums up.
// With contacts (`by_contact`): per contact, the tails of that contact's sequences (key −1: all
// events as one list).
int ContactOf(const Event& e, bool by_contact) { return by_contact ? e.contact : -1; }
int ContactOf(const TheirEvent& e, bool by_contact) { return by_contact ? e.contact.value_or(-1) : -1; }

template <class E>
std::map<int, std::vector<std::pair<double, double>>> Tails(const std::vector<E>& list, double slack,
                                                            bool by_contact) {
  std::map<int, std::vector<std::pair<double, double>>> tails;
  std::map<int, double> last_impact;
  for (const auto& e : list) {
    const int c = ContactOf(e, by_contact);
    if (e.kind == EventKind::kImpact) last_impact[c] = e.t;
    if (e.kind == EventKind::kAccumulation)
      tails[c].emplace_back(last_impact.count(c) ? last_impact[c] : -std::numeric_limits<double>::infinity(),
                            e.t + slack);
  }
  return tails;
}

bool InTail(const std::map<int, std::vector<std::pair<double, double>>>& tails, int contact, double t) {
  const auto it = tails.find(contact);
  if (it == tails.end()) return false;
  for (const auto& [a, b] : it->second)
    if (t > a && t <= b) return true;
  return false;
}

// " at contact j" when events are matched per contact.
std::string AtContact(int contact) { return contact >= 0 ? fmt::format(" at contact {}", contact) : ""; }

}  // namespace

std::vector<std::string> EventTableProblems(const std::vector<TheirEvent>& theirs, double t_begin, double t_end,
                                            double T, double window,
                                            const std::function<std::string(const TheirEvent&)>& where,
                                            size_t limit) {
  std::vector<std::string> problems;
  const double lo = t_begin - window * T, hi = t_end + window * T;
  const TheirEvent* previous = nullptr;
  for (const auto& e : theirs) {
    if (problems.size() >= limit) {
      problems.push_back(fmt::format("stopped checking the events after {} problems", limit));
      break;
    }
    if (!std::isfinite(e.t)) {
      problems.push_back(fmt::format("{}: time {} is not a finite number", where(e), e.t));
      continue;
    }
    if (e.velocity && !std::isfinite(*e.velocity))
      problems.push_back(fmt::format("{}: velocity {} is not a finite number", where(e), *e.velocity));
    if (e.t < lo)
      problems.push_back(fmt::format("{}: time {:.17g} is before the scene's start, initial.time = {:.17g}", where(e),
                                     e.t, t_begin));
    else if (e.t > hi) {
      const double needed = std::ceil((e.t - t_begin) / T);
      problems.push_back(fmt::format(
          "{}: time {:.17g} is after the end of the scene's run, t = {:.17g} (initial.time + run.periods·T, T = {:.10g}); "
          "vibro runs the scene as given: {}",
          where(e), e.t, t_end, T,
          needed <= 1e12 ? fmt::format("set run.periods to cover the events (≥ {:.0f})", needed)
                         : std::string("no scene runs that long (run.periods ≤ 1e12)")));
    }
    if (previous && std::isfinite(previous->t)) {
      if (e.t < previous->t)
        problems.push_back(fmt::format("{}: time {:.17g} is earlier than the previous event's, {:.17g} ({}): events "
                                       "must be in time order",
                                       where(e), e.t, previous->t, where(*previous)));
      else if (e.t == previous->t && e.kind == previous->kind)
        problems.push_back(fmt::format("{}: the same time and kind as the previous event ({}): a repeated event "
                                       "(two events share a time only when their kinds differ)",
                                       where(e), where(*previous)));
    }
    previous = &e;
  }
  return problems;
}

ScoreReport ScoreEvents(const std::vector<Event>& ours, const std::vector<TheirEvent>& theirs, double T,
                        const ScoreOptions& opt) {
  ScoreReport rep;
  rep.period = T;
  // Their events name their contacts (all of them: ScoreEventTable checks it): events are matched
  // per kind and contact; otherwise per kind.
  const bool by_contact = !theirs.empty() && theirs.front().contact.has_value();
  using Key = std::pair<EventKind, int>;  // kind, contact (−1: any)
  std::map<EventKind, std::vector<const Event*>> by_kind;
  std::map<Key, std::vector<const Event*>> by_key;
  double v_scale = 0;
  for (const auto& e : ours) {
    by_kind[e.kind].push_back(&e);
    by_key[{e.kind, ContactOf(e, by_contact)}].push_back(&e);
    if (e.kind == EventKind::kImpact) v_scale = std::max(v_scale, std::abs(e.v_before));
  }
  std::map<Key, std::vector<const TheirEvent*>> their_kind;
  for (const auto& e : theirs) their_kind[{e.kind, ContactOf(e, by_contact)}].push_back(&e);

  // Per kind (and contact), in order (the n-th impact of a chattering sequence with the n-th, even
  // where the impacts are closer together than the time error): the two lists are walked
  // together, a pair within window·T matches, otherwise the earlier event is left unmatched.
  std::map<const TheirEvent*, const Event*> match;
  std::map<const Event*, const TheirEvent*> matched_ours;
  for (auto& [key, list] : their_kind) {
    const auto& mine = by_key[key];
    size_t i = 0, j = 0;
    while (i < list.size() && j < mine.size()) {
      if (std::abs(mine[j]->t - list[i]->t) <= opt.window * T) {
        matched_ours[mine[j]] = list[i];
        match[list[i++]] = mine[j++];
      } else if (list[i]->t < mine[j]->t) {
        ++i;
      } else {
        ++j;
      }
    }
  }
  const double slack = opt.tolerance * T;
  const auto our_tails = Tails(ours, slack, by_contact), their_tails = Tails(theirs, slack, by_contact);
  const auto at_end = [&](double t) { return std::abs(t - opt.t_end) <= slack; };
  bool their_accumulations = false;
  for (const auto& e : theirs) their_accumulations = their_accumulations || e.kind == EventKind::kAccumulation;

  std::map<EventKind, KindScore> score;
  for (const auto& [kind, list] : by_kind) {
    score[kind].kind = kind;
    score[kind].ours = static_cast<long long>(list.size());
  }
  const auto diverge = [&](Divergence d) {
    if (!rep.divergence || d.t < rep.divergence->t) rep.divergence = std::move(d);
  };
  for (const auto& e : theirs) {
    KindScore& s = score[e.kind];
    s.kind = e.kind;
    ++s.theirs;
    const auto it = match.find(&e);
    if (it != match.end()) {
      const Event* m = it->second;
      ++s.matched;
      const double err = std::abs(e.t - m->t) / T;
      s.max_time_error = std::max(s.max_time_error, err);
      s.mean_time_error += err;
      rep.max_time_error = std::max(rep.max_time_error, err);
      if (e.velocity && v_scale > 0) {
        const double dv = std::abs(*e.velocity - m->v_before) / v_scale;
        s.max_velocity_error = std::max(s.max_velocity_error.value_or(0.0), dv);
        rep.max_velocity_error = std::max(rep.max_velocity_error.value_or(0.0), dv);
      }
      if (err > opt.tolerance)
        diverge({e.t, e.kind, "theirs", fmt::format("time error {:.3g} T", err), m->t});
      continue;
    }
    if (e.kind == EventKind::kImpact && InTail(our_tails, ContactOf(e, by_contact), e.t)) {
      ++s.in_accumulation;
      continue;
    }
    if (at_end(e.t)) continue;
    ++s.unmatched_theirs;
    diverge({e.t, e.kind, "theirs",
             fmt::format("unmatched: vibro has no {}{} within {:g} T of it", ToString(e.kind),
                         AtContact(ContactOf(e, by_contact)), opt.window),
             std::nullopt});
  }
  for (const auto& e : ours) {
    if (matched_ours.count(&e)) continue;
    KindScore& s = score[e.kind];
    if (e.kind == EventKind::kAccumulation && !their_accumulations) {
      s.scored = false;
      continue;
    }
    if (e.kind == EventKind::kImpact && InTail(their_tails, ContactOf(e, by_contact), e.t)) {
      ++s.ours_in_accumulation;
      continue;
    }
    if (at_end(e.t)) continue;
    ++s.unmatched_ours;
    diverge({e.t, e.kind, "vibro",
             fmt::format("missed: vibro has {} {}{} here that the other simulator does not have within {:g} T",
                         e.kind == EventKind::kImpact || e.kind == EventKind::kAccumulation ? "an" : "a",
                         ToString(e.kind), AtContact(ContactOf(e, by_contact)), opt.window),
             e.t});
  }
  for (auto& [kind, s] : score) {
    if (s.matched > 0) s.mean_time_error /= static_cast<double>(s.matched);
    const long long of = s.matched + std::max(s.unmatched_theirs, s.unmatched_ours);
    if (s.scored && of > 0) s.matched_fraction = static_cast<double>(s.matched) / static_cast<double>(of);
    if (s.scored) {
      rep.matched += s.matched;
      rep.unmatched += s.unmatched_theirs + s.unmatched_ours;
    }
    rep.kinds.push_back(s);
  }
  return rep;
}

}  // namespace vibro
