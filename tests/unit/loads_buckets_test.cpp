// The loads recorder's bounded memory (docs/loads.md §5): a LoadsRecorder with a small bucket cap
// is fed a synthetic stream of events and checkpoints over many times more periods than the cap,
// and its means and batch-means intervals are checked against a plain recomputation from the same
// per-period values, kept by the test (the rule of docs/loads.md §5 written out directly: one sum
// per period, blocks of whole buckets once the cap is passed), including phases spanning period
// boundaries, the `partial` flag (a phase held with other contacts without an account) and a run
// resumed in the middle. The recorder's rows stay within the cap.
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "vibro/loads.hpp"
#include "vibro/scene_file.hpp"

namespace vibro::test {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// One period of one contact, as the test sums it itself.
struct Truth {
  double impacts = 0, impulse = 0, reaction = 0, energy = 0, work = 0, held = 0;
  bool partial = false;
};

// The stream a run would report: events and period-boundary checkpoints, in time order.
struct Item {
  long long period;
  std::optional<Event> event;
  std::optional<Checkpoint> checkpoint;
};

struct Stream {
  std::vector<Item> items;
  std::vector<std::vector<Truth>> truth;  // [contact][period]
};

// `periods` periods of `contacts` contacts: 0 to 3 impacts per period and contact, sticking phases
// of 0 to 2 period boundaries (the checkpoints carry the open phase's ∫R dt and duration so far),
// and at the periods in `partial` (contact 1) a phase held with another contact without an account
// (its release has NaN ∫R dt and duration).
Stream Generate(int contacts, long long periods, const std::vector<double>& mass,
                const std::vector<long long>& partial, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Stream s;
  s.truth.assign(static_cast<size_t>(contacts), std::vector<Truth>(static_cast<size_t>(periods)));
  std::vector<int> open_left(static_cast<size_t>(contacts), -1);  // boundaries left; −1: not held
  std::vector<double> cum_r(static_cast<size_t>(contacts), 0), cum_h(static_cast<size_t>(contacts), 0);
  const auto checkpoint = [&](long long p) {
    Checkpoint cp{};
    cp.clock.period = p;
    for (int j = 0; j < contacts; ++j) {
      const bool open = open_left[static_cast<size_t>(j)] >= 0;
      cp.reaction_integral.push_back(open ? cum_r[static_cast<size_t>(j)] : 0.0);
      cp.stick_duration.push_back(open ? cum_h[static_cast<size_t>(j)] : 0.0);
      cp.reaction_max.push_back(kNaN);
    }
    s.items.push_back({p, std::nullopt, cp});
  };
  for (long long p = 0; p < periods; ++p) {
    checkpoint(p);
    for (int j = 0; j < contacts; ++j) {
      const auto J = static_cast<size_t>(j);
      Truth& t = s.truth[J][static_cast<size_t>(p)];
      if (open_left[J] < 0) {
        const int n = static_cast<int>(4 * u(rng));
        for (int i = 0; i < n; ++i) {
          Event e{};
          e.kind = EventKind::kImpact;
          e.clock.period = p;
          e.contact = j;
          e.v_before = -u(rng);
          e.v_after = -0.6 * e.v_before;
          e.impulse = 1.6 * mass[J] * -e.v_before;
          e.energy_dissipated = 0.5 * (1 - 0.36) * mass[J] * e.v_before * e.v_before;
          s.items.push_back({p, e, std::nullopt});
          t.impacts += 1;
          t.impulse += e.impulse;
          t.energy += e.energy_dissipated;
          t.work += 0.5 * mass[J] * (e.v_before * e.v_before + e.v_after * e.v_after);
        }
        const bool unaccounted = j == 1 && std::find(partial.begin(), partial.end(), p) != partial.end();
        // No ordinary phase of contact 1 may still be open at a partial period.
        const bool near = j == 1 && std::any_of(partial.begin(), partial.end(), [&](long long q) { return p < q && q <= p + 2; });
        if (unaccounted || (!near && u(rng) < 0.3)) {
          Event st{};
          st.kind = EventKind::kStick;
          st.clock.period = p;
          st.contact = j;
          s.items.push_back({p, st, std::nullopt});
          open_left[J] = unaccounted ? 0 : static_cast<int>(3 * u(rng));
          cum_r[J] = cum_h[J] = 0;
          if (unaccounted) {
            // Held with another contact, not accounted: released at once with NaN values.
            Event rel{};
            rel.kind = EventKind::kRelease;
            rel.clock.period = p;
            rel.contact = j;
            s.items.push_back({p, rel, std::nullopt});
            open_left[J] = -1;
            t.partial = true;
            continue;
          }
        }
      }
      if (open_left[J] >= 0) {
        // This period's share of the open phase.
        const double dr = u(rng), dh = 0.5 * u(rng);
        cum_r[J] += dr;
        cum_h[J] += dh;
        t.reaction += dr;
        t.held += dh;
        if (open_left[J] == 0) {
          Event rel{};
          rel.kind = EventKind::kRelease;
          rel.clock.period = p;
          rel.contact = j;
          rel.reaction_integral = cum_r[J];
          rel.stick_duration = cum_h[J];
          s.items.push_back({p, rel, std::nullopt});
          open_left[J] = -1;
        } else {
          --open_left[J];
        }
      }
    }
  }
  checkpoint(periods);
  return s;
}

// Feeds the items of periods [from, to]: from the checkpoint at `from` (the start, or a resume) to
// the one at `to` (the end of the run).
void Feed(LoadsRecorder& rec, const Stream& s, long long from, long long to) {
  for (const Item& it : s.items) {
    if (it.period < from || it.period > to) continue;
    if (it.checkpoint) rec.OnCheckpoint(*it.checkpoint);
    else if (it.period < to) rec.OnEvent(*it.event);
  }
}

// 95 % two-sided quantiles of Student's t (standard tables) for the block counts used here.
double T975(int blocks) {
  switch (blocks - 1) {
    case 1: return 12.706;
    case 2: return 4.303;
    case 3: return 3.182;
    case 4: return 2.776;
    case 9: return 2.262;
    default: ADD_FAILURE() << "no t quantile for " << blocks << " blocks"; return kNaN;
  }
}

std::vector<double> Quantities(const Truth& sum, double n, double period) {
  const double t = n * period;
  return {sum.impacts / n, sum.impulse / n, sum.partial ? kNaN : sum.reaction / n,
          sum.partial ? kNaN : (sum.impulse + sum.reaction) / t, sum.energy / t, sum.work / t,
          sum.partial ? kNaN : sum.held / t};
}

Truth Sum(const std::vector<Truth>& rows, long long a, long long b) {
  Truth s;
  for (long long p = a; p < b; ++p) {
    const Truth& r = rows[static_cast<size_t>(p)];
    s.impacts += r.impacts;
    s.impulse += r.impulse;
    s.reaction += r.reaction;
    s.energy += r.energy;
    s.work += r.work;
    s.held += r.held;
    s.partial = s.partial || r.partial;
  }
  return s;
}

struct Expected {
  long long first = 0, periods = 0, block_periods = 0;
  std::vector<double> mean;
  std::vector<std::optional<std::pair<double, double>>> ci;
};

// docs/loads.md §5 over periods [begin, last) of one contact, written out directly. Up to `cap`
// periods: L = ⌊n/blocks⌋, the last blocks·L periods, blocks of L periods. Beyond: buckets of the
// least power of two B with n ≤ cap·B periods from `begin`; blocks of ⌊(n/B)/blocks⌋ whole buckets,
// the last ones of the whole buckets; the means over the last n − n % blocks periods (when
// n % blocks < cap/16; else those of the blocks), the interval centred on them.
Expected Recompute(const std::vector<Truth>& rows, long long begin, long long last, int blocks, long long cap,
                   double period) {
  Expected e;
  const long long n = last - begin;
  long long B = 1;
  while (n > cap * B) B *= 2;
  const long long L = B == 1 ? n / blocks : (n / B) / blocks * B;
  if (L < 2) {  // no interval: the means of the whole window
    e.first = begin;
    e.periods = n;
    e.mean = Quantities(Sum(rows, begin, last), static_cast<double>(n), period);
    e.ci.assign(7, std::nullopt);
    return e;
  }
  e.block_periods = L;
  const long long blocks_end = B == 1 ? last : begin + (n / B) * B, blocks_begin = blocks_end - blocks * L;
  std::vector<std::vector<double>> bm;
  for (int i = 0; i < blocks; ++i)
    bm.push_back(Quantities(Sum(rows, blocks_begin + i * L, blocks_begin + (i + 1) * L), static_cast<double>(L), period));
  const long long cut = n % blocks;
  const bool own_window = B > 1 && cut < cap / 16;
  e.first = own_window ? begin + cut : blocks_begin;
  e.periods = own_window ? n - cut : blocks * L;
  const std::vector<double> window = Quantities(Sum(rows, e.first, e.first + e.periods), static_cast<double>(e.periods), period);
  for (size_t q = 0; q < 7; ++q) {
    double m = 0, v = 0;
    for (const auto& b : bm) m += b[q];
    m /= blocks;
    for (const auto& b : bm) v += (b[q] - m) * (b[q] - m);
    v /= blocks - 1;
    const double half = std::max(T975(blocks) * std::sqrt(v / blocks),
                                 16 * std::numeric_limits<double>::epsilon() * static_cast<double>(L) * std::abs(m));
    const double centre = own_window ? window[q] : m;
    e.mean.push_back(centre);
    e.ci.push_back(std::isfinite(m) && std::isfinite(centre) ? std::optional(std::pair{centre - half, centre + half})
                                                              : std::nullopt);
  }
  return e;
}

void ExpectNear(double got, double want, const std::string& what) {
  if (std::isnan(want)) {
    EXPECT_TRUE(std::isnan(got)) << what << ": " << got;
    return;
  }
  EXPECT_NEAR(got, want, 1e-11 * std::max(1.0, std::abs(want))) << what;
}

void ExpectSummary(const LoadsSummary& s, const Stream& st, long long begin, long long last, int blocks,
                   long long cap, double period, const std::string& label) {
  ASSERT_EQ(s.contacts.size(), st.truth.size()) << label;
  for (size_t j = 0; j < st.truth.size(); ++j) {
    const Expected e = Recompute(st.truth[j], begin, last, blocks, cap, period);
    const std::string at = label + " contact " + std::to_string(j);
    EXPECT_EQ(s.first_period, e.first) << at;
    EXPECT_EQ(s.periods, e.periods) << at;
    EXPECT_EQ(s.block_periods, e.block_periods) << at << " " << s.note;
    const ContactLoads& c = s.contacts[j];
    const double got[7] = {c.impacts_per_period, c.impulse_per_period, c.reaction_integral_per_period,
                           c.mean_force, c.dissipated_power, c.work_rate, c.contact_fraction};
    const ContactLoads::Interval* ci[7] = {&c.impacts_per_period_ci, &c.impulse_per_period_ci,
                                           &c.reaction_integral_per_period_ci, &c.mean_force_ci,
                                           &c.dissipated_power_ci, &c.work_rate_ci, &c.contact_fraction_ci};
    for (size_t q = 0; q < 7; ++q) {
      const std::string what = at + " quantity " + std::to_string(q);
      ExpectNear(got[q], e.mean[q], what + " mean");
      ASSERT_EQ(ci[q]->has_value(), e.ci[q].has_value()) << what;
      if (e.ci[q]) {
        ExpectNear((*ci[q])->first, e.ci[q]->first, what + " lo");
        ExpectNear((*ci[q])->second, e.ci[q]->second, what + " hi");
      }
    }
  }
}

TEST(LoadsBuckets, MeansAndIntervalsAgainstPlainSumsBeyondTheCap) {
  const System sys(LoadScene(std::string(VIBRO_SCENES_DIR) + "/contacts_two_sided_1dof.toml", {}).scene);
  ASSERT_EQ(sys.contacts().size(), 2u);
  const std::vector<double> mass = {1 / sys.contacts()[0].s_B, 1 / sys.contacts()[1].s_B};
  constexpr long long cap = 64;  // head: 4 periods kept apart
  const long long total = 10 * cap + 2000;
  // Contact 1 is partial at period 30 (inside every window below), contact 0 never.
  const Stream st = Generate(2, total, mass, {30}, 7);
  // Lengths below the cap, up to one merge, bucket 0 shorter and longer than the head, and 40× cap.
  for (const long long last : {50LL, 77LL, 140LL, 200LL, 300LL, 677LL, 1500LL, total}) {
    for (const long long skip : {0LL, 13LL}) {
      LoadsRecorder rec(sys, skip, cap);
      Feed(rec, st, 0, last);
      for (const int blocks : {2, 3, 4, 5, 10}) {
        const std::string label = "last " + std::to_string(last) + " skip " + std::to_string(skip) + " blocks " +
                                  std::to_string(blocks);
        ExpectSummary(rec.Summary(blocks), st, skip, last, blocks, cap, sys.period(), label);
      }
      // Means only: the whole window, every bucket (the last partial one too).
      const LoadsSummary none = rec.Summary(0);
      const Expected e = Recompute(st.truth[0], skip, last, 1000000, cap, sys.period());
      EXPECT_EQ(none.periods, last - skip);
      ExpectNear(none.contacts[0].work_rate, e.mean[5], "blocks 0 work rate");
      ExpectNear(none.contacts[0].contact_fraction, e.mean[6], "blocks 0 contact fraction");
      EXPECT_TRUE(std::isnan(none.contacts[1].mean_force)) << "partial period 30 in the window";
      EXPECT_NE(none.note.find("contact 1"), std::string::npos) << none.note;
    }
  }
}

TEST(LoadsBuckets, PartialOnlyBeforeTheMeansWindow) {
  // Contact 1 partial at period 2 only: left out of the means (n % 4 = 3 first periods cut), but
  // bucket 0 holds it, so a block containing bucket 0 is unknown and there is no interval then.
  const System sys(LoadScene(std::string(VIBRO_SCENES_DIR) + "/contacts_two_sided_1dof.toml", {}).scene);
  const std::vector<double> mass = {1 / sys.contacts()[0].s_B, 1 / sys.contacts()[1].s_B};
  constexpr long long cap = 64;
  const long long last = 64 * 8 + 3;  // 515 periods: buckets of 16, 32 whole
  const Stream st = Generate(2, last, mass, {2}, 11);
  LoadsRecorder rec(sys, 0, cap);
  Feed(rec, st, 0, last);
  EXPECT_EQ(rec.bucket_periods(), 16);
  const LoadsSummary s = rec.Summary(4);  // 4 blocks of 8 buckets: bucket 0 in the first block
  EXPECT_EQ(s.first_period, 3);
  EXPECT_TRUE(std::isfinite(s.contacts[1].mean_force));
  EXPECT_FALSE(s.contacts[1].mean_force_ci.has_value());
  EXPECT_TRUE(s.contacts[1].work_rate_ci.has_value());
  ExpectSummary(s, st, 0, last, 4, cap, sys.period(), "partial before the window");
  // 3 blocks of 10 buckets (buckets 2 to 31, without period 2), but n % 3 = 2: the means' window
  // starts at period 2, its mean force is unknown, and so is the interval centred on it.
  const LoadsSummary s3 = rec.Summary(3);
  EXPECT_EQ(s3.first_period, 2);
  EXPECT_TRUE(std::isnan(s3.contacts[1].mean_force));
  EXPECT_FALSE(s3.contacts[1].mean_force_ci.has_value());
  ExpectSummary(s3, st, 0, last, 3, cap, sys.period(), "partial before the blocks");
}

TEST(LoadsBuckets, ResumedInTheMiddleEqualsUninterrupted) {
  // A run resumed at period 300 (a sticking phase may be open there: the checkpoint carries its
  // part so far) records the same loads over the same window as the run that went through.
  const System sys(LoadScene(std::string(VIBRO_SCENES_DIR) + "/contacts_two_sided_1dof.toml", {}).scene);
  const std::vector<double> mass = {1 / sys.contacts()[0].s_B, 1 / sys.contacts()[1].s_B};
  constexpr long long cap = 64;
  const long long total = 3000, resume = 300, skip = 400;
  const Stream st = Generate(2, total, mass, {1000}, 5);
  bool open_at_resume = false;
  for (const Item& it : st.items)
    if (it.checkpoint && it.period == resume)
      for (const double r : it.checkpoint->reaction_integral) open_at_resume = open_at_resume || r > 0;
  LoadsRecorder whole(sys, skip, cap), resumed(sys, skip - resume, cap);
  Feed(whole, st, 0, total);
  Feed(resumed, st, resume, total);
  EXPECT_EQ(whole.bucket_periods(), resumed.bucket_periods());
  for (const int blocks : {0, 2, 3, 5, 10}) {
    const LoadsSummary a = whole.Summary(blocks), b = resumed.Summary(blocks);
    ExpectSummary(a, st, skip, total, blocks == 0 ? 1000000 : blocks, cap, sys.period(), "uninterrupted");
    EXPECT_EQ(a.first_period, b.first_period);
    EXPECT_EQ(a.periods, b.periods);
    for (size_t j = 0; j < 2; ++j) {
      EXPECT_EQ(a.contacts[j].work_rate, b.contacts[j].work_rate) << blocks;
      const double ra = a.contacts[j].reaction_integral_per_period, rb = b.contacts[j].reaction_integral_per_period;
      EXPECT_TRUE(ra == rb || (std::isnan(ra) && std::isnan(rb))) << blocks << " " << ra << " " << rb;
      EXPECT_EQ(std::isnan(ra), j == 1) << "contact 1 is partial at period 1000";
      EXPECT_EQ(a.contacts[j].contact_fraction_ci, b.contacts[j].contact_fraction_ci) << blocks;
      EXPECT_EQ(a.contacts[j].impulse_per_period_ci, b.contacts[j].impulse_per_period_ci) << blocks;
    }
  }
  // The stream does carry a phase open across the resume point for this seed (else the test
  // would not exercise the checkpoint's share).
  EXPECT_TRUE(open_at_resume);
}

// What a store keeps: every period's rows as the recorder closes it (LoadsSink).
struct KeptRows final : LoadsSink {
  std::vector<long long> periods;
  std::vector<std::vector<LoadsRow>> rows;
  void OnPeriodLoads(long long period, const std::vector<LoadsRow>& r) override {
    periods.push_back(period);
    rows.push_back(r);
  }
};

void ExpectIdentical(const LoadsSummary& a, const LoadsSummary& b, const std::string& label) {
  EXPECT_EQ(a.first_period, b.first_period) << label;
  EXPECT_EQ(a.periods, b.periods) << label;
  EXPECT_EQ(a.block_periods, b.block_periods) << label;
  EXPECT_EQ(a.note, b.note) << label;
  EXPECT_EQ(a.whole_run, b.whole_run) << label;
  ASSERT_EQ(a.contacts.size(), b.contacts.size()) << label;
  const auto same = [](double x, double y) { return x == y || (std::isnan(x) && std::isnan(y)); };
  for (size_t j = 0; j < a.contacts.size(); ++j) {
    const ContactLoads &x = a.contacts[j], &y = b.contacts[j];
    for (const auto& [u, v] : {std::pair{x.impacts_per_period, y.impacts_per_period},
                               {x.impulse_per_period, y.impulse_per_period},
                               {x.reaction_integral_per_period, y.reaction_integral_per_period},
                               {x.mean_force, y.mean_force}, {x.dissipated_power, y.dissipated_power},
                               {x.work_rate, y.work_rate}, {x.contact_fraction, y.contact_fraction}})
      EXPECT_TRUE(same(u, v)) << label << " contact " << j << ": " << u << " vs " << v;
    EXPECT_EQ(x.work_rate_ci, y.work_rate_ci) << label;
    EXPECT_EQ(x.impulse_per_period_ci, y.impulse_per_period_ci) << label;
    EXPECT_EQ(x.contact_fraction_ci.has_value(), y.contact_fraction_ci.has_value()) << label;
    if (x.contact_fraction_ci && y.contact_fraction_ci) {
      EXPECT_EQ(*x.contact_fraction_ci, *y.contact_fraction_ci) << label;
    }
  }
}

TEST(LoadsBuckets, ReplayedRowsGiveTheWholeRunsLoadsToTheBit) {
  // A run stopped at period `at` whose store kept every period's rows (the sink), resumed by a
  // recorder that is given them back (Resumed, ReplayPeriod) and then sees the rest of the stream,
  // reports the loads of the run that went through, to the bit: before and after the rows are
  // merged into buckets, with a phase open at the resume point, with the partial period, and with
  // the transient of a longer run (an extension: skip grows with the total).
  const System sys(LoadScene(std::string(VIBRO_SCENES_DIR) + "/contacts_two_sided_1dof.toml", {}).scene);
  const std::vector<double> mass = {1 / sys.contacts()[0].s_B, 1 / sys.contacts()[1].s_B};
  constexpr long long cap = 64;
  const long long total = 3000;
  const Stream st = Generate(2, total, mass, {1000}, 5);
  for (const long long skip : {0LL, 300LL}) {
    LoadsRecorder whole(sys, skip, cap);
    Feed(whole, st, 0, total);
    for (const long long at : {1LL, 40LL, 200LL, 300LL, 1000LL, 1001LL, 2999LL}) {
      const std::string label = "skip " + std::to_string(skip) + ", resumed at " + std::to_string(at);
      // The interrupted run, with its store.
      KeptRows kept;
      LoadsRecorder first(sys, skip, cap);
      first.SetSink(&kept);
      Feed(first, st, 0, at);
      ASSERT_EQ(kept.periods.size(), static_cast<size_t>(at)) << label;
      for (long long p = 0; p < at; ++p) EXPECT_EQ(kept.periods[static_cast<size_t>(p)], p) << label;
      // Resumed at the checkpoint of period `at`.
      const Checkpoint* cp = nullptr;
      for (const Item& it : st.items)
        if (it.checkpoint && it.period == at) cp = &*it.checkpoint;
      ASSERT_NE(cp, nullptr);
      LoadsRecorder resumed(sys, skip, cap);
      KeptRows more;
      resumed.Resumed(0, 0, *cp);
      for (const auto& r : kept.rows) resumed.ReplayPeriod(r);
      resumed.SetSink(&more);
      for (const Item& it : st.items) {
        if (it.period < at || it.period > total) continue;
        if (it.checkpoint) {
          if (it.period > at) resumed.OnCheckpoint(*it.checkpoint);
        } else if (it.period < total) {
          resumed.OnEvent(*it.event);
        }
      }
      EXPECT_EQ(more.periods.size(), static_cast<size_t>(total - at)) << label;
      EXPECT_EQ(whole.bucket_periods(), resumed.bucket_periods()) << label;
      for (const int blocks : {0, 2, 3, 5, 10}) ExpectIdentical(whole.Summary(blocks), resumed.Summary(blocks), label);
      // Replayed rows are the store's: the sink is not given them again.
      EXPECT_TRUE(more.periods.empty() || more.periods.front() == at) << label;
    }
  }
}

TEST(LoadsBuckets, PeriodsNotKnownCutTheWindowAndSaySo) {
  // A run resumed at period 1000 from a store without rows: the window of the whole run (from
  // period 300) is cut to the periods from 1000, and the summary says so; equal to a recorder
  // that saw only those periods with its window starting there.
  const System sys(LoadScene(std::string(VIBRO_SCENES_DIR) + "/contacts_two_sided_1dof.toml", {}).scene);
  const std::vector<double> mass = {1 / sys.contacts()[0].s_B, 1 / sys.contacts()[1].s_B};
  constexpr long long cap = 64;
  const long long total = 3000, at = 1000, skip = 300;
  const Stream st = Generate(2, total, mass, {}, 9);
  const Checkpoint* cp = nullptr;
  for (const Item& it : st.items)
    if (it.checkpoint && it.period == at) cp = &*it.checkpoint;
  ASSERT_NE(cp, nullptr);
  LoadsRecorder resumed(sys, skip, cap), fresh(sys, 0, cap);
  resumed.Resumed(0, at, *cp);
  Feed(fresh, st, at, total);
  for (const Item& it : st.items) {
    if (it.period < at || it.period > total) continue;
    if (it.checkpoint) {
      if (it.period > at) resumed.OnCheckpoint(*it.checkpoint);
    } else if (it.period < total) {
      resumed.OnEvent(*it.event);
    }
  }
  for (const int blocks : {0, 2, 10}) {
    const LoadsSummary s = resumed.Summary(blocks), f = fresh.Summary(blocks);
    EXPECT_FALSE(s.whole_run);
    EXPECT_EQ(s.known_from, at);
    EXPECT_EQ(s.first_period + s.periods, total);
    EXPECT_GE(s.first_period, at);
    EXPECT_NE(s.coverage.find("the periods before 1000 are not known"), std::string::npos) << s.coverage;
    EXPECT_NE(s.coverage.find("not the window from period 300"), std::string::npos) << s.coverage;
    LoadsSummary g = f;
    g.whole_run = false;
    ExpectIdentical(s, g, "cut window, blocks " + std::to_string(blocks));
  }
}

TEST(LoadsBuckets, MemoryStaysWithinTheCap) {
  const System sys(LoadScene(std::string(VIBRO_SCENES_DIR) + "/contacts_two_sided_1dof.toml", {}).scene);
  const std::vector<double> mass = {1 / sys.contacts()[0].s_B, 1 / sys.contacts()[1].s_B};
  constexpr long long cap = 64;
  const Stream st = Generate(2, 40 * cap, mass, {}, 3);
  LoadsRecorder rec(sys, 0, cap);
  long long fed_to = 0;
  for (const long long last : {cap, 10 * cap, 40 * cap}) {
    Feed(rec, st, fed_to, last);
    fed_to = last;
    EXPECT_LE(rec.stored_rows(), static_cast<size_t>(cap + cap / 16)) << last;
  }
  EXPECT_EQ(rec.bucket_periods(), 64);  // 2560 periods ≤ 64 buckets of 64
  // 40 whole buckets: 41 blocks cannot be formed (a short run would have had 62 periods per block).
  const LoadsSummary many = rec.Summary(41);
  EXPECT_EQ(many.block_periods, 0);
  EXPECT_NE(many.note.find("too many blocks"), std::string::npos) << many.note;
  EXPECT_FALSE(many.contacts[0].work_rate_ci.has_value());
  EXPECT_EQ(many.periods, 40 * cap);
  EXPECT_EQ(rec.Summary(40).block_periods, 64);
  // The default cap: 2^16 rows per contact.
  LoadsRecorder big(sys, 0);
  const Stream small = Generate(2, 100, mass, {}, 3);
  Feed(big, small, 0, 100);
  EXPECT_EQ(big.bucket_periods(), 1);
  EXPECT_LE(big.stored_rows(), 128u);
}

}  // namespace
}  // namespace vibro::test
