#include "cli/text_format.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

namespace vibro::cli {

double SnapZero(double x, double scale) {
  return std::abs(x) <= 64 * std::numeric_limits<double>::epsilon() * std::abs(scale) ? 0.0 : x;
}

std::string FormatMultipliers(const std::vector<std::complex<double>>& raw, int digits) {
  double scale = 1.0;
  for (const auto& m : raw) scale = std::max(scale, std::abs(m));
  std::vector<std::complex<double>> multipliers;
  for (const auto& m : raw)
    multipliers.emplace_back(SnapZero(m.real(), scale) + 0.0, SnapZero(m.imag(), scale) + 0.0);  // + 0.0: no -0
  std::vector<bool> used(multipliers.size(), false);
  std::string out;
  const auto real_enough = [](std::complex<double> m) {
    return std::abs(m.imag()) <= 1e-12 * std::max(1.0, std::abs(m));
  };
  for (size_t i = 0; i < multipliers.size(); ++i) {
    if (used[i]) continue;
    used[i] = true;
    const auto m = multipliers[i];
    std::string item;
    if (real_enough(m)) {
      item = fmt::format("{:.{}g}", m.real(), digits);
    } else {
      // Its conjugate, if present, is folded into a ± pair.
      for (size_t j = i + 1; j < multipliers.size(); ++j)
        if (!used[j] && std::abs(multipliers[j] - std::conj(m)) <= 1e-9 * std::max(1.0, std::abs(m))) {
          used[j] = true;
          item = fmt::format("{:.{}g} ± {:.{}g}i", m.real(), digits, std::abs(m.imag()), digits);
          break;
        }
      if (item.empty())
        item = fmt::format("{:.{}g} {} {:.{}g}i", m.real(), digits, m.imag() < 0 ? '-' : '+',
                           std::abs(m.imag()), digits);
    }
    out += fmt::format("{}{} (|μ| = {:.{}g})", out.empty() ? "" : ", ", item, std::abs(m), digits);
  }
  return out;
}

std::string AttractorText(const Attractor& a, double restitution, const std::string& indent, bool named) {
  std::string s = fmt::format("{}attractor    {}", indent, a.kind);
  if (a.period) s += fmt::format(", period {}", *a.period);
  // Compliant stops (docs/compliant.md): contact phases, neither impacts nor sticking; impacts on
  // rigid contacts beside them are still counted.
  const bool contact = a.kind == "contact-periodic";
  if (contact)
    s += fmt::format(", {} contact phase{} per orbit period", a.stick_phases.size(), a.stick_phases.size() == 1 ? "" : "s");
  if (a.impacts_per_period && (!contact || *a.impacts_per_period > 0))
    s += fmt::format(", {} impact{} per orbit period", *a.impacts_per_period,
                     *a.impacts_per_period == 1 ? "" : "s");
  if (a.searched_period)
    s += *a.searched_period > 0 ? fmt::format(" (no period ≤ {}, run.max_period)", *a.searched_period)
                                : std::string(" (too short a record to search a period)");
  if (a.sticking_fraction)
    s += fmt::format(", {} fraction {:.6f}", contact || a.contact_fraction ? "contact" : "sticking", *a.sticking_fraction);
  s += "\n";
  if (a.recurrence_period)
    s += fmt::format("{}recurrence   the section repeats with period {} (to {:.1e}): rerun with "
                     "--set run.max_period={} to classify it\n",
                     indent, *a.recurrence_period, a.recurrence_distance.value_or(0.0), *a.recurrence_period);
  // The contact of event k, when known: "contact J, " (named) or "".
  const auto who = [named](const std::vector<int>& contacts, size_t k) {
    return named && k < contacts.size() ? fmt::format("contact {}, ", contacts[k]) : std::string();
  };
  if (!a.stick_phases.empty() || a.impact_phases.empty()) {
    std::string p;
    for (size_t k = 0; k < a.stick_phases.size(); ++k) {
      const auto& [b, e] = a.stick_phases[k];
      const std::string c = who(a.stick_contacts, k);
      p += fmt::format("{}{}[{:.6f}, {:.6f}]", p.empty() ? "" : (named ? "; " : " "),
                       c.empty() ? "" : c.substr(0, c.size() - 2) + " ", b, e);
    }
    s += fmt::format("{}{} {}\n", indent, contact ? "in contact  " : "stick phases", p.empty() ? "none" : p);
  }
  for (size_t k = 0; k < a.impact_phases.size(); ++k) {
    const double before = k < a.impact_velocities.size() ? a.impact_velocities[k] : std::nan("");
    s += fmt::format("{}{}{}phase {:.6f}, {} before {:.6g}{}\n", indent, k == 0 ? "impacts      " : "             ",
                     who(a.impact_contacts, k), a.impact_phases[k], named ? "ġ" : "ẋ_B", before,
                     std::isnan(restitution) ? "" : fmt::format(", after {:.6g}", -restitution * before));
  }
  return s;
}

std::string LyapunovText(const LyapunovSpectrum& s, const std::string& indent) {
  if (!s.undefined.empty()) return fmt::format("{}lyapunov     none: {}\n", indent, s.undefined);
  std::string list;
  for (size_t i = 0; i < s.exponents.size(); ++i) {
    const double e = s.exponents[i];
    list += list.empty() ? "" : ", ";
    if (!std::isfinite(e))
      list += "-inf";
    else if (i < s.ci.size())
      list += fmt::format("{:.4g} ± {:.2g}", e, 0.5 * (s.ci[i].second - s.ci[i].first));
    else
      list += fmt::format("{:.4g}", e);
  }
  return fmt::format("{}lyapunov     {} per unit time ({} periods{}){}\n{}", indent, list, s.periods,
                     s.singular_periods ? fmt::format(", {} left out for a grazing", s.singular_periods) : "",
                     s.chaotic() ? ": chaotic" : "",
                     s.corner.empty() ? "" : fmt::format("{}corner       {}\n", indent, s.corner));
}

std::string LargestExponentCell(const std::optional<LyapunovSpectrum>& s) {
  if (!s || !s->undefined.empty() || s->exponents.empty()) return "-";
  if (!std::isfinite(s->exponents.front())) return "-inf";
  return fmt::format("{:.4g}", s->exponents.front());
}

}  // namespace vibro::cli
