// What the contacts endure (docs/loads.md) against independent truths: the momentum balance of
// the equations of motion integrated over a window (positions by quadrature of dense samples, not
// impulses), the energy balance (forcing work = viscous loss + impact loss + ΔE), the 1-DOF r = 0
// closed forms of the paper (the flight (33) and the reaction (5)), the chattering tail against a
// quad run that follows every impact, the rigid-limit normal work of a spring–dashpot contact
// integrated independently, and the batch-means interval.
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "support.hpp"
#include "vibro/loads.hpp"
#include "vibro/orbit_from_state.hpp"
#include "vibro/poincare.hpp"
#include "vibro/scene_file.hpp"

namespace vibro::test {
namespace {

Scene Load(const std::string& name, const std::vector<std::string>& sets) {
  return LoadScene(std::string(VIBRO_SCENES_DIR) + "/" + name, sets).scene;
}

struct Recorded {
  RunResult result;
  Log log;
  LoadsSummary loads;
};

Recorded RunLoads(const Scene& scene, long long skip, int blocks) {
  const System sys(scene);
  Recorded out;
  LoadsRecorder loads(sys, skip);
  SimulationOptions opt;
  opt.observers = {&out.log, &loads};
  out.result = vibro::Simulate(sys, scene, opt);
  out.loads = loads.Summary(blocks);
  return out;
}

// (B1) of docs/loads.md §5 over the window [a, b) of whole periods, mode by mode:
//   ω_i² ∫X_i dt + [Ẋ_i] + 2ζ_iω_i [X_i] − T_A,i f ∫sin ωt dt = Σ_j T_j,i J_j,
// ∫X_i by the trapezoid rule on the dense samples, [·] from the section points, ∫sin = 0 over whole
// periods; J_j = (impulse + ∫R dt per period) × periods from the loads recorder.
void ExpectMomentumBalance(const Scene& scene, long long periods, int spp, double tol) {
  Scene s = scene;
  s.run.periods = periods;
  s.run.samples_per_period = spp;
  const System sys(s);
  const Recorded rec = RunLoads(s, periods / 4, 2);
  ASSERT_EQ(rec.result.status, RunStatus::kOk) << rec.result.message;
  const long long a = rec.loads.first_period, b = a + rec.loads.periods;
  ASSERT_GT(rec.loads.periods, 0);
  const int n = sys.dof();
  const double h = sys.period() / spp;
  Eigen::VectorXd integral = Eigen::VectorXd::Zero(n);
  const Log::Row* first = nullptr;
  const Log::Row* last = nullptr;
  for (const auto& r : rec.log.sections) {
    if (r.clock.period == a) first = &r;
    if (r.clock.period == b) last = &r;
  }
  ASSERT_TRUE(first && last);
  for (const auto& r : rec.log.samples) {
    if (r.clock.period < a || r.clock.period >= b) continue;
    const double wgt = (r.clock.period == a && r.clock.offset == 0.0) ? 0.5 : 1.0;
    integral += wgt * h * r.X;
  }
  integral += 0.5 * h * last->X;
  double worst = 0;
  for (int i = 0; i < n; ++i) {
    const double w = sys.omega()[i], z = sys.damping()[i];
    const double lhs = w * w * integral[i] + (last->V[i] - first->V[i]) + 2 * z * w * (last->X[i] - first->X[i]);
    double rhs = 0, scale = std::abs(w * w * integral[i]);
    for (size_t j = 0; j < sys.contacts().size(); ++j) {
      const ContactLoads& c = rec.loads.contacts[j];
      const double J = (c.impulse_per_period + c.reaction_integral_per_period) * static_cast<double>(b - a);
      rhs += sys.contacts()[j].contact[i] * J;
      scale += std::abs(sys.contacts()[j].contact[i] * J);
    }
    worst = std::max(worst, std::abs(lhs - rhs) / scale);
    EXPECT_NEAR(lhs, rhs, tol * scale) << "mode " << i << " over periods [" << a << ", " << b << ")";
  }
  ::testing::Test::RecordProperty("worst_relative_residual", std::to_string(worst));
}

TEST(LoadsMomentumBalance, Fig8StickingChatteringOrbit) {
  // Fig. 8: period-1 orbit with a chattering sequence, its accumulation tail and a sticking phase.
  ExpectMomentumBalance(Load("fig08_preload.toml", {}), 40, 4000, 2e-6);
}

TEST(LoadsMomentumBalance, Chain3StickingHeldFlow) {
  // 3-DOF chain, r = 0: masses 1 and 2 move while mass 3 sticks (the held flow of several modes).
  ExpectMomentumBalance(Load("chain3.toml", {}), 40, 4000, 2e-6);
}

TEST(LoadsMomentumBalance, Chain3Chattering) {
  ExpectMomentumBalance(Load("chain3.toml", {"stop.restitution=0.5"}), 40, 4000, 2e-6);
}

TEST(LoadsMomentumBalance, DampedChain2) {
  ExpectMomentumBalance(Load("chain2_damped.toml", {}), 40, 4000, 2e-6);
}

TEST(LoadsMomentumBalance, SeveralContacts) {
  for (const char* name : {"contacts_preload_clearance_1dof.toml", "contacts_chain2.toml",
                           "contacts_impact_pair.toml", "contacts_two_sided_1dof.toml"}) {
    SCOPED_TRACE(name);
    ExpectMomentumBalance(Load(name, {}), 40, 4000, 2e-6);
  }
}

// Energy over [a, b): E(b) − E(a) = ∫ f sin ωt (μT_A)ᵀẊ dt − ∫ Ẋᵀ μ D Ẋ dt − Σ impact losses, with
// μ_i = 1/T_B,i (every mode seen by the single contact), integrals by the trapezoid rule.
// Two masses held on two stops at once (tests/reference/contacts/scenes/contacts_held_pair.toml:
// m = k = 1, K = [[2, −1], [−1, 2]], stops q_0 ≥ 0.3 and q_1 ≥ 0.2, r = 0, f = 0.5 on mass 1,
// ω = 0.7). Mass 0 is held throughout (λ_0 = 0.6 − q_1 > 0), so every sticking phase of mass 1 is
// held on both stops: q = d constant, and the contact forces are algebraic, λ = K d − b f sin ωt,
// λ_1 = 0.1 − 0.5 sin ωt; over a phase [t_s, t_r]
//   ∫λ_1 dt = 0.1 (t_r − t_s) + 0.5 (cos ωt_r − cos ωt_s)/ω   (long double, independent of vibro).
Scene HeldPair(long long periods, int spp) {
  Scene s = LoadScene(std::string(VIBRO_CONTACTS_SCENES_DIR) + "/contacts_held_pair.toml", {}).scene;
  s.run.periods = periods;
  s.run.samples_per_period = spp;
  return s;
}

TEST(LoadsHeldSet, TwoMassesOnBothStopsClosedForm) {
  const Recorded rec = RunLoads(HeldPair(20, 0), 0, 0);
  ASSERT_EQ(rec.result.status, RunStatus::kOk) << rec.result.message;
  const long double w = 0.7L;
  double t_stick = std::nan("");
  int phases = 0, interior = 0;
  for (const Event& e : rec.log.events) {
    if (e.contact == 0) {
      EXPECT_NE(e.kind, EventKind::kRelease) << "mass 0 leaves its stop at t = " << e.t;
    }
    if (e.contact != 1) continue;
    if (e.kind == EventKind::kStick) t_stick = e.t;
    if (e.kind != EventKind::kRelease) continue;
    ASSERT_TRUE(std::isfinite(t_stick));
    const long double ts = t_stick, tr = e.t;
    const long double exact = 0.1L * (tr - ts) + 0.5L * (std::cos(w * tr) - std::cos(w * ts)) / w;
    EXPECT_NEAR(e.stick_duration, static_cast<double>(tr - ts), 1e-12 * static_cast<double>(tr));
    // Event times carry the absolute-time rounding (a few ulp of t): the integral too.
    EXPECT_NEAR(e.reaction_integral, static_cast<double>(exact), 1e-12 * static_cast<double>(tr)) << "t = " << e.t;
    // max λ_1 over [t_s, t_r]: at an end, or 0.6 where sin ωt = −1 inside.
    long double lmax = std::max(0.1L - 0.5L * std::sin(w * ts), 0.1L - 0.5L * std::sin(w * tr));
    const long double k = std::ceil((w * ts - 1.5L * 3.14159265358979323846264L) / (2 * 3.14159265358979323846264L));
    const long double t_min = (1.5L * 3.14159265358979323846264L + 2 * 3.14159265358979323846264L * k) / w;
    if (t_min > ts && t_min < tr) lmax = 0.6L;
    EXPECT_NEAR(e.reaction_max, static_cast<double>(lmax), 1e-12) << "t = " << e.t;
    interior += lmax == 0.6L;
    ++phases;
  }
  EXPECT_GE(phases, 15);
  EXPECT_GE(interior, 10);  // maxima inside the phases, found by the search
  // The run's loads are known: the note names no contact, every mean is finite.
  const LoadsSummary s = rec.loads;
  EXPECT_EQ(s.note.find("not accounted"), std::string::npos) << s.note;
  ASSERT_EQ(s.contacts.size(), 2u);
  for (const ContactLoads& c : s.contacts) {
    EXPECT_TRUE(std::isfinite(c.mean_force)) << c.contact;
    EXPECT_TRUE(std::isfinite(c.reaction_integral_per_period)) << c.contact;
  }
  EXPECT_NEAR(s.contacts[0].contact_fraction, 1.0, 1e-15);
}

TEST(LoadsMomentumBalance, HeldPairBothStops) {
  // Mass 0 held for the whole window (its reaction only through the per-period account of an
  // open phase), mass 1 alternating flights and phases held on both stops.
  ExpectMomentumBalance(HeldPair(40, 4000), 40, 4000, 2e-6);
}

TEST(LoadsEnergyBalance, DampedChain2) {
  Scene s = Load("chain2_damped.toml", {});
  const int spp = 20000;
  s.run.periods = 30;
  s.run.samples_per_period = spp;
  const System sys(s);
  const Recorded rec = RunLoads(s, 10, 2);
  ASSERT_EQ(rec.result.status, RunStatus::kOk) << rec.result.message;
  const long long a = rec.loads.first_period, b = a + rec.loads.periods;
  const Eigen::VectorXd mu = sys.contact().cwiseInverse();
  const double h = sys.period() / spp, f = sys.amplitude(), w = sys.frequency();
  const auto energy = [&](const Eigen::VectorXd& X, const Eigen::VectorXd& V) {
    return 0.5 * (mu.cwiseProduct(V).dot(V) + mu.cwiseProduct(sys.omega().cwiseAbs2()).cwiseProduct(X).dot(X));
  };
  double forcing = 0, viscous = 0, e_a = 0, e_b = 0;
  std::vector<const Log::Row*> rows;
  for (const auto& r : rec.log.samples)
    if (r.clock.period >= a && r.clock.period < b) rows.push_back(&r);
  for (const auto& r : rec.log.sections) {
    if (r.clock.period == a) e_a = energy(r.X, r.V);
    if (r.clock.period == b) {
      e_b = energy(r.X, r.V);
      rows.push_back(&r);
    }
  }
  for (size_t k = 0; k < rows.size(); ++k) {
    const auto& r = *rows[k];
    const double wgt = (k == 0 || k + 1 == rows.size()) ? 0.5 : 1.0;
    forcing += wgt * h * f * std::sin(w * r.t) * mu.cwiseProduct(sys.forcing()).dot(r.V);
    viscous += wgt * h * (2 * sys.damping().cwiseProduct(sys.omega()).cwiseProduct(mu)).cwiseProduct(r.V).dot(r.V);
  }
  const double impacts = rec.loads.contacts[0].dissipated_power * static_cast<double>(b - a) * sys.period();
  EXPECT_GT(impacts, 0.05 * forcing);
  EXPECT_GT(viscous, 0.05 * forcing);
  EXPECT_NEAR(forcing, viscous + impacts + (e_b - e_a), 2e-4 * forcing)
      << "forcing " << forcing << " viscous " << viscous << " impacts " << impacts << " ΔE " << e_b - e_a;
}

// The paper's 1-DOF r = 0 orbit (docs/model.md §6): released at sin ωt'_1 = x0/f (32), the flight
// (33) lands at t'_0 with speed ẋ(t'_0) (impulse |ẋ(t'_0)|, m = 1), then sticks with
// R = x0 − f sin ωt (5) until the next release: ∫R dt = x0 Δt + f (cos ωt_r − cos ωt'_0)/ω.
TEST(LoadsClosedForm, OneDofPlasticLandingAndSticking) {
  const LD w = 2.8L, f = 1.2L, x0 = 1.0L;
  Scene s = OneDof(0.0, static_cast<double>(w), static_cast<double>(f), static_cast<double>(x0), 3);
  s.initial_displacement = Eigen::VectorXd::Constant(1, 1.0);
  s.initial_velocity = Eigen::VectorXd::Zero(1);
  const Recorded rec = RunLoads(s, 0, 2);
  ASSERT_EQ(rec.result.status, RunStatus::kOk);
  const auto& ev = rec.log.events;
  // Initial sticking phase [0, t'_1].
  const LD t1 = ReleaseTime(w, f, x0);
  size_t i = 0;
  while (i < ev.size() && ev[i].kind != EventKind::kRelease) ++i;
  ASSERT_LT(i, ev.size());
  EXPECT_NEAR(ev[i].stick_duration, static_cast<double>(t1), 1e-13);
  EXPECT_NEAR(ev[i].reaction_integral, static_cast<double>(x0 * t1 + f * (std::cos(w * t1) - 1) / w), 1e-13);
  EXPECT_NEAR(ev[i].reaction_max, 1.0, 1e-15);  // R(0) = x0, falling after
  // Landing.
  const Flight1 flight{w, f, t1, x0, 0};
  const LD t0 = flight.Landing(x0);
  const LD v = flight.v(t0);
  ++i;
  ASSERT_EQ(ev[i].kind, EventKind::kImpact);
  EXPECT_NEAR(ev[i].t, static_cast<double>(t0), 1e-10);
  EXPECT_NEAR(ev[i].impulse, static_cast<double>(-v), 1e-10);
  EXPECT_NEAR(ev[i].energy_dissipated, static_cast<double>(v * v / 2), 1e-10);
  // The sticking phase after it, to the next release.
  while (i < ev.size() && ev[i].kind != EventKind::kRelease) ++i;
  ASSERT_LT(i, ev.size());
  const LD tr = static_cast<LD>(ev[i].t);
  LD T = 2 * M_PIl / w, tr_exact = t1;
  while (tr_exact < t0) tr_exact += T;
  EXPECT_NEAR(static_cast<double>(tr), static_cast<double>(tr_exact), 1e-12);
  EXPECT_NEAR(ev[i].stick_duration, static_cast<double>(tr_exact - t0), 1e-10);
  EXPECT_NEAR(ev[i].reaction_integral,
              static_cast<double>(x0 * (tr_exact - t0) + f * (std::cos(w * tr_exact) - std::cos(w * t0)) / w), 1e-10);
  LD rmax = -1;
  for (int k = 0; k <= 200000; ++k) {
    const LD t = t0 + (tr_exact - t0) * k / 200000;
    rmax = std::max(rmax, x0 - f * std::sin(w * t));
  }
  EXPECT_NEAR(ev[i].reaction_max, static_cast<double>(rmax), 1e-9);
}

// max R and ∫R over a sticking phase of the 3-DOF chain (a held flow of two modes), against the
// reaction (5) evaluated on the dense samples of the phase (Simpson-free: trapezoid, max of samples).
TEST(LoadsClosedForm, HeldFlowReactionAgainstSamples) {
  Scene s = Load("chain3.toml", {});
  const int spp = 40000;
  s.run.periods = 6;
  s.run.samples_per_period = spp;
  const System sys(s);
  const Recorded rec = RunLoads(s, 0, 2);
  ASSERT_EQ(rec.result.status, RunStatus::kOk);
  const double h = sys.period() / spp;
  int checked = 0;
  const auto& ev = rec.log.events;
  for (size_t i = 0; i < ev.size(); ++i) {
    if (ev[i].kind != EventKind::kRelease || !(ev[i].stick_duration > 0.5)) continue;
    const double t_rel = ev[i].t, t_stick = t_rel - ev[i].stick_duration;
    double integral = 0, rmax = -1e300;
    for (const auto& r : rec.log.samples) {
      if (r.t < t_stick || r.t > t_rel) continue;
      // R = (Σ c_i ω_i² X_i − s_A f sin ωt)/s_B (eq. (5)), undamped.
      const double R = (sys.contact_shape().cwiseProduct(sys.omega().cwiseAbs2()).dot(r.X) -
                        sys.s_A() * sys.amplitude() * std::sin(sys.frequency() * r.t)) / sys.s_B();
      integral += h * R;
      rmax = std::max(rmax, R);
    }
    // R ≥ 0 vanishing at the release: the rectangle sum errs by at most h·max R at each end.
    EXPECT_NEAR(ev[i].reaction_integral, integral, 2 * h * ev[i].reaction_max);
    EXPECT_GE(ev[i].reaction_max, rmax - 1e-12);
    EXPECT_LE(ev[i].reaction_max, rmax + 1e-6 * rmax);
    ++checked;
  }
  EXPECT_GE(checked, 3);
}

// The tail of a chattering sequence (docs/loads.md §2) against following every impact in quad
// precision (run.chatter = "none") down to speeds below 1e-25: from an impact leaving at u, the
// impacts that follow sum to P_tail = (1 + r)u/((1 − r)s_B) (1 − ε/(3(1 + r))) and
// E_tail = u²/(2 s_B) (1 − 2ε/(3(1 + r + r²))) to O(ε²), ε the relative fall of R over the tail
// (docs/model.md §5.4a); without the ε terms they would be off by O(ε).
TEST(LoadsChatteringTail, GeometricSumAgainstQuadImpacts) {
  Scene s = Load("fig08_preload.toml", {"run.precision=\"quad\"", "run.chatter=\"none\"", "run.periods=2"});
  s.run.samples_per_period = 0;
  const System sys(s);
  const Recorded rec = RunLoads(s, 0, 2);
  // The run ends where the flights fall below quad's time resolution.
  const auto& ev = rec.log.events;
  std::vector<Event> seq;
  for (const auto& e : ev) {
    if (e.kind != EventKind::kImpact) continue;
    if (!seq.empty() && -e.v_before > -seq.back().v_before) seq.clear();  // a new sequence
    seq.push_back(e);
  }
  ASSERT_GT(seq.size(), 100u);
  ASSERT_LT(-seq.back().v_before, 1e-25);
  const double r = sys.restitution();
  int tested = 0;
  for (size_t k = 0; k + 1 < seq.size(); ++k) {
    const double u = seq[k].v_after;
    if (!(u > 1e-14)) continue;
    double P = 0, E = 0;
    for (size_t i = k + 1; i < seq.size(); ++i) {
      P += seq[i].impulse;
      E += seq[i].energy_dissipated;
    }
    // ε = −Ṙ Δ0 / R with Δ0 = 2u/((1 − r) s_B R), R = x0 − f sin ωt (1-DOF, eq. (5)).
    const double ph = sys.frequency() * seq[k].t;
    const double R = sys.stop() - sys.amplitude() * std::sin(ph);
    const double Rdot = -sys.amplitude() * sys.frequency() * std::cos(ph);
    const double eps = -Rdot * 2 * u / ((1 - r) * sys.s_B() * R * R);
    // The expansion is in ε and in the tail's duration against the oscillation: (ω Δ0)² terms
    // (the contact's stiffness and R̈ over the tail, docs/chattering.md) are not in it.
    const double delta0 = 2 * u / ((1 - r) * sys.s_B() * R), wd2 = std::pow(sys.frequency() * delta0, 2);
    if (!(std::abs(eps) < 0.01 && wd2 < 1e-6)) continue;
    const double Pg = (1 + r) * u / ((1 - r) * sys.s_B()), Eg = u * u / (2 * sys.s_B());
    const double Pt = Pg * (1 - eps / (3 * (1 + r))), Et = Eg * (1 - 2 * eps / (3 * (1 + r + r * r)));
    EXPECT_NEAR(P, Pt, (4 * eps * eps + 4 * wd2 + 1e-13) * Pt) << "u = " << u << ", ε = " << eps;
    EXPECT_NEAR(E, Et, (4 * eps * eps + 4 * wd2 + 1e-13) * Et) << "u = " << u << ", ε = " << eps;
    // The first-order terms matter: the constant-R sums are off by about ε/(3(1 + r)).
    if (std::abs(eps) > 1e-4) {
      EXPECT_GT(std::abs(P - Pg), 0.1 * std::abs(eps) / (3 * (1 + r)) * Pg);
    }
    ++tested;
  }
  EXPECT_GT(tested, 20);
}

// The double run's accumulation event carries the tail from its last impact: against the quad run
// that follows every impact of the same sequence.
TEST(LoadsChatteringTail, AccumulationEventAgainstQuadImpacts) {
  Scene quad = Load("fig08_preload.toml", {"run.precision=\"quad\"", "run.chatter=\"none\"", "run.periods=2"});
  Scene dbl = Load("fig08_preload.toml", {"run.periods=2"});
  quad.run.samples_per_period = dbl.run.samples_per_period = 0;
  const Recorded q = RunLoads(quad, 0, 2), d = RunLoads(dbl, 0, 2);
  size_t acc = 0;
  while (acc < d.log.events.size() && d.log.events[acc].kind != EventKind::kAccumulation) ++acc;
  ASSERT_LT(acc, d.log.events.size());
  ASSERT_EQ(d.log.events[acc - 1].kind, EventKind::kImpact);
  const double t_last = d.log.events[acc - 1].t;
  // The same impact in the quad run, then everything after it until the sequence ends.
  size_t k = 0;
  while (k < q.log.events.size() && std::abs(q.log.events[k].t - t_last) > 1e-9) ++k;
  ASSERT_LT(k, q.log.events.size());
  double P = 0, E = 0;
  for (size_t i = k + 1; i < q.log.events.size() && q.log.events[i].kind == EventKind::kImpact; ++i) {
    P += q.log.events[i].impulse;
    E += q.log.events[i].energy_dissipated;
  }
  const Event& a = d.log.events[acc];
  EXPECT_NEAR(a.impulse, P, 1e-7 * P);
  EXPECT_NEAR(a.energy_dissipated, E, 1e-7 * E);
}

// The normal work of a spring–dashpot contact (docs/loads.md §4): a mass m arriving at speed v on
// k x + c ẋ, integrated with RK4 until the force returns to zero (it cannot pull), gives a
// restitution r = |ẋ_end|/v and a normal work ∫|F ẋ| dt that is ½ m v² (1 + r²) whatever k and c.
TEST(LoadsNormalWork, SpringDashpotImpactIsHalfMV2OnePlusR2) {
  for (const double k : {1e2, 1e4, 1e6}) {
    for (const double zeta : {0.02, 0.1, 0.3}) {
      const double m = 2.5, v = 0.7, c = 2 * zeta * std::sqrt(k * m);
      // State (x, ẋ, W), x the penetration, ẋ > 0 into the contact.
      struct St { double x, u, W; };
      const auto deriv = [&](const St& s) {
        const double F = k * s.x + c * s.u;
        return St{s.u, -F / m, F * std::abs(s.u)};
      };
      const double dt = 1e-4 * std::sqrt(m / k);
      St s{0, v, 0};
      for (int step = 0; step < 10000000; ++step) {
        const St k1 = deriv(s);
        const St k2 = deriv({s.x + dt / 2 * k1.x, s.u + dt / 2 * k1.u, 0});
        const St k3 = deriv({s.x + dt / 2 * k2.x, s.u + dt / 2 * k2.u, 0});
        const St k4 = deriv({s.x + dt * k3.x, s.u + dt * k3.u, 0});
        const St n{s.x + dt / 6 * (k1.x + 2 * k2.x + 2 * k3.x + k4.x),
                   s.u + dt / 6 * (k1.u + 2 * k2.u + 2 * k3.u + k4.u),
                   s.W + dt / 6 * (k1.W + 2 * k2.W + 2 * k3.W + k4.W)};
        if (k * n.x + c * n.u <= 0 && n.u < 0) {
          // The force vanishes inside this step: interpolate linearly in the force.
          const double F0 = k * s.x + c * s.u, F1 = k * n.x + c * n.u, a = F0 / (F0 - F1);
          s = {s.x + a * (n.x - s.x), s.u + a * (n.u - s.u), s.W + a * (n.W - s.W)};
          break;
        }
        s = n;
      }
      const double r = -s.u / v;
      EXPECT_GT(r, 0.1);
      EXPECT_LT(r, 1.0);
      EXPECT_NEAR(s.W, 0.5 * m * v * v * (1 + r * r), 1e-6 * m * v * v) << "k " << k << " zeta " << zeta;
    }
  }
}

// Batch means: the interval of a long run that settles on Fig. 8's period-1 orbit covers the
// orbit's exact per-period values (vibro orbit's: one period simulated from the converged orbit).
TEST(LoadsBatchMeans, IntervalCoversOrbitValue) {
  Scene s = Load("fig08_preload.toml", {"run.periods=400"});
  s.initial_displacement = Eigen::VectorXd::Constant(1, 1.5);
  s.initial_velocity = Eigen::VectorXd::Constant(1, 0.3);
  s.run.samples_per_period = 0;
  const Recorded rec = RunLoads(s, 0, 10);
  ASSERT_EQ(rec.result.status, RunStatus::kOk);
  ASSERT_GT(rec.loads.block_periods, 0) << rec.loads.note;
  const System sys(s);
  OrbitRequest req;
  req.kind = OrbitKind::kAuto;
  const OrbitResult orbit = SolveOrbit(sys, Load("fig08_preload.toml", {}), req);
  ASSERT_EQ(orbit.status, "converged") << orbit.message;
  const LoadsSummary exact = OrbitLoads(sys, Load("fig08_preload.toml", {}), orbit);
  ASSERT_EQ(exact.contacts.size(), 1u) << exact.note;
  const ContactLoads& o = exact.contacts[0];
  EXPECT_NEAR(o.impacts_per_period, 33.0, 0.0);
  // The orbit's values against the closed balance of the orbit: mean force = ⟨x⟩ (ω_1 = 1, m = 1)
  // is checked by LoadsMomentumBalance; here they must agree with the long run's intervals.
  const ContactLoads& c = rec.loads.contacts[0];
  const auto covers = [](const ContactLoads::Interval& ci, double v) {
    return ci && ci->first <= v + 1e-12 * std::abs(v) && v - 1e-12 * std::abs(v) <= ci->second;
  };
  EXPECT_TRUE(covers(c.mean_force_ci, o.mean_force)) << o.mean_force;
  EXPECT_TRUE(covers(c.work_rate_ci, o.work_rate)) << o.work_rate;
  EXPECT_TRUE(covers(c.dissipated_power_ci, o.dissipated_power)) << o.dissipated_power;
  EXPECT_TRUE(covers(c.contact_fraction_ci, o.contact_fraction)) << o.contact_fraction;
  EXPECT_TRUE(covers(c.impulse_per_period_ci, o.impulse_per_period)) << o.impulse_per_period;
  // A run too short for its blocks says so and gives no interval.
  const Recorded shortrun = RunLoads(Load("fig08_preload.toml", {"run.periods=10"}), 0, 10);
  EXPECT_EQ(shortrun.loads.block_periods, 0);
  EXPECT_NE(shortrun.loads.note.find("too short"), std::string::npos);
  EXPECT_FALSE(shortrun.loads.contacts[0].mean_force_ci.has_value());
}

}  // namespace
}  // namespace vibro::test
