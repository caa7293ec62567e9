// The interval model and the derivative bounds of a flight (enclosure.hpp).
#include "proof/enclosure.hpp"

#include <stdexcept>
#include <utility>

namespace vibro::proof {

namespace {
// "1.25", or "[1.2, 1.3]": every number between two decimals (a parameter interval).
Interval Parameter(const std::string& text) {
  if (!text.empty() && text.front() == '[' && text.back() == ']') {
    const auto comma = text.find(',');
    if (comma == std::string::npos) throw std::invalid_argument("not an interval: '" + text + "'");
    const auto trim = [](std::string t) {
      t.erase(0, t.find_first_not_of(' '));
      t.erase(t.find_last_not_of(' ') + 1);
      return t;
    };
    return Union(Interval::Decimal(trim(text.substr(1, comma - 1))), Interval::Decimal(trim(text.substr(comma + 1, text.size() - comma - 2))));
  }
  return Interval::Decimal(text);
}
}  // namespace

IntervalModel IntervalModel::FromDecimals(std::vector<std::string> omega, std::vector<std::string> forcing,
                                          std::vector<std::string> contact, std::vector<std::string> shape,
                                          std::string stop, std::string restitution, std::string amplitude,
                                          std::string frequency) {
  IntervalModel m;
  m.n = static_cast<int>(omega.size());
  if (forcing.size() != omega.size() || contact.size() != omega.size() || shape.size() != omega.size())
    throw std::invalid_argument("the modal lists have different lengths");
  for (const auto& t : omega) m.omega.push_back(Parameter(t));
  for (const auto& t : forcing) m.forcing.push_back(Parameter(t));
  for (const auto& t : contact) m.contact.push_back(Parameter(t));
  for (const auto& t : shape) m.shape.push_back(Parameter(t));
  m.stop = Parameter(stop);
  m.restitution = Parameter(restitution);
  m.amplitude = Parameter(amplitude);
  m.frequency = Parameter(frequency);
  for (int i = 0; i < m.n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    m.s_A += m.shape[k] * m.forcing[k];
    m.s_B += m.shape[k] * m.contact[k];
  }
  m.period = Interval(2.0) * Interval::Pi() / m.frequency;
  m.omega_text = std::move(omega);
  m.forcing_text = std::move(forcing);
  m.contact_text = std::move(contact);
  m.shape_text = std::move(shape);
  m.stop_text = std::move(stop);
  m.restitution_text = std::move(restitution);
  m.amplitude_text = std::move(amplitude);
  m.frequency_text = std::move(frequency);
  return m;
}

namespace {
Interval Power(const Interval& x, int k) {
  Interval y(1.0);
  for (int j = 0; j < k; ++j) y *= x;
  return y;
}
}  // namespace

Interval DerivativeBound(const IntervalModel& m, const Interval& t0, const std::vector<Interval>& X,
                         const std::vector<Interval>& V, int order) {
  const Interval sin0 = Sin(m.frequency * t0), cos0 = Cos(m.frequency * t0);
  Interval bound(0.0), forced(0.0);
  for (int i = 0; i < m.n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const Interval ua = m.forcing[k] * m.amplitude / (Sqr(m.omega[k]) - Sqr(m.frequency));
    const Interval a = X[k] - ua * sin0;
    const Interval b = (V[k] - ua * m.frequency * cos0) / m.omega[k];
    bound += Abs(m.shape[k]) * Power(m.omega[k], order) * Sqrt(Sqr(a) + Sqr(b));
    forced += m.shape[k] * ua;
  }
  return bound + Abs(forced) * Power(m.frequency, order);
}

}  // namespace vibro::proof
