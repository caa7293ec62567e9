// Plain-text renderings of results for the `vibro` command's terminal output (not --json).
#pragma once

#include <complex>
#include <optional>
#include <string>
#include <vector>

#include "vibro/attractor.hpp"
#include "vibro/lyapunov.hpp"

namespace vibro::cli {

// x, or 0 when x is within rounding of zero for a quantity of size `scale`: |x| ≤ 64 ε·scale.
// `scale` is the size of what x was computed from (the terms of a sum, the entries of a matrix
// whose eigenvalue x is), not of x itself: a sum of O(1) terms that cancels leaves O(ε) residue.
double SnapZero(double x, double scale);

// Floquet multipliers, conjugate pairs folded into one "a ± bi (|μ| = m)" entry. An imaginary
// part within rounding of zero (|Im μ| ≤ 1e-12·max(1, |μ|)) is printed as a real multiplier.
// Real and imaginary parts and moduli within rounding of zero print as 0 (SnapZero with the
// scale max(1, largest |μ|): eigenvalues of the monodromy matrix are accurate to about ε times its
// norm, which is at least its largest |μ|, and 1 for the O(1) entries of a contracting map).
std::string FormatMultipliers(const std::vector<std::complex<double>>& multipliers, int digits = 6);

// The attractor lines of `simulate`, `orbit` and the studies: kind, period, impacts per orbit
// period, sticking fraction, stick phases, and for impact orbits each impact's phase with the
// contact velocity before and after it (after = −r·before, the impact law, docs/model.md §3;
// restitution NaN: not printed). `named`: each stick phase and impact names its contact (scenes
// with [[contact]] tables; the velocity is then the contact's gap velocity ġ_j).
std::string AttractorText(const Attractor& attractor, double restitution, const std::string& indent = "",
                          bool named = false);

// The line "lyapunov     λ1 ± h1, ... per unit time (N periods)[: chaotic]" of `simulate` and the
// studies (−inf for a direction collapsed by sticking; "none: why" without exponents).
std::string LyapunovText(const LyapunovSpectrum& spectrum, const std::string& indent = "");

// The largest exponent as a table cell: "λ1" (a sweep's column), "-inf", or "-" without exponents.
std::string LargestExponentCell(const std::optional<LyapunovSpectrum>& spectrum);

}  // namespace vibro::cli
