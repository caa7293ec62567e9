// A brute-force sweep in the store (docs/output.md, /sweep): one row per run, in the order run.
#include <algorithm>
#include <limits>

#include "io/hdf5_store_impl.hpp"

namespace vibro {

void Hdf5Store::WriteSweep(const std::vector<SweepPoint>& sweep, const SweepSpec& spec) {
  impl_->Sync();
  const h5::Handle g = h5::CreateGroup(impl_->file.get(), "/sweep");
  const h5::Size n = sweep.size(), rec = static_cast<h5::Size>(std::max(spec.record, 1));
  std::vector<double> value, sp, xB(n * rec, std::numeric_limits<double>::quiet_NaN()), vB = xB;
  std::vector<std::uint8_t> up;
  std::vector<std::int32_t> period;
  std::vector<std::int64_t> impacts;
  std::vector<std::string> kind;
  std::vector<double> lyap, lyap_lo, lyap_hi;
  std::vector<std::int8_t> chaotic;
  for (h5::Size i = 0; i < n; ++i) {
    const SweepPoint& p = sweep[i];
    const store::LyapunovColumns c = store::LyapunovRow(p.lyapunov);
    lyap.push_back(c.largest);
    lyap_lo.push_back(c.low);
    lyap_hi.push_back(c.high);
    chaotic.push_back(c.chaotic);
    value.push_back(p.value);
    up.push_back(p.upward ? 1 : 0);
    kind.push_back(p.attractor.kind);
    period.push_back(p.attractor.period.value_or(-1));
    impacts.push_back(p.attractor.impacts_per_period.value_or(-1));
    sp.push_back(p.attractor.sticking_fraction.value_or(std::numeric_limits<double>::quiet_NaN()));
    // The last `record` section points, the most recent last (rows of shorter runs NaN-padded in front).
    const h5::Size k = std::min<h5::Size>(p.x_B.size(), rec);
    for (h5::Size j = 0; j < k; ++j) {
      xB[i * rec + rec - k + j] = p.x_B[p.x_B.size() - k + j];
      vB[i * rec + rec - k + j] = p.v_B[p.v_B.size() - k + j];
    }
  }
  const h5::Id gg = g.get();
  h5::WriteDataset(gg, "value", h5::Type::F64(), value.data(), {n});
  h5::WriteDataset(gg, "upward", h5::Type::U8(), up.data(), {n});
  h5::WriteStrings(gg, "kind", kind);
  h5::WriteDataset(gg, "period", h5::Type::I32(), period.data(), {n});
  h5::WriteDataset(gg, "impacts_per_period", h5::Type::I64(), impacts.data(), {n});
  h5::WriteDataset(gg, "sticking_fraction", h5::Type::F64(), sp.data(), {n});
  h5::WriteDataset(gg, "lyapunov_max", h5::Type::F64(), lyap.data(), {n});
  h5::WriteDataset(gg, "lyapunov_max_ci_low", h5::Type::F64(), lyap_lo.data(), {n});
  h5::WriteDataset(gg, "lyapunov_max_ci_high", h5::Type::F64(), lyap_hi.data(), {n});
  h5::WriteDataset(gg, "chaotic", h5::Type::I8(), chaotic.data(), {n});
  h5::WriteDataset(gg, "x_B", h5::Type::F64(), xB.data(), {n, rec});
  h5::WriteDataset(gg, "v_B", h5::Type::F64(), vB.data(), {n, rec});
  h5::WriteString(gg, "param", spec.param);
  h5::WriteDouble(gg, "from", spec.from);
  h5::WriteDouble(gg, "to", spec.to);
  h5::WriteInt(gg, "steps", spec.steps);
  h5::WriteInt(gg, "record", spec.record);
  h5::WriteInt(gg, "both_ways", spec.both_ways ? 1 : 0);
}

}  // namespace vibro
