// What the contacts endure over a run, per contact (docs/loads.md): impact rate, impulse and
// reaction integral per period, mean contact force, dissipated power, normal work rate (rigid
// limit) and contact time fraction, each with a confidence interval from batch means over blocks
// of periods.
#pragma once

#include <algorithm>
#include <cstddef>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "vibro/observer.hpp"
#include "vibro/poincare.hpp"
#include "vibro/scene.hpp"
#include "vibro/system.hpp"

namespace vibro {

// One contact's means over the periods analysed. Per period: impacts, impulse (impacts and summed
// chattering tails), ∫R dt (sticking phases, impulsive reactions while held included); per unit
// time: mean_force = (Σ impulses + Σ ∫R dt)/time, dissipated_power, work_rate
// (Σ ½ m (v⁻² + v⁺²)/time, the normal work of the impacts in the rigid limit, docs/loads.md §4),
// contact_fraction (time held / time).
struct ContactLoads {
  int contact = 0;
  double impacts_per_period = 0, impulse_per_period = 0, reaction_integral_per_period = 0,
         mean_force = 0, dissipated_power = 0, work_rate = 0, contact_fraction = 0;
  // 95 % intervals (Student t over the block means); absent when the run is too short.
  using Interval = std::optional<std::pair<double, double>>;
  Interval impacts_per_period_ci, impulse_per_period_ci, reaction_integral_per_period_ci,
      mean_force_ci, dissipated_power_ci, work_rate_ci, contact_fraction_ci;
  // A compliant stop (docs/compliant.md; docs/loads.md, "Peak force and contact duration over a
  // run"): its contact phases per period, and per contact phase the mean certified peak force and
  // the mean duration, each the ratio estimator Σ/Σ phases over the window (intervals from the
  // block ratios), and the largest certified peak force of the window's phases. NaN when the
  // window holds no phase (or a replayed period does not know its phases). A rigid contact:
  // compliant false, the impacts, impulse and work rate (rigid limit) are its loads.
  bool compliant = false;
  double phases_per_period = 0, peak_force_mean = 0, contact_duration_mean = 0, peak_force_max = 0;
  Interval phases_per_period_ci, peak_force_mean_ci, contact_duration_mean_ci;
};

struct LoadsSummary {
  std::vector<ContactLoads> contacts;
  long long first_period = 0, periods = 0;  // the window analysed: [first, first + periods)
  int blocks = 0;                           // blocks asked for
  long long block_periods = 0;              // periods per block (0: no interval)
  std::string note;                         // why there is no interval, when there is none
  // False when the periods of the run before `known_from` are not known (a run resumed or
  // extended from a file that does not store them, docs/loads.md §5): the window is then cut to
  // the periods from known_from on, and `coverage` says so.
  bool whole_run = true;
  long long known_from = 0;
  std::string coverage;
};

// The sums of one contact over one period (or, in a LoadsRecorder's buckets, over several):
// impacts, impulse, ∫R dt, energy dissipated, normal work, time held.
struct LoadsRow {
  double impacts = 0, impulse = 0, reaction = 0, energy = 0, work = 0, held = 0;
  // A phase held together with other contacts touched this period without an account (a run
  // without loads, SimulationOptions::loads): its ∫R dt and duration are unknown, so are the
  // reaction, mean force and contact fraction (docs/loads.md).
  bool partial = false;
  // A compliant stop's contact phases ended this period (at their release event): their number, the
  // sums of their certified peak forces and of their durations, and the largest peak force (0 when
  // none). NaN: not known (a period replayed from a file written before these sums were stored).
  double phases = 0, peak_sum = 0, duration_sum = 0, peak_max = 0;
};

// Where a LoadsRecorder gives each period's rows (one per contact) once the period has ended:
// the store of a run (vibro/hdf5_store.hpp) keeps them, so that a resumed or extended run
// gives them back (LoadsRecorder::Resumed) and reports the loads of the whole run.
class LoadsSink {
 public:
  virtual ~LoadsSink() = default;
  virtual void OnPeriodLoads(long long period, const std::vector<LoadsRow>& rows) = 0;
};

// An observer of a run. The first `skip` periods of the run (a transient) are left out of the means.
// Memory is bounded whatever the run's length (docs/loads.md §5): the periods analysed are kept one
// row per period up to `bucket_cap` rows per contact; beyond, adjacent rows are merged pairwise
// (each row then sums 2, 4, 8, … periods) and the first bucket_cap/16 periods analysed are kept
// apart, one row each. `bucket_cap` is rounded up to a power of two, at least 32.
class LoadsRecorder final : public Observer {
 public:
  static constexpr long long kBucketCap = 1LL << 16;
  LoadsRecorder(const System& system, long long skip = 0, long long bucket_cap = kBucketCap);
  void OnEvent(const Event& e) override;
  void OnCheckpoint(const Checkpoint& cp) override;

