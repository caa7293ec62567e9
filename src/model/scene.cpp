// Scene validation: every physical constraint of docs/scenes.md / docs/model.md §1, §8, each problem
// reported against its key.
#include "vibro/scene.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>
#include <tuple>
#include <utility>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "vibro/system.hpp"

namespace vibro {
namespace {

std::string Show(double v) { return fmt::format("{}", v); }
std::string Show(const Eigen::VectorXd& v) {
  return fmt::format("[{}]", fmt::join(v.data(), v.data() + v.size(), ", "));
}
std::string Show(const Eigen::MatrixXd& m) {
  std::string s = "[";
  for (Eigen::Index i = 0; i < m.rows(); ++i) {
    Eigen::VectorXd row = m.row(i).transpose();
    s += (i ? ", " : "") + Show(row);
  }
  return s + "]";
}

class Checker {
 public:
  void Require(bool ok, const std::string& key, const std::string& value, std::string constraint) {
    if (!ok) issues_.push_back({key, value, std::move(constraint)});
  }
  std::vector<InputIssue> Take() { return std::move(issues_); }
  bool empty() const { return issues_.empty(); }
  size_t size() const { return issues_.size(); }

 private:
  std::vector<InputIssue> issues_;
};

bool SymmetricPositiveDefinite(const Eigen::MatrixXd& m) {
  if (m.rows() != m.cols() || m.rows() == 0) return false;
  Eigen::LLT<Eigen::MatrixXd> llt(m);
  return llt.info() == Eigen::Success;
}

bool Symmetric(const Eigen::MatrixXd& m) {
  const double scale = m.cwiseAbs().maxCoeff();
  return (m - m.transpose()).cwiseAbs().maxCoeff() <= 1e-12 * scale;
}

void CheckModal(const ModalStructureSpec& m, Checker& c) {
  const auto n = m.frequencies.size();
  c.Require(n > 0, "structure.frequencies", Show(m.frequencies), "at least one mode is required");
  for (Eigen::Index i = 0; i < n; ++i)
    c.Require(m.frequencies[i] > 0, "structure.frequencies", Show(m.frequencies),
              fmt::format("ω_i > 0 (element {} is {})", i, m.frequencies[i]));
  c.Require(m.forcing.size() == n, "structure.forcing", Show(m.forcing),
            fmt::format("one value per mode: length {} expected (structure.frequencies), got {}",
                        n, m.forcing.size()));
  c.Require(m.contact.size() == n, "structure.contact", Show(m.contact),
            fmt::format("one value per mode: length {} expected (structure.frequencies), got {}",
                        n, m.contact.size()));
  for (Eigen::Index i = 0; i < m.contact.size(); ++i)
    c.Require(m.contact[i] > 0, "structure.contact", Show(m.contact),
              fmt::format("T_B,i > 0 (element {} is {}); a mode with a node at B is invisible to "
                          "the contact: give the physical form (mass, stiffness, contact_dof) and "
                          "vibro keeps such modes out of the contact model",
                          i, m.contact[i]));
}

// `own_contact_dof`: contact_dof is the scene's (a [stop]); with [[contact]] tables it is
// contact[0]'s DOF, checked (and located) there.
void CheckPhysical(const PhysicalStructureSpec& p, bool own_contact_dof, Checker& c) {
  const auto N = p.mass.rows();
  const bool square_m = p.mass.rows() == p.mass.cols() && N > 0;
  const bool square_k = p.stiffness.rows() == p.stiffness.cols() && p.stiffness.rows() > 0;
  c.Require(square_m, "structure.mass", Show(p.mass), "a square, non-empty matrix");
  c.Require(square_k, "structure.stiffness", Show(p.stiffness), "a square, non-empty matrix");
  if (square_m) {
    c.Require(Symmetric(p.mass), "structure.mass", Show(p.mass), "symmetric (M = Mᵀ)");
    c.Require(SymmetricPositiveDefinite(p.mass), "structure.mass", Show(p.mass),
              "positive definite (every mass positive, no rigid constraint)");
  }
  if (square_k) {
    c.Require(Symmetric(p.stiffness), "structure.stiffness", Show(p.stiffness),
              "symmetric (K = Kᵀ)");
    c.Require(SymmetricPositiveDefinite(p.stiffness), "structure.stiffness", Show(p.stiffness),
              "positive definite (no rigid-body mode: the structure must be held)");
  }
  if (square_m && square_k)
    c.Require(p.stiffness.rows() == N, "structure.stiffness", Show(p.stiffness),
              fmt::format("same size as structure.mass ({0}×{0})", N));
  c.Require(p.forcing_dof >= 0 && p.forcing_dof < N, "structure.forcing_dof",
            std::to_string(p.forcing_dof), fmt::format("a DOF index in [0, {})", N));
  if (own_contact_dof)
    c.Require(p.contact_dof >= 0 && p.contact_dof < N, "structure.contact_dof",
              std::to_string(p.contact_dof), fmt::format("a DOF index in [0, {})", N));
}

// Magnitudes the double arithmetic of the engines can square and sum without overflow.
constexpr double kHuge = 1e100;
constexpr double kTiny = 1e-100;
// Largest structure: the model keeps several n×n matrices, and so does every engine.
constexpr Eigen::Index kMaxModes = 2000;

void CheckMagnitude(const Eigen::Ref<const Eigen::VectorXd>& v, const std::string& key, Checker& c) {
  for (Eigen::Index i = 0; i < v.size(); ++i)
    if (!(std::abs(v[i]) <= kHuge)) {
      c.Require(false, key, "",
                fmt::format("|value| ≤ {:g} (element {} is {}; its square must be representable)", kHuge,
                            i, v[i]));
      return;
    }
}
void CheckMagnitude(double v, const std::string& key, Checker& c) {
  c.Require(std::abs(v) <= kHuge, key, Show(v), fmt::format("|value| ≤ {:g} (its square must be representable)", kHuge));
}

// The [[contact]] tables (docs/contacts.md): indices, restitution, no two dependent contacts
// (MODEL §11.1.3: the same direction σw twice, or a two-sided stop without clearance).
// Modal form (docs/contacts.md, "the modal form"): every contact j ≥ 1 gives a_j, one component per
// listed mode, finite, not zero on every kept mode (W_jj > 0). Dependence needs the model: Validate.
void CheckModalContacts(const Scene& s, Eigen::Index n_modes, Checker& c) {
  const auto key = [](size_t j) { return fmt::format("contact[{}].modal", j); };
  const std::vector<int> kept = System::KeptModes(s.modal->frequencies, s.modes);
  for (size_t j = 1; j < s.contacts.size(); ++j) {
    const Eigen::VectorXd& a = s.contacts[j].modal;
    if (a.size() != n_modes) {  // none given: the file layer reports the missing key
      c.Require(false, key(j), Show(a),
                fmt::format("one component per mode: length {} expected (structure.frequencies), got {}",
                            n_modes, a.size()));
      continue;
    }
    const size_t before = c.size();
    CheckMagnitude(a, key(j), c);
    if (c.size() != before) continue;
    bool seen = false;
    for (int i : kept) seen = seen || a[i] != 0.0;
    c.Require(seen, key(j), Show(a),
              fmt::format("the contact sees a kept mode: a_{},i ≠ 0 for at least one of the {} mode(s) "
                          "kept (a contact on no mode never closes and has no impact law)",
                          j, kept.size()));
  }
}

// The compliant stops (docs/compliant.md): k ≥ 0 and c ≥ 0 finite, a damping only with a stiffness;
// they run in double precision, with the exact engine's closed forms or CVODE.
void CheckCompliance(const Scene& s, Checker& c) {
  const auto one = [&](const Compliance& k, const std::string& at) {
    c.Require(std::isfinite(k.stiffness) && k.stiffness >= 0 && k.stiffness <= kHuge, at + ".stiffness",
              Show(k.stiffness), fmt::format("0 < k ≤ {:g} (0: a rigid stop)", kHuge));
    c.Require(std::isfinite(k.damping) && k.damping >= 0 && k.damping <= kHuge, at + ".damping", Show(k.damping),
              fmt::format("0 ≤ c ≤ {:g}", kHuge));
    c.Require(k.stiffness > 0 || k.damping == 0, at + ".damping", Show(k.damping),
              "belongs to a compliant stop: give its stiffness too");
  };
  if (s.contacts.empty()) one(s.stop_compliance, "stop");
  for (size_t j = 0; j < s.contacts.size(); ++j) one(s.contacts[j].compliance, fmt::format("contact[{}]", j));
  if (!HasCompliantContact(s)) return;
  c.Require(s.run.precision == Precision::kDouble, "run.precision", ToString(s.run.precision),
            "\"double\": a compliant stop's contact phase is not yet available in quad precision "
            "(docs/compliant.md)");
}

void CheckContacts(const Scene& s, Eigen::Index n_dofs, Checker& c) {
  if (s.contacts.empty()) return;
  const auto key = [](size_t j, const char* leaf) { return fmt::format("contact[{}].{}", j, leaf); };
  if (!s.physical) {
    for (size_t j = 0; j < s.contacts.size(); ++j) {
      c.Require(s.contacts[j].restitution >= 0 && s.contacts[j].restitution <= 1, key(j, "restitution"),
                Show(s.contacts[j].restitution), "0 ≤ r ≤ 1");
      CheckMagnitude(s.contacts[j].position, key(j, "position"), c);
    }
    if (s.modal) CheckModalContacts(s, n_dofs, c);
    return;
  }
  const auto N = static_cast<int>(n_dofs);
  bool indices_ok = true;
  for (size_t j = 0; j < s.contacts.size(); ++j) {
    const ContactSpec& k = s.contacts[j];
    const bool pair = k.partner >= 0 || k.partner < -1;
    const std::string dof_key = key(j, pair ? "dofs" : "dof");
    const bool in = k.dof >= 0 && k.dof < N && (!pair || (k.partner >= 0 && k.partner < N));
    c.Require(in, dof_key, pair ? fmt::format("[{}, {}]", k.dof, k.partner) : std::to_string(k.dof),
              fmt::format("DOF indices in [0, {})", N));
    c.Require(!pair || k.dof != k.partner, dof_key, fmt::format("[{}, {}]", k.dof, k.partner),
              "an impact pair joins two different DOFs");
    indices_ok = indices_ok && in && (!pair || k.dof != k.partner);
    c.Require(k.restitution >= 0 && k.restitution <= 1, key(j, "restitution"), Show(k.restitution),
              "0 ≤ r ≤ 1");
    CheckMagnitude(k.position, key(j, "position"), c);
  }
  if (!indices_ok) return;
  // Directions σw as sparse pairs (+1 at one DOF, −1 at another or none), for comparison.
  const auto direction = [](const ContactSpec& k) {
    const int sg = k.side == Side::kBelow ? 1 : -1;
    return std::tuple{k.dof, k.partner, sg};
  };
  for (size_t j = 0; j < s.contacts.size(); ++j)
    for (size_t k = j + 1; k < s.contacts.size(); ++k) {
      const auto [bj, aj, sj] = direction(s.contacts[j]);
      const auto [bk, ak, sk] = direction(s.contacts[k]);
      // Same line: the same DOF set; the same orientation or the opposite one.
      int same = 0;  // +1 same direction, −1 opposite, 0 independent
      if (bj == bk && aj == ak) same = sj == sk ? 1 : -1;
      else if (aj >= 0 && bj == ak && aj == bk) same = sj == sk ? -1 : 1;
      if (same == 1)
        c.Require(false, key(k, "side"), fmt::format("\"{}\"", ToString(s.contacts[k].side)),
                  fmt::format("two contacts on one side of the same {} (contact {} and {}) are "
                              "dependent: keep one (the Delassus matrix is singular)",
                              aj >= 0 ? "pair" : "DOF", j, k));
      if (same == -1) {
        // σ_k w_k = −σ_j w_j: g_j + g_k = −(σ_j d_j + σ_k d_k), the clearance.
        const double clearance = -(sj * s.contacts[j].position + sk * s.contacts[k].position);
        c.Require(clearance > 0, key(k, "position"), Show(s.contacts[k].position),
                  fmt::format("a positive clearance between the two sides of contact {} and {} "
                              "(here {}): below must lie under above",
                              j, k, clearance));
      }
    }
}

}  // namespace

std::vector<InputIssue> Validate(const Scene& s) {
  Checker c;
  Eigen::Index n_listed = 0;  // modes listed (modal form) or DOFs (physical form)
  if (s.modal && s.physical) {
    c.Require(false, "structure", "",
              "give either the modal form (frequencies, forcing, contact) or the physical form "
              "(mass, stiffness, forcing_dof, contact_dof), not both");
  } else if (s.modal) {
    CheckModal(*s.modal, c);
    n_listed = s.modal->frequencies.size();
  } else if (s.physical) {
    CheckPhysical(*s.physical, s.contacts.empty(), c);
    n_listed = s.physical->mass.rows();
  } else {
    c.Require(false, "structure", "",
              "missing: give the modal form (frequencies, forcing, contact) or the physical form "
              "(mass, stiffness, forcing_dof, contact_dof)");
  }
  if (s.damping_ratios.size() > 0) {
    c.Require(s.damping_ratios.size() == n_listed, "structure.damping_ratios",
              Show(s.damping_ratios),
              fmt::format("one ratio per mode: length {} expected, got {}", n_listed,
                          s.damping_ratios.size()));
    for (Eigen::Index i = 0; i < s.damping_ratios.size(); ++i)
      c.Require(s.damping_ratios[i] >= 0 && s.damping_ratios[i] < 1, "structure.damping_ratios",
                Show(s.damping_ratios),
                fmt::format("0 ≤ ζ_i < 1 (element {} is {}; over- and critically damped modes "
                            "are not supported)",
                            i, s.damping_ratios[i]));
  }
  c.Require(s.modes >= 0 && s.modes <= n_listed, "structure.modes", std::to_string(s.modes),
            fmt::format("1 ≤ modes ≤ {} (the number of modes of the structure)", n_listed));

  c.Require(s.restitution >= 0 && s.restitution <= 1, "stop.restitution", Show(s.restitution),
            "0 ≤ r ≤ 1");
  // With harmonics, amplitude and frequency are derived (f_0, ω_b): ValidateHarmonics checks each.
  const bool lists = !s.harmonics.empty();
  c.Require(lists || s.amplitude >= 0, "excitation.amplitude", Show(s.amplitude), "f ≥ 0");
  c.Require(lists || s.frequency > 0, "excitation.frequency", Show(s.frequency), "ω > 0");
  // What the machine allows: the period T = 2π/ω, the forcing and the squares of every state
  // (energies, ω²X) must be representable with room to spare, so magnitudes stay in
  // [kTiny, kHuge]; a forcing below kTiny is no forcing (give 0).
  c.Require(lists || s.amplitude == 0 || (s.amplitude >= kTiny && s.amplitude <= kHuge), "excitation.amplitude",
            Show(s.amplitude), fmt::format("f = 0 or {:g} ≤ f ≤ {:g} (representable forcing)", kTiny, kHuge));
  c.Require(lists || !(s.frequency > 0) || (s.frequency >= kTiny && s.frequency <= kHuge), "excitation.frequency",
            Show(s.frequency),
            fmt::format("{:g} ≤ ω ≤ {:g} (the period 2π/ω and the phase ωt representable)", kTiny, kHuge));
  CheckMagnitude(s.stop_position, "stop.position", c);
  CheckMagnitude(s.initial_time, "initial.time", c);
  CheckMagnitude(s.initial_displacement, "initial.displacement", c);
  CheckMagnitude(s.initial_velocity, "initial.velocity", c);
  CheckMagnitude(s.run.max_step, "run.max_step", c);
  if (s.modal) {
    CheckMagnitude(s.modal->frequencies, "structure.frequencies", c);
    CheckMagnitude(s.modal->forcing, "structure.forcing", c);
    CheckMagnitude(s.modal->contact, "structure.contact", c);
  }
  if (s.physical) {
    CheckMagnitude(s.physical->mass.reshaped(), "structure.mass", c);
    CheckMagnitude(s.physical->stiffness.reshaped(), "structure.stiffness", c);
    // A mass or stiffness below kTiny (a subnormal one) makes ω² = k/m overflow or vanish.
    for (const auto& [M, key] : {std::pair{&s.physical->mass, "structure.mass"},
                                 std::pair{&s.physical->stiffness, "structure.stiffness"}})
      for (Eigen::Index i = 0; i < std::min(M->rows(), M->cols()); ++i)
        c.Require(!((*M)(i, i) > 0) || (*M)(i, i) >= kTiny, key, Show(*M),
                  fmt::format("diagonal entries ≥ {:g} (entry ({}, {}) is {:g}; ω² = k/m must be representable)",
                              kTiny, i, i, (*M)(i, i)));
  }
  c.Require(n_listed <= kMaxModes, "structure", std::to_string(n_listed),
            fmt::format("at most {} modes or DOFs (the model's matrices are n×n)", kMaxModes));

  CheckContacts(s, n_listed, c);
  for (auto& issue : ValidateHarmonics(s.harmonics, static_cast<long>(n_listed)))
    c.Require(false, issue.key, issue.value, issue.constraint);
  CheckCompliance(s, c);

  const auto& r = s.run;
  c.Require(r.periods >= 1, "run.periods", std::to_string(r.periods), "periods ≥ 1");
  // The absolute times written (t0 + k·T + offset, one double) must resolve every sample: their
  // rounding, about 2e-16 of (|t0|/T + periods)·T, stays below 2e-4 of the sample spacing.
  if (s.frequency >= kTiny && s.frequency <= kHuge && std::isfinite(s.initial_time) && r.periods >= 1) {
    const double T = 2 * M_PI / s.frequency;
    const double per = std::max<double>(1.0, static_cast<double>(r.samples_per_period));
    const double span = std::abs(s.initial_time) / T + static_cast<double>(r.periods);
    if (!(span * per <= 1e12)) {
      const bool t0 = std::abs(s.initial_time) / T * per > 0.5e12;
      c.Require(false, t0 ? "initial.time" : "run.periods",
                t0 ? Show(s.initial_time) : std::to_string(r.periods),
                fmt::format("(|t0|/T + periods) · max(1, samples_per_period) ≤ 1e12, here {:.3g} with T = {:.6g}: "
                            "beyond, the absolute times written no longer resolve the samples{}",
                            span * per, T,
                            t0 ? " (t0 only sets the forcing phase: give t0 modulo T)" : ""));
    }
  }
  c.Require(r.rtol >= 1e-14 && r.rtol < 1, "run.rtol", Show(r.rtol),
            "1e-14 ≤ rtol < 1 (CVODE cannot honour a smaller relative tolerance in double precision)");
  c.Require(r.atol > 0 && r.atol < 1, "run.atol", Show(r.atol), "0 < atol < 1");
  c.Require(r.max_step >= 0, "run.max_step", Show(r.max_step), "max_step ≥ 0 (0 = no limit)");
  c.Require(r.max_steps >= 1, "run.max_steps", std::to_string(r.max_steps), "max_steps ≥ 1");
  c.Require(r.chatter_switch > 0 && r.chatter_switch < 1, "run.chatter_switch",
            Show(r.chatter_switch), "0 < chatter_switch < 1 (relative to the first impact)");
  c.Require(r.chatter_tolerance == 0 || (r.chatter_tolerance >= 1e-32 && r.chatter_tolerance <= 1e-3),
            "run.chatter_tolerance", Show(r.chatter_tolerance),
            "chatter_tolerance = 0 (the default of the precision) or 1e-32 ≤ chatter_tolerance ≤ "
            "1e-3 (relative to the forcing period)");
  if (r.precision == Precision::kQuad) {
    c.Require(r.engine == Engine::kExact, "run.precision", "\"quad\"",
              "precision = \"quad\" needs run.engine = \"exact\" (CVODE runs in double)");
    c.Require(r.chatter_tolerance == 0 || r.chatter_tolerance >= 1e-32, "run.chatter_tolerance",
              Show(r.chatter_tolerance), "chatter_tolerance ≥ 1e-32 in quad precision");
  } else {
    c.Require(r.chatter_tolerance == 0 || r.chatter_tolerance >= 1e-15, "run.chatter_tolerance",
              Show(r.chatter_tolerance),
              "chatter_tolerance ≥ 1e-15 in double precision (use run.precision = \"quad\" "
              "below)");
  }
  c.Require(r.samples_per_period >= 0, "run.samples_per_period",
            std::to_string(r.samples_per_period), "samples_per_period ≥ 0");
  c.Require(r.max_period >= 1, "run.max_period", std::to_string(r.max_period), "max_period ≥ 1");
  c.Require(r.period_tolerance > 0 && r.period_tolerance < 1, "run.period_tolerance",
            Show(r.period_tolerance), "0 < period_tolerance < 1");

  const bool has_x = s.initial_displacement.size() > 0;
  const bool has_v = s.initial_velocity.size() > 0;
  if (has_x)
    c.Require(s.initial_displacement.size() == n_listed, "initial.displacement",
              Show(s.initial_displacement),
              fmt::format("one value per {}: length {} expected, got {}",
                          s.physical ? "DOF" : "mode", n_listed, s.initial_displacement.size()));
  if (has_v)
    c.Require(s.initial_velocity.size() == n_listed, "initial.velocity",
              Show(s.initial_velocity),
              fmt::format("one value per {}: length {} expected, got {}",
                          s.physical ? "DOF" : "mode", n_listed, s.initial_velocity.size()));
  if (has_x != has_v)
    c.Require(false, has_x ? "initial.velocity" : "initial.displacement", "",
              "give both initial.displacement and initial.velocity, or neither");

  if (!c.empty()) return c.Take();

  // The structure is consistent: check what needs the model.
  std::optional<System> built;
  try {
    built.emplace(s);
  } catch (const std::invalid_argument& e) {
    c.Require(false, s.modes > 0 ? "structure.modes" : "contact", s.modes > 0 ? std::to_string(s.modes) : "",
              fmt::format("every contact sees a kept mode ({})", e.what()));
    return c.Take();
  }
  const System& sys = *built;
  if (s.modal && sys.contact_count() > 1) {
    // Modal form: two contacts are dependent when c_k ∥ c_j on the kept modes
    // (docs/contacts_reference.md, "the modal form": W_jk = c_jᵀμ⁻¹c_k, so W_jk² = W_jj W_kk, the
    // Cauchy–Schwarz equality in the μ⁻¹ inner product). Typed components carry rounding, so
    // parallel means |W_jk| ≥ (1 − 1e-12) √(W_jj W_kk).
    const Eigen::MatrixXd& W = sys.delassus();
    for (int j = 0; j < sys.contact_count(); ++j)
      for (int k = j + 1; k < sys.contact_count(); ++k) {
        if (!(std::abs(W(j, k)) >= (1 - 1e-12) * std::sqrt(W(j, j) * W(k, k)))) continue;
        const ContactModel& cj = sys.contacts()[static_cast<size_t>(j)];
        const ContactModel& ck = sys.contacts()[static_cast<size_t>(k)];
        if (W(j, k) > 0) {
          c.Require(false, fmt::format("contact[{}].modal", k), Show(s.contacts[static_cast<size_t>(k)].modal),
                    fmt::format("contacts {} and {} are dependent: their gaps read the kept modes in one "
                                "direction on one side (c_{} = {} c_{}); keep one (the Delassus matrix "
                                "is singular)",
                                j, k, k, W(j, k) / W(j, j), j));
        } else {
          // c_k = −α c_j: g_j + g_k/α = −(e_j + e_k/α), the clearance between the two sides.
          const double alpha = -W(j, k) / W(j, j);
          const double clearance = -(cj.stop + ck.stop / alpha);
          c.Require(clearance > 0, fmt::format("contact[{}].position", k), Show(ck.spec.position),
                    fmt::format("a positive clearance between the two sides of contact {} and {} "
                                "(c_{} = −{} c_{}; here {}): below must lie under above",
                                j, k, k, alpha, j, clearance));
        }
      }
    if (!c.empty()) return c.Take();
  }
  if (!s.contacts.empty()) {
    // Every gap of the initial state (the default one included) open or closed, never violated.
    const auto init = sys.Initial(s);
    for (int j = 0; j < sys.contact_count(); ++j) {
      const ContactModel& k = sys.contacts()[static_cast<size_t>(j)];
      const double g = k.shape.dot(init.X) - k.stop;
      const double scale = std::abs(k.stop) + k.shape.cwiseProduct(init.X).cwiseAbs().sum();
      const double tol = System::kStopUlps * std::numeric_limits<double>::epsilon() * scale;
      const double below = 1e-12 * std::max(1.0, std::abs(k.stop));
      c.Require(g >= -below, has_x ? "initial.displacement" : fmt::format("contact[{}].position", j),
                has_x ? Show(s.initial_displacement) : Show(k.spec.position),
                fmt::format("admissible initial state: the gap of contact {} is {} < 0{}", j, g,
                            has_x ? "" : " at the default state (give initial.displacement and "
                                         "initial.velocity)"));
      if (has_v && g <= tol && g >= -below && !k.spec.compliance.compliant()) {
        const double v = k.shape.dot(init.V);
        c.Require(v >= -System::kStopUlps * std::numeric_limits<double>::epsilon() *
                           k.shape.cwiseProduct(init.V).cwiseAbs().sum(),
                  "initial.velocity", Show(s.initial_velocity),
                  fmt::format("admissible initial state: on contact {} its gap velocity must not "
                              "point into it ({} < 0)",
                              j, v));
      }
    }
    return c.Take();
  }
  if (has_x && has_v) {
    const auto init = sys.Initial(s);
    const double xB = sys.ContactDisplacement(init.X);
    const double vB = sys.ContactVelocity(init.V);
    const double x0 = s.stop_position;
    // Initial() has taken a state within rounding of the stop onto it, and at rest there
    // (System::StopTolerance, RestTolerance; docs/scenes.md).
    const double below = sys.BelowStopTolerance();
    c.Require(xB >= x0 - below, "initial.displacement", Show(s.initial_displacement),
              fmt::format("admissible initial state x_B ≥ x0 (x_B = {}, x0 = {})", xB, x0));
    // A compliant stop takes a body arriving on it (its contact phase begins at t0).
    if (xB - x0 <= sys.StopTolerance(init.X) && xB >= x0 - below && !s.stop_compliance.compliant())
      c.Require(vB >= -sys.RestTolerance(init.V), "initial.velocity", Show(s.initial_velocity),
                fmt::format("admissible initial state: on the stop (x_B = x0) the contact "
                            "velocity must not point into it (ẋ_B = {} < 0)",
                            vB));
  }
  return c.Take();
}

std::vector<ContactSpec> Contacts(const Scene& scene) {
  if (!scene.contacts.empty()) return scene.contacts;
  if (!scene.physical) return {};
  ContactSpec k{scene.physical->contact_dof, -1, Side::kBelow, scene.stop_position, scene.restitution};
  k.compliance = scene.stop_compliance;
  return {k};
}

bool HasCompliantContact(const Scene& scene) {
  if (scene.stop_compliance.compliant()) return true;
  for (const ContactSpec& k : scene.contacts)
    if (k.compliance.compliant()) return true;
  return false;
}

const char* ToString(Side s) { return s == Side::kBelow ? "below" : "above"; }
const char* ToString(Separation s) { return s == Separation::kGap ? "gap" : "force"; }

const char* ToString(Engine e) { return e == Engine::kExact ? "exact" : "cvode"; }
const char* ToString(ChatterTreatment c) {
  switch (c) {
    case ChatterTreatment::kAccumulation: return "accumulation";
    case ChatterTreatment::kThreshold: return "threshold";
    case ChatterTreatment::kNone: return "none";
  }
  return "?";
}
const char* ToString(CvodeMethod m) { return m == CvodeMethod::kAdams ? "adams" : "bdf"; }
const char* ToString(Precision p) { return p == Precision::kDouble ? "double" : "quad"; }

double ChatterTolerance(const RunSpec& run) {
  if (run.chatter_tolerance > 0) return run.chatter_tolerance;
  return run.precision == Precision::kQuad ? 1e-28 : 1e-12;
}

}  // namespace vibro
