// The contact phases of a continued branch's points, per contact (vibro/continuation.hpp,
// docs/compliant.md "Along a continued branch").
#include <algorithm>
#include <limits>

#include "vibro/continuation.hpp"

namespace vibro {

ContactPhaseExtremes ExtremesOf(const std::vector<OrbitResult::ContactPhase>& phases, int contacts) {
  const auto m = static_cast<size_t>(std::max(contacts, 0));
  ContactPhaseExtremes e;
  e.peak_force.assign(m, std::numeric_limits<double>::quiet_NaN());
  e.duration.assign(m, std::numeric_limits<double>::quiet_NaN());
  e.phases.assign(m, 0);
  for (const auto& p : phases) {
    if (p.contact < 0 || static_cast<size_t>(p.contact) >= m) continue;
    const auto j = static_cast<size_t>(p.contact);
    // fmax: a NaN start (no phase yet) gives way to the first phase's value.
    e.peak_force[j] = std::fmax(e.peak_force[j], p.peak_force);
    e.duration[j] = std::fmax(e.duration[j], p.duration);
    ++e.phases[j];
  }
  return e;
}

}  // namespace vibro
