// Checking claimed orbits of a scene with several contacts (include/vibro/branch_check.hpp,
// docs/contacts.md "Check, validate and partition") against the closed form of the symmetric
// two-sided 1-DOF oscillator (docs/contacts_reference.md): unit mass and stiffness (ω1 = 1),
// stops at ±Δ, a sin ωt, restitution r at both. Its symmetric period-1 orbit hits +Δ at phase φ
// with speed V, −Δ half a period later:
//   (k1² + k2²) V² − 2Δ k1 V + Δ² − U² = 0,  k1 = (1 + r) tan(θ/2)/(2ω1), k2 = (1 − r)/(2ω),
//   θ = ω1π/ω, U = a/(ω1² − ω²),  φ = atan2((Δ − k1V)/U, k2V/U),
// so the state just after the impact on +Δ is x = Δ, ẋ = −rV at t = φ/ω.
#include <cmath>

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "vibro/branch_check.hpp"
#include "vibro/scene_file.hpp"

namespace vibro {
namespace {

using ::testing::HasSubstr;

constexpr double kR = 0.8, kDelta = 1.0, kA = 1.0;

Scene TwoSided(double w) {
  return LoadScene(std::string(VIBRO_SCENES_DIR) + "/contacts_two_sided_1dof.toml",
                   {fmt::format("excitation.frequency={}", w), fmt::format("excitation.amplitude={}", kA),
                    fmt::format("contact[0].restitution={}", kR), fmt::format("contact[1].restitution={}", kR),
                    "run.samples_per_period=0"})
      .scene;
}

// The stable root (the larger V) of the closed form: {V, φ}.
std::pair<double, double> ClosedForm(double w) {
  const double theta = M_PI / w, k1 = (1 + kR) * std::tan(theta / 2) / 2, k2 = (1 - kR) / (2 * w);
  const double U = kA / (1 - w * w);
  const double qa = k1 * k1 + k2 * k2, qb = -2 * kDelta * k1, qc = kDelta * kDelta - U * U;
  const double V = (-qb + std::sqrt(qb * qb - 4 * qa * qc)) / (2 * qa);
  double phi = std::atan2((kDelta - k1 * V) / U, k2 * V / U);
  if (phi < 0) phi += 2 * M_PI;
  return {V, phi};
}

ClaimedPoint Claim(double w, double x, double v, std::string sequence = "") {
  ClaimedPoint p;
  p.value = w;
  p.time = ClosedForm(w).second / w;
  p.displacement = Eigen::VectorXd::Constant(1, x);
  p.velocity = Eigen::VectorXd::Constant(1, v);
  p.sequence = std::move(sequence);
  return p;
}

TEST(ContactsValidate, ClosedFormOracle) {
  EXPECT_NEAR(ClosedForm(2.5).first, 1.79902274247141, 1e-13);
}

TEST(ContactsValidate, ClaimedStartPerContact) {
  const Scene s = TwoSided(2.5);
  const System sys(s);
  const auto [V, phi] = ClosedForm(2.5);
  std::string problem;
  // Another tool's rounding: 5e-10 beyond the upper stop, moving into it at V: put on the stop
  // and the impact law of contact 1 applied (one DOF: ẋ⁺ = −r ẋ⁻ exactly).
  auto start = ClaimedStart(sys, s, Claim(2.5, kDelta + 5e-10, V), problem);
  EXPECT_EQ(problem, "");
  EXPECT_NEAR(start.X[0], kDelta, 1e-15);
  EXPECT_NEAR(start.V[0], -kR * V, 1e-14);
  // The same at the lower stop (contact 0).
  start = ClaimedStart(sys, s, Claim(2.5, -kDelta, -V), problem);
  EXPECT_EQ(problem, "");
  EXPECT_NEAR(start.V[0], kR * V, 1e-14);
  // Beyond the rounding forgiven: outside the gap of contact 1.
  ClaimedStart(sys, s, Claim(2.5, kDelta + 2e-9, 0.0), problem);
  EXPECT_THAT(problem, HasSubstr("outside the gap of contact 1"));
  (void)phi;
}

TEST(ContactsValidate, ClosedFormConfirmedWrongSequenceRefuted) {
  CheckTolerances tol;
  for (double w : {2.2, 2.5, 3.0}) {
    SCOPED_TRACE(w);
    const Scene s = TwoSided(w);
    const double V = ClosedForm(w).first;
    // Written from either stop: the same cyclic word.
    for (const char* sequence : {"", "0:impact 1:impact", "1:impact 0:impact"}) {
      const PointCheck c = CheckPoint(s, Claim(w, kDelta, -kR * V, sequence), OrbitKind::kAuto, 1, tol);
      EXPECT_EQ(c.verdict, "confirmed") << c.detail;
      ASSERT_TRUE(c.distance);
      EXPECT_LT(*c.distance, 1e-12);
    }
    const PointCheck bad = CheckPoint(s, Claim(w, kDelta, -kR * V, "0:impact 0:impact"), OrbitKind::kAuto, 1, tol);
    EXPECT_EQ(bad.verdict, "sequence-differs");
    EXPECT_THAT(bad.detail, HasSubstr("claimed sequence 0:impact 0:impact"));
    EXPECT_THAT(bad.detail, HasSubstr("vibro's orbit has"));
    const PointCheck off = CheckPoint(s, Claim(w, kDelta, -kR * V + 1e-3, "0:impact 1:impact"), OrbitKind::kAuto, 1, tol);
    EXPECT_EQ(off.verdict, "no-orbit-near");
  }
}

}  // namespace
}  // namespace vibro
