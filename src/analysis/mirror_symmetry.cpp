// The mirror symmetry of a model (see mirror_symmetry.hpp).
#include "analysis/mirror_symmetry.hpp"

#include <algorithm>
#include <cmath>

namespace vibro {

std::optional<std::vector<int>> MirrorImage(const System& sys) {
  for (const Harmonic& h : sys.harmonics())
    if (h.amplitude != 0 && h.multiple % 2 == 0) return std::nullopt;
  const auto& contacts = sys.contacts();
  const int m = static_cast<int>(contacts.size());
  if (m < 2) return std::nullopt;
  const auto close = [](double a, double b) { return std::abs(a - b) <= 1e-12 * std::max({1.0, std::abs(a), std::abs(b)}); };
  const auto mirrored = [&](const ContactModel& a, const ContactModel& b) {
    if (a.shape.size() != b.shape.size() || !close(a.stop, b.stop) || a.restitution != b.restitution ||
        a.spec.compliance.stiffness != b.spec.compliance.stiffness ||
        a.spec.compliance.damping != b.spec.compliance.damping ||
        a.spec.compliance.separation != b.spec.compliance.separation)
      return false;
    const double scale = std::max(a.shape.cwiseAbs().maxCoeff(), b.shape.cwiseAbs().maxCoeff());
    return scale > 0 && (a.shape + b.shape).cwiseAbs().maxCoeff() <= 1e-12 * scale;
  };
  std::vector<int> image(static_cast<size_t>(m), -1);
  for (int j = 0; j < m; ++j) {
    if (image[static_cast<size_t>(j)] >= 0) continue;
    for (int k = j + 1; k < m && image[static_cast<size_t>(j)] < 0; ++k)
      if (image[static_cast<size_t>(k)] < 0 && mirrored(contacts[static_cast<size_t>(j)], contacts[static_cast<size_t>(k)])) {
        image[static_cast<size_t>(j)] = k;
        image[static_cast<size_t>(k)] = j;
      }
    if (image[static_cast<size_t>(j)] < 0) return std::nullopt;
  }
  return image;
}

}  // namespace vibro
