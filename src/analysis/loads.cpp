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

}  // namespace

LoadsRecorder::LoadsRecorder(const System& system, long long skip) : period_(system.period()), skip_(skip) {
  for (const ContactModel& c : system.contacts()) {
    mass_.push_back(1.0 / c.s_B);
    restitution_.push_back(c.restitution);
  }
  rows_.resize(mass_.size());
  open_reaction_.assign(mass_.size(), 0.0);
  open_held_.assign(mass_.size(), 0.0);
}

LoadsRecorder::Row& LoadsRecorder::At(int contact, long long period) {
  if (first_ < 0) first_ = period;
  if (period < first_) period = first_;  // never: events come in time order
  const auto k = static_cast<size_t>(period - first_);
  for (auto& r : rows_)
    if (r.size() <= k) r.resize(k + 1);
  last_ = std::max(last_, period + 1);
  return rows_[static_cast<size_t>(contact)][k];
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
    for (size_t j = 0; j < rows_.size() && j < cp.reaction_integral.size(); ++j) {
      const bool open = std::isfinite(cp.reaction_integral[j]);
      open_reaction_[j] = open ? cp.reaction_integral[j] : 0;
      open_held_[j] = open ? cp.stick_duration[j] : 0;
    }
    return;
  }
  // A period boundary: the part of each open phase since the last account goes to the period
  // that ends here.
  if (cp.clock.period <= first_) return;
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
}

LoadsSummary LoadsRecorder::Summary(int blocks) const {
  LoadsSummary s;
  s.blocks = blocks;
  if (first_ < 0 || last_ <= first_) {
    s.note = "no complete period recorded";
    return s;
  }
  const long long begin = std::min(first_ + skip_, last_);
  s.first_period = begin;
  s.periods = last_ - begin;
  const long long L = blocks >= 2 ? s.periods / blocks : 0;
  if (blocks == 0)
    s.note = "";
  else if (blocks < 2)
    s.note = "no interval: --blocks must be at least 2";
  else if (L < kMinBlockPeriods)
    s.note = fmt::format("run too short for the interval: {} periods analysed, {} blocks need at least {}",
                         s.periods, blocks, kMinBlockPeriods * blocks);
  else
    s.block_periods = L;
  // With an interval, the means are those of the blocks' window: the last blocks·L periods (the
  // first periods % blocks of the window are left out: the end of a run is the most settled).
  if (s.block_periods > 0) {
    s.first_period = last_ - L * blocks;
    s.periods = L * blocks;
  }
  for (size_t j = 0; j < rows_.size(); ++j) {
    const auto& rows = rows_[j];
    const auto row = [&](long long p) {
      const auto k = static_cast<size_t>(p - first_);
      return k < rows.size() ? rows[k] : Row{};
    };
    // The seven quantities of a window [a, b) of periods.
    const auto means = [&](long long a, long long b) {
      Row sum;
      for (long long p = a; p < b; ++p) {
        const Row r = row(p);
        sum.partial = sum.partial || r.partial;
        sum.impacts += r.impacts;
        sum.impulse += r.impulse;
        sum.reaction += r.reaction;
        sum.energy += r.energy;
        sum.work += r.work;
        sum.held += r.held;
      }
      const double n = static_cast<double>(b - a), t = n * period_;
      const double unknown = std::numeric_limits<double>::quiet_NaN();
      return std::array<double, 7>{sum.impacts / n, sum.impulse / n, sum.partial ? unknown : sum.reaction / n,
                                   sum.partial ? unknown : (sum.impulse + sum.reaction) / t,
                                   sum.energy / t, sum.work / t, sum.partial ? unknown : sum.held / t};
    };
    ContactLoads c;
    c.contact = static_cast<int>(j);
    if (s.periods > 0) {
      const auto m = means(s.first_period, last_);
      c.impacts_per_period = m[0];
      c.impulse_per_period = m[1];
      c.reaction_integral_per_period = m[2];
      c.mean_force = m[3];
      c.dissipated_power = m[4];
      c.work_rate = m[5];
      c.contact_fraction = m[6];
    }
    if (s.block_periods > 0) {
      const long long start = s.first_period;
      std::vector<std::array<double, 7>> b;
      for (int i = 0; i < blocks; ++i) b.push_back(means(start + i * L, start + (i + 1) * L));
      const double t = StudentT975(blocks - 1);
      ContactLoads::Interval* ci[7] = {&c.impacts_per_period_ci, &c.impulse_per_period_ci,
                                       &c.reaction_integral_per_period_ci, &c.mean_force_ci,
                                       &c.dissipated_power_ci, &c.work_rate_ci, &c.contact_fraction_ci};
      double* point[7] = {&c.impacts_per_period, &c.impulse_per_period, &c.reaction_integral_per_period,
                          &c.mean_force, &c.dissipated_power, &c.work_rate, &c.contact_fraction};
      for (int q = 0; q < 7; ++q) {
        double mean = 0, var = 0;
        for (const auto& x : b) mean += x[static_cast<size_t>(q)];
        mean /= blocks;
        for (const auto& x : b) var += (x[static_cast<size_t>(q)] - mean) * (x[static_cast<size_t>(q)] - mean);
        var /= blocks - 1;
        // At least the rounding of the sums (a settled periodic run has equal block means).
        const double half = std::max(t * std::sqrt(var / blocks),
                                     16 * std::numeric_limits<double>::epsilon() * static_cast<double>(L) * std::abs(mean));
        if (std::isfinite(mean)) *ci[q] = std::pair{mean - half, mean + half};
        *point[q] = mean;  // the mean of equal blocks: the mean over the window
      }
    }
    if (!std::isfinite(c.mean_force))
      s.note += fmt::format("{}contact {}: phases held together with other contacts are not accounted "
                            "(docs/loads.md): its reaction integral, mean force and contact fraction "
                            "are unknown", s.note.empty() ? "" : "; ", j);
    s.contacts.push_back(c);
  }
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
