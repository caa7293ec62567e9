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
                                          std::string frequency, std::vector<std::string> damping) {
  IntervalModel m;
  if (!damping.empty() && damping.size() != omega.size())
    throw std::invalid_argument("the damping ratios are not one per mode");
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
  for (std::size_t k = 0; k < damping.size(); ++k) {
    const Interval zeta = Parameter(damping[k]);
    if (!(zeta.lo() >= 0 && zeta.hi() < 1)) throw std::invalid_argument("a damping ratio outside [0, 1): '" + damping[k] + "'");
    const Interval w2 = Sqr(m.omega[k]), w = m.frequency, sigma = zeta * m.omega[k];
    const Interval det = w2 - Sqr(w), two_sw = Interval(2.0) * sigma * w;
    const Interval delta = Sqr(det) + Sqr(two_sw), kappa = m.forcing[k] * m.amplitude;
    m.damping.push_back(zeta);
    m.sigma.push_back(sigma);
    m.omega_d.push_back(m.omega[k] * Sqrt(Interval(1.0) - Sqr(zeta)));
    m.forced_sin.push_back(kappa * det / delta);
    m.forced_cos.push_back(-(kappa * two_sw / delta));
  }
  m.damping_text = std::move(damping);
  ContactData c0;
  c0.shape = m.shape;
  c0.contact = m.contact;
  c0.stop = m.stop;
  c0.restitution = m.restitution;
  c0.W = m.s_B;
  c0.shape_text = shape;
  c0.contact_text = contact;
  c0.stop_text = stop;
  c0.restitution_text = restitution;
  m.contacts.push_back(std::move(c0));
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

void IntervalModel::AddContact(std::vector<std::string> shape_, std::vector<std::string> contact_, std::string stop_,
                               std::string restitution_) {
  if (shape_.size() != omega.size() || contact_.size() != omega.size())
    throw std::invalid_argument("a contact's modal lists are not one per mode");
  ContactData c;
  for (const auto& t : shape_) c.shape.push_back(Parameter(t));
  for (const auto& t : contact_) c.contact.push_back(Parameter(t));
  c.stop = Parameter(stop_);
  c.restitution = Parameter(restitution_);
  for (std::size_t k = 0; k < omega.size(); ++k) c.W += c.shape[k] * c.contact[k];
  c.shape_text = std::move(shape_);
  c.contact_text = std::move(contact_);
  c.stop_text = std::move(stop_);
  c.restitution_text = std::move(restitution_);
  contacts.push_back(std::move(c));
}

namespace {
Interval Power(const Interval& x, int k) {
  Interval y(1.0);
  for (int j = 0; j < k; ++j) y *= x;
  return y;
}
}  // namespace

Interval DerivativeBound(const IntervalModel& m, const Interval& t0, const std::vector<Interval>& X,
                         const std::vector<Interval>& V, int order, int j) {
  const auto& shape = m.contacts[static_cast<std::size_t>(j)].shape;
  if (m.damped()) {
    // Per mode e^{−σs}(a cos ω_d s + b sin ω_d s) = Re((a − ib) e^{(−σ + iω_d)s}): its derivatives are
    // bounded by √(a² + b²) |−σ + iω_d|^order = √(a² + b²) ω_i^order for s ≥ 0; the forced part
    // (ΣcP) sin ωt + (ΣcQ) cos ωt by its amplitude times ω^order.
    const Interval sin0 = Sin(m.frequency * t0), cos0 = Cos(m.frequency * t0);
    Interval bound(0.0), fs(0.0), fc(0.0);
    for (int i = 0; i < m.n; ++i) {
      const auto k = static_cast<std::size_t>(i);
      const Interval &P = m.forced_sin[k], &Q = m.forced_cos[k];
      const Interval a = X[k] - (P * sin0 + Q * cos0);
      const Interval b = (V[k] - m.frequency * (P * cos0 - Q * sin0) + m.sigma[k] * a) / m.omega_d[k];
      bound += Abs(shape[k]) * Power(m.omega[k], order) * Sqrt(Sqr(a) + Sqr(b));
      fs += shape[k] * P;
      fc += shape[k] * Q;
    }
    return bound + Sqrt(Sqr(fs) + Sqr(fc)) * Power(m.frequency, order);
  }
  const Interval sin0 = Sin(m.frequency * t0), cos0 = Cos(m.frequency * t0);
  Interval bound(0.0), forced(0.0);
  for (int i = 0; i < m.n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const Interval ua = m.forcing[k] * m.amplitude / (Sqr(m.omega[k]) - Sqr(m.frequency));
    const Interval a = X[k] - ua * sin0;
    const Interval b = (V[k] - ua * m.frequency * cos0) / m.omega[k];
    bound += Abs(shape[k]) * Power(m.omega[k], order) * Sqrt(Sqr(a) + Sqr(b));
    forced += shape[k] * ua;
  }
  return bound + Abs(forced) * Power(m.frequency, order);
}

}  // namespace vibro::proof
