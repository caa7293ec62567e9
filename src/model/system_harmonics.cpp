// The forcing of a System as a sum of harmonics (docs/harmonics.md): each harmonic's modal forcing
// T_A^(h), its projection on every contact and on the modes held on it.
#include <cmath>
#include <stdexcept>

#include "vibro/system.hpp"

namespace vibro {

void System::BuildHarmonics(const Scene& scene) {
  harmonics_.clear();
  if (scene.harmonics.empty()) {
    harmonics_.push_back({f_, w_, 0.0, 1, forcing_});
  } else {
    std::vector<double> written;
    for (const HarmonicSpec& hs : scene.harmonics) written.push_back(hs.frequency);
    const CommonPeriod cp = FindCommonPeriod(written);
    if (!cp.commensurate) throw std::invalid_argument(cp.why);
    // scene.frequency is the base pulsation, scene.amplitude f_0: a change of either scales every
    // harmonic (vibro continue --param excitation.frequency keeps the ratios).
    const double f0 = scene.harmonics.front().amplitude;
    const double scale = f0 > 0 ? scene.amplitude / f0 : 1.0;
    for (size_t h = 0; h < scene.harmonics.size(); ++h) {
      const HarmonicSpec& hs = scene.harmonics[h];
      Harmonic out;
      out.multiple = cp.multiples[h];
      out.frequency = out.multiple * w_;
      out.amplitude = hs.amplitude * scale;
      out.phase = hs.phase;
      if (hs.vector.size() == 0) {
        out.forcing = forcing_;
      } else if (physical_) {
        // T_A,i = ψ_iᵀ v / m_i (docs/model.md §1.3 step 3 with e_A → v).
        out.forcing = (mode_shapes_.transpose() * hs.vector).cwiseQuotient(modal_masses_);
      } else {
        out.forcing.resize(omega_.size());
        for (Eigen::Index i = 0; i < omega_.size(); ++i) out.forcing[i] = hs.vector[kept_[static_cast<size_t>(i)]];
      }
      harmonics_.push_back(std::move(out));
    }
  }
  const Harmonic& h0 = harmonics_.front();
  harmonic_sum_ = harmonics_.size() > 1 || h0.multiple != 1 || h0.phase != 0.0 || h0.forcing != forcing_;
  harmonic_s_A_.assign(contacts_.size(), {});
  harmonic_stick_.assign(contacts_.size(), {});
  for (size_t j = 0; j < contacts_.size(); ++j) {
    const ContactModel& k = contacts_[j];
    for (const Harmonic& h : harmonics_) {
      const double sA = k.shape.dot(h.forcing);
      harmonic_s_A_[j].push_back(sA);
      const Eigen::VectorXd Fc = h.forcing - (sA / k.s_B) * k.contact;
      harmonic_stick_[j].push_back(k.constrained.left * Fc);
    }
  }
}

namespace {
double Turned(double p, int d) {
  switch (d & 3) {
    case 0: return std::sin(p);
    case 1: return std::cos(p);
    case 2: return -std::sin(p);
    default: return -std::cos(p);
  }
}
}  // namespace

Eigen::VectorXd System::HarmonicForce(double phase, int d) const {
  Eigen::VectorXd out = Eigen::VectorXd::Zero(omega_.size());
  for (const Harmonic& h : harmonics_)
    out += h.forcing * (h.amplitude * std::pow(h.frequency, d) * Turned(h.multiple * phase + h.phase, d));
  return out;
}

double System::HarmonicContactForce(int j, double phase, int d) const {
  double out = 0;
  for (size_t k = 0; k < harmonics_.size(); ++k) {
    const Harmonic& h = harmonics_[k];
    out += harmonic_s_A_[static_cast<size_t>(j)][k] * h.amplitude * std::pow(h.frequency, d) *
           Turned(h.multiple * phase + h.phase, d);
  }
  return out;
}

}  // namespace vibro
