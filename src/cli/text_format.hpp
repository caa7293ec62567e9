// Plain-text renderings of results for the `vibro` command's terminal output (not --json).
#pragma once

#include <complex>
#include <string>
#include <vector>

#include "vibro/attractor.hpp"

namespace vibro::cli {

// Floquet multipliers, conjugate pairs folded into one "a ± bi (|μ| = m)" entry. An imaginary
// part within rounding of zero (|Im μ| ≤ 1e-12·max(1, |μ|)) is printed as a real multiplier.
std::string FormatMultipliers(const std::vector<std::complex<double>>& multipliers, int digits = 6);

// The attractor lines of `simulate`, `orbit` and the studies: kind, period, impacts per orbit
// period, sticking fraction, stick phases, and for impact orbits each impact's phase with the
// contact velocity before and after it (after = −r·before, the impact law, docs/model.md §3).
std::string AttractorText(const Attractor& attractor, double restitution, const std::string& indent = "");

}  // namespace vibro::cli