  // Means over every period recorded after `skip`, and intervals from `blocks` batch means
  // (at least kMinBlockPeriods periods per block, blocks ≥ 2; 0: means only, no interval asked).
  // `blocks` 1 is refused with a note. Once rows are merged, blocks are whole buckets and the
  // interval is centred on the mean (docs/loads.md §5, "Long runs").
  LoadsSummary Summary(int blocks) const;
  static constexpr long long kMinBlockPeriods = 2;

  // Per-period sums of one contact (time in units of time; row k = period first + k).
  using Row = LoadsRow;

  // Every period's rows, once it has ended, go to `sink` too (nullptr: nowhere).
  void SetSink(LoadsSink* sink) { sink_ = sink; }
  // A run resumed at checkpoint `cp` (or extended from it), that began at period `run_first`:
  // the rows of the periods [known_from, cp.clock.period) follow through ReplayPeriod, one call
  // per period in order (they come from the run's store, not to the sink); the periods before
  // known_from are unknown (a store that did not keep them), and the window analysed starts
  // at known_from at the earliest (LoadsSummary::whole_run false when that cuts it). Call before
  // the run's first event.
  void Resumed(long long run_first, long long known_from, const Checkpoint& cp);
  void ReplayPeriod(const std::vector<Row>& rows);

  // Memory (for tests): periods per bucket (1 until the first merge) and rows held per contact
  // (buckets and the head kept apart), never more than bucket_cap + bucket_cap/16.
  long long bucket_periods() const { return bucket_; }
  size_t stored_rows() const;

 private:
  Row& At(int contact, long long period);
  void ClosePeriod();  // the open period's rows to the sink and into the buckets
  long long Begin() const { return std::max(first_ + skip_, known_from_); }
  LoadsSummary SummaryOfClosed(int blocks) const;
  void Merge();  // every contact's buckets pairwise: bucket_ doubles
  double period_;
  long long skip_, cap_, head_periods_;
  std::vector<double> mass_, restitution_;
  std::vector<bool> compliant_;
  // rows_[contact][k]: the sums of periods begin + [k·bucket_, (k + 1)·bucket_), begin = first_ + skip_
  // (the periods before begin are not analysed and not kept).
  std::vector<std::vector<Row>> rows_;
  long long bucket_ = 1;
  std::vector<std::vector<Row>> head_;  // [contact][period − begin] for the first head_periods_, once merged
  std::vector<Row> rest_;               // [contact]: periods begin + [head_periods_, bucket_), once bucket_ > head
  std::vector<Row> open_;               // [contact]: the sums of period open_period_ so far
  long long open_period_ = -1;          // the period being summed (the ones before are closed)
  LoadsSink* sink_ = nullptr;
  long long known_from_ = -1;           // the first period known (a resumed run: see Resumed)
  long long first_ = -1, last_ = -1;    // periods seen: [first_, last_)
  std::vector<double> open_reaction_, open_held_;  // open phases' parts already counted
};

// The exact per-period loads of a converged periodic orbit (docs/loads.md): one orbit period q·T
// simulated from its section point (in quad precision when the orbit needed it, or when double
// leaves a chattering sequence undetermined); means without intervals. Empty contacts and a note
// when the orbit did not converge or the period could not be simulated.
LoadsSummary OrbitLoads(const System& system, const Scene& scene, const OrbitResult& orbit);

}  // namespace vibro
