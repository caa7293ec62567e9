// Per-contact loads of a run and their batch-means intervals (docs/loads.md).
#include "vibro/loads.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "vibro/simulator.hpp"

namespace vibro {

namespace {

// Two-sided 95 % quantile of Student's t with df degrees of freedom.
double StudentT975(long long df) {
  static const double table[] = {12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228,
                                 2.201,  2.179, 2.160, 2.145, 2.131, 2.120, 2.110, 2.101, 2.093, 2.086,
                                 2.080,  2.074, 2.069, 2.064, 2.060, 2.056, 2.052, 2.048, 2.045, 2.042};
  if (df >= 1 && df <= 30) return table[df - 1];
  // Beyond the table: the Cornish-Fisher expansion about the normal quantile (error < 1e-3).
  const double z = 1.959964, d = static_cast<double>(df);
  return z + (z * z * z + z) / (4 * d) + (5 * std::pow(z, 5) + 16 * z * z * z + 3 * z) / (96 * d * d);
}

// The quantities of a sum of n periods of one contact (docs/loads.md §5): the seven loads, then a
// compliant stop's contact phases per period and, per phase, the mean peak force and mean duration
// (ratio estimators: Σ over the phases / their number, NaN when there is none; docs/loads.md,
// "Peak force and contact duration over a run").
constexpr size_t kQuantities = 10;
std::array<double, kQuantities> Quantities(const LoadsRecorder::Row& sum, double n, double period) {
  const double t = n * period;
  const double unknown = std::numeric_limits<double>::quiet_NaN();
  const bool phases = sum.phases > 0;  // false for 0 and for NaN (not known)
  return std::array<double, kQuantities>{sum.impacts / n, sum.impulse / n, sum.partial ? unknown : sum.reaction / n,
                                         sum.partial ? unknown : (sum.impulse + sum.reaction) / t,
                                         sum.energy / t, sum.work / t, sum.partial ? unknown : sum.held / t,
                                         sum.phases / n, phases ? sum.peak_sum / sum.phases : unknown,
                                         phases ? sum.duration_sum / sum.phases : unknown};
}

void Add(LoadsRecorder::Row& sum, const LoadsRecorder::Row& r) {
  sum.partial = sum.partial || r.partial;
  sum.impacts += r.impacts;
  sum.impulse += r.impulse;
  sum.reaction += r.reaction;
  sum.energy += r.energy;
  sum.work += r.work;
  sum.held += r.held;
  sum.phases += r.phases;
  sum.peak_sum += r.peak_sum;
  sum.duration_sum += r.duration_sum;
  // The largest peak: NaN (not known) wins, as in the sums.
  sum.peak_max = std::isnan(sum.peak_max) || std::isnan(r.peak_max) ? std::numeric_limits<double>::quiet_NaN()
                                                                    : std::max(sum.peak_max, r.peak_max);
}

long long PowerOfTwoAtLeast(long long n) {
  long long p = 32;
  while (p < n) p *= 2;
  return p;
}

}  // namespace

LoadsRecorder::LoadsRecorder(const System& system, long long skip, long long bucket_cap)
    : period_(system.period()), skip_(skip), cap_(PowerOfTwoAtLeast(bucket_cap)), head_periods_(cap_ / 16) {
  for (const ContactModel& c : system.contacts()) {
    mass_.push_back(1.0 / c.s_B);
    restitution_.push_back(c.restitution);
    compliant_.push_back(c.spec.compliance.compliant());
  }
  rows_.resize(mass_.size());
  head_.resize(mass_.size());
  rest_.resize(mass_.size());
  open_reaction_.assign(mass_.size(), 0.0);
  open_held_.assign(mass_.size(), 0.0);
}

size_t LoadsRecorder::stored_rows() const {
  size_t most = 0;
  for (size_t j = 0; j < rows_.size(); ++j) most = std::max(most, rows_[j].capacity() + head_[j].capacity());
  return most;
}

void LoadsRecorder::Merge() {
  for (size_t j = 0; j < rows_.size(); ++j) {
    auto& r = rows_[j];
    // The first merge: the head's periods are kept one by one (the means' window may start
    // inside it, docs/loads.md §5).
    if (bucket_ == 1) head_[j].assign(r.begin(), r.begin() + std::min<long long>(head_periods_, static_cast<long long>(r.size())));
    // Bucket 0 grows past the head: what it holds beyond the head is kept apart too.
    if (2 * bucket_ > head_periods_) {
      const Row next = r.size() > 1 ? r[1] : Row{};
      if (bucket_ > head_periods_) {
        Add(rest_[j], next);
      } else {
        rest_[j] = next;
      }
    }
    const size_t m = (r.size() + 1) / 2;
    for (size_t i = 0; i < m; ++i) {
      Row x = r[2 * i];
      if (2 * i + 1 < r.size()) Add(x, r[2 * i + 1]);
      r[i] = x;
    }
    r.resize(m);
  }
  bucket_ *= 2;
}

LoadsRecorder::Row& LoadsRecorder::At(int contact, long long period) {
  if (first_ < 0) first_ = period;
  if (open_period_ < 0) {
    open_period_ = first_;
    open_.assign(rows_.size(), Row{});
  }
  if (period < open_period_) period = open_period_;  // never: events come in time order
  while (open_period_ < period) ClosePeriod();
  last_ = std::max(last_, period + 1);
  return open_[static_cast<size_t>(contact)];
}

void LoadsRecorder::ClosePeriod() {
  const long long period = open_period_;
  if (sink_) sink_->OnPeriodLoads(period, open_);
  const long long begin = Begin();
  if (period >= begin) {  // analysed: added to its bucket (the periods before begin are not kept)
    auto k = (period - begin) / bucket_;
    while (k >= cap_) {
      Merge();
      k = (period - begin) / bucket_;
    }
    for (size_t j = 0; j < rows_.size(); ++j) {
      auto& r = rows_[j];
      if (static_cast<long long>(r.size()) <= k) r.resize(static_cast<size_t>(k) + 1);
      Add(r[static_cast<size_t>(k)], open_[j]);
    }
  }
  std::fill(open_.begin(), open_.end(), Row{});
  ++open_period_;
}

void LoadsRecorder::Resumed(long long run_first, long long known_from, const Checkpoint& cp) {
  first_ = run_first;
  known_from_ = std::max(run_first, known_from);
  open_period_ = known_from_;
  last_ = known_from_;
  open_.assign(rows_.size(), Row{});
  // The parts of the phases open at the checkpoint that its period boundary counted already.
  for (size_t j = 0; j < rows_.size(); ++j) {
    const bool open = j < cp.reaction_integral.size() && std::isfinite(cp.reaction_integral[j]);
    open_reaction_[j] = open ? cp.reaction_integral[j] : 0;
    open_held_[j] = open && j < cp.stick_duration.size() ? cp.stick_duration[j] : 0;
  }
}

void LoadsRecorder::ReplayPeriod(const std::vector<Row>& rows) {
  for (size_t j = 0; j < open_.size() && j < rows.size(); ++j) open_[j] = rows[j];
  LoadsSink* sink = sink_;
  sink_ = nullptr;  // the store has them
  ClosePeriod();
  sink_ = sink;
  last_ = open_period_;
}

void LoadsRecorder::OnEvent(const Event& e) {
  if (e.contact < 0 || static_cast<size_t>(e.contact) >= rows_.size()) return;
  const auto j = static_cast<size_t>(e.contact);
  Row& row = At(e.contact, e.clock.period);
  switch (e.kind) {
    case EventKind::kImpact:
      row.impacts += 1;
      row.impulse += e.impulse;
      row.energy += e.energy_dissipated;
      // Normal work in the rigid limit: ½ m (v⁻² + v⁺²) (docs/loads.md §4).
      row.work += 0.5 * mass_[j] * (e.v_before * e.v_before + e.v_after * e.v_after);
      break;
    case EventKind::kAccumulation: {
      // The tail arrives at u, r u, r² u, …: Σ ½ m (1 + r²) r²ⁿ u² = E_tail (1 + r²)/(1 − r²).
      const double r = restitution_[j];
      row.impulse += e.impulse;
      row.energy += e.energy_dissipated;
      row.work += e.energy_dissipated * (1 + r * r) / (1 - r * r);
      break;
    }
    case EventKind::kStick:
      open_reaction_[j] = open_held_[j] = 0;
      break;
    case EventKind::kRelease:
      if (!std::isfinite(e.reaction_integral)) row.partial = true;  // held with other contacts
      if (std::isfinite(e.reaction_integral)) row.reaction += e.reaction_integral - open_reaction_[j];
      if (std::isfinite(e.stick_duration)) row.held += e.stick_duration - open_held_[j];
      // A compliant stop's contact phase (docs/compliant.md): the energy its dashpot took, and the
      // phase's certified peak force and duration, counted in the period of its release
      // (docs/loads.md, "Peak force and contact duration over a run").
      if (std::isfinite(e.peak_time)) {
        if (std::isfinite(e.energy_dissipated)) row.energy += e.energy_dissipated;
        row.phases += 1;
        row.peak_sum += e.reaction_max;
        row.duration_sum += e.stick_duration;
        row.peak_max = std::isnan(row.peak_max) || std::isnan(e.reaction_max) ? std::numeric_limits<double>::quiet_NaN()
                                                                               : std::max(row.peak_max, e.reaction_max);
      }
      open_reaction_[j] = open_held_[j] = 0;
      break;
    case EventKind::kGrazing: break;
  }
}

void LoadsRecorder::OnCheckpoint(const Checkpoint& cp) {
  if (first_ < 0) {
    // The first checkpoint of a run (its start, or the resumed one): phases open there began
    // before what this recorder sees, and are counted from here on.
    first_ = cp.clock.period;
    last_ = first_;
    open_period_ = first_;
    open_.assign(rows_.size(), Row{});
    for (size_t j = 0; j < rows_.size() && j < cp.reaction_integral.size(); ++j) {
      const bool open = std::isfinite(cp.reaction_integral[j]);
      open_reaction_[j] = open ? cp.reaction_integral[j] : 0;
      open_held_[j] = open ? cp.stick_duration[j] : 0;
    }
    return;
  }
  // A period boundary: the part of each open phase since the last account goes to the period
  // that ends here, and that period is closed.
  if (cp.clock.period <= std::max(first_, open_period_)) return;
  const long long ended = cp.clock.period - 1;
  // Held with other contacts, without an account (SimulationOptions::loads off): unknown.
  for (const int j : cp.held)
    if (static_cast<size_t>(j) >= cp.reaction_integral.size() || !std::isfinite(cp.reaction_integral[static_cast<size_t>(j)]))
      At(j, ended).partial = true;
  for (size_t j = 0; j < rows_.size(); ++j) {
    Row& row = At(static_cast<int>(j), ended);
    if (j < cp.reaction_integral.size() && std::isfinite(cp.reaction_integral[j])) {
      row.reaction += cp.reaction_integral[j] - open_reaction_[j];
      row.held += cp.stick_duration[j] - open_held_[j];
      open_reaction_[j] = cp.reaction_integral[j];
      open_held_[j] = cp.stick_duration[j];
    }
  }
  last_ = std::max(last_, cp.clock.period);
  while (open_period_ < cp.clock.period) ClosePeriod();
}

LoadsSummary LoadsRecorder::Summary(int blocks) const {
  // A run stopped inside a period: that period's sums so far count as its own (closed in a copy).
  if (open_period_ >= 0 && open_period_ < last_) {
    LoadsRecorder closed(*this);
    closed.sink_ = nullptr;
    while (closed.open_period_ < closed.last_) closed.ClosePeriod();
    return closed.SummaryOfClosed(blocks);
  }
  return SummaryOfClosed(blocks);
}

LoadsSummary LoadsRecorder::SummaryOfClosed(int blocks) const {
  LoadsSummary s;
  s.blocks = blocks;
  if (first_ < 0 || last_ <= std::max(first_, known_from_)) {
    s.note = "no complete period recorded";
    return s;
  }
  const long long begin = std::min(Begin(), last_);
  s.known_from = std::max(first_, known_from_);
  s.whole_run = known_from_ <= first_ + skip_;
  s.first_period = begin;
  s.periods = last_ - begin;
  const long long n = s.periods;
  const bool merged = bucket_ > 1;
  // Once merged, a block is a whole number of buckets (the last, partial bucket is in no block).
  const long long whole = n / bucket_;
  const long long L = blocks < 2 ? 0 : merged ? whole / blocks * bucket_ : n / blocks;
  if (blocks == 0)
    s.note = "";
  else if (blocks < 2)
    s.note = "no interval: --blocks must be at least 2";
  else if (merged && L == 0)
    s.note = fmt::format("too many blocks for the interval: {} periods analysed are kept as {} buckets of {} "
                         "periods (docs/loads.md §5), {} blocks need at least {} buckets",
                         n, whole, bucket_, blocks, blocks);
  else if (L < kMinBlockPeriods)
    s.note = fmt::format("run too short for the interval: {} periods analysed, {} blocks need at least {}",
                         s.periods, blocks, kMinBlockPeriods * blocks);
  else
    s.block_periods = L;
  // With an interval, the means are those of the last blocks·⌊periods/blocks⌋ periods (the first
  // periods % blocks of the window are left out: the end of a run is the most settled). Once
  // merged this holds while periods % blocks < the head kept period by period; beyond, the means
  // are those of the blocks.
  const long long cut = blocks >= 2 ? n % blocks : 0;
  const bool means_of_blocks = merged && s.block_periods > 0 && cut >= head_periods_;
  if (s.block_periods > 0) {
    const long long span = merged ? (means_of_blocks ? L * blocks : n - cut) : L * blocks;
    s.first_period = merged && means_of_blocks ? begin + whole * bucket_ - span : last_ - span;
    s.periods = span;
  }
  for (size_t j = 0; j < rows_.size(); ++j) {
    const auto& rows = rows_[j];
    // Row k of the window: period begin + k, or (merged) bucket k.
    const auto row = [&](long long k) {
      return k >= 0 && k < static_cast<long long>(rows.size()) ? rows[static_cast<size_t>(k)] : Row{};
    };
    // The sums of the rows [a, b) (periods, or buckets once merged) of the window, and their quantities.
    const auto sum_of = [&](long long a, long long b) {
      Row sum;
      for (long long k = a; k < b; ++k) Add(sum, row(k));
      return sum;
    };
    const auto means = [&](long long a, long long b) {
      return Quantities(sum_of(a, b), static_cast<double>((b - a) * bucket_), period_);
    };
    ContactLoads c;
    c.contact = static_cast<int>(j);
    c.compliant = compliant_[j];
    std::array<double, kQuantities> m{};
    double* point[kQuantities] = {&c.impacts_per_period, &c.impulse_per_period, &c.reaction_integral_per_period,
                                  &c.mean_force,         &c.dissipated_power,   &c.work_rate,
                                  &c.contact_fraction,   &c.phases_per_period,  &c.peak_force_mean,
                                  &c.contact_duration_mean};
    if (s.periods > 0) {
      Row sum;
      if (!merged || means_of_blocks) {
        sum = sum_of((s.first_period - begin) / bucket_, (s.first_period - begin + s.periods + bucket_ - 1) / bucket_);
      } else {
        // Merged: from period s.first_period on, one by one through the head, then the buckets
        // beyond it (the part of bucket 0 beyond the head kept apart once bucket 0 is longer).
        const long long from = s.first_period - begin;
        const auto& head = head_[j];
        for (long long k = from; k < head_periods_; ++k)
          if (k < static_cast<long long>(head.size())) Add(sum, head[static_cast<size_t>(k)]);
        long long k0 = head_periods_ / bucket_;
        if (bucket_ > head_periods_) {
          Add(sum, rest_[j]);
          k0 = 1;
        }
        for (long long k = k0; k < static_cast<long long>(rows.size()); ++k) Add(sum, rows[static_cast<size_t>(k)]);
      }
      m = Quantities(sum, static_cast<double>(s.periods), period_);
      for (size_t q = 0; q < kQuantities; ++q) *point[q] = m[q];
      c.peak_force_max = sum.phases > 0 ? sum.peak_max : std::numeric_limits<double>::quiet_NaN();
    }
    if (s.block_periods > 0) {
      // The blocks: the last blocks·L periods (merged: of the whole buckets).
      const long long per = L / bucket_, start = merged ? whole - per * blocks : (s.first_period - begin);
      std::vector<std::array<double, kQuantities>> b;
      for (int i = 0; i < blocks; ++i) b.push_back(means(start + i * per, start + (i + 1) * per));
      const double t = StudentT975(blocks - 1);
      ContactLoads::Interval* ci[kQuantities] = {
          &c.impacts_per_period_ci, &c.impulse_per_period_ci, &c.reaction_integral_per_period_ci,
          &c.mean_force_ci,         &c.dissipated_power_ci,   &c.work_rate_ci,
          &c.contact_fraction_ci,   &c.phases_per_period_ci,  &c.peak_force_mean_ci,
          &c.contact_duration_mean_ci};
      for (size_t q = 0; q < kQuantities; ++q) {
        double mean = 0, var = 0;
        for (const auto& x : b) mean += x[q];
        mean /= blocks;
        for (const auto& x : b) var += (x[q] - mean) * (x[q] - mean);
        var /= blocks - 1;
        // At least the rounding of the sums (a settled periodic run has equal block means).
        const double half = std::max(t * std::sqrt(var / blocks),
                                     16 * std::numeric_limits<double>::epsilon() * static_cast<double>(L) * std::abs(mean));
        // Merged, the means' window may differ from the blocks' by a few periods at its ends: the
        // interval is centred on the mean reported. The per-phase means (ratio estimators) are
        // centred on the window's ratio Σ/Σ phases, not on the mean of the block ratios (which
        // differs from it by O(1/L) when the blocks hold different numbers of phases).
        const bool ratio = q >= 8;
        const double centre = (merged && !means_of_blocks) || ratio ? *point[q] : mean;
        if (std::isfinite(mean) && std::isfinite(centre)) *ci[q] = std::pair{centre - half, centre + half};
        *point[q] = centre;  // the mean of equal blocks: the mean over the window
      }
    }
    if (c.compliant) {  // no impacts: the rigid-limit normal work of §4 does not apply (not a zero)
      c.work_rate = std::numeric_limits<double>::quiet_NaN();
      c.work_rate_ci.reset();
    }
    if (!std::isfinite(c.mean_force))
      s.note += fmt::format("{}contact {}: phases held together with other contacts are not accounted "
                            "(docs/loads.md): its reaction integral, mean force and contact fraction "
                            "are unknown", s.note.empty() ? "" : "; ", j);
    s.contacts.push_back(c);
  }
  if (!s.whole_run)
    s.coverage = fmt::format("the periods before {} are not known (the run was resumed or extended from a file "
                             "that does not hold its per-period loads, docs/loads.md §5): the loads cover "
                             "periods {}..{} only, not the window from period {} of the whole run",
                             known_from_, s.first_period, s.first_period + s.periods, first_ + skip_);
  return s;
}

LoadsSummary OrbitLoads(const System& system, const Scene& scene, const OrbitResult& orbit) {
  LoadsSummary none;
  if (orbit.status != "converged" || orbit.period < 1) {
    none.note = "no converged orbit";
    return none;
  }
  Scene one = scene;
  one.run.periods = orbit.period;
  one.run.samples_per_period = 0;
  one.run.lyapunov = false;
  const InitialOverride start{orbit.section_time, orbit.X, orbit.V};
  for (int attempt = 0; attempt < 2; ++attempt) {
    if (attempt == 1) {
      if (one.run.precision == Precision::kQuad || one.run.engine != Engine::kExact) break;
      one.run.precision = Precision::kQuad;
    } else if (orbit.quad_evaluations > 0 && one.run.engine == Engine::kExact) {
      one.run.precision = Precision::kQuad;
    }
    LoadsRecorder recorder(system, 0);
    SimulationOptions opt;
    opt.observers = {&recorder};
    opt.initial = &start;
    const RunResult r = Simulate(system, one, opt);
    if (r.status == RunStatus::kOk) return recorder.Summary(0);
  }
  none.note = "one period of the orbit could not be simulated";
  return none;
}

}  // namespace vibro
