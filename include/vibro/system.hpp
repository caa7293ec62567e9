// System: the immutable structural model of a scene in the paper's modal scaling (docs/model.md §1.3),
// the stop, the excitation and the constrained (sticking) modes (docs/model.md §4.2). Built once, shared
// by const& across engines and threads.
//
// Modal state: X, Ẋ ∈ ℝⁿ. The contact coordinate is x_B = cᵀX, where c_i = 1 for a mode seen by
// the contact (ψ_i(B) = 1, T_B,i = 1/m_i > 0) and c_i = 0 for a mode with a node at B, which is
// kept in the response but out of the contact model (docs/model.md §1.3 step 4; such a mode is mass
// normalised and has T_B,i = 0). In the modal form every mode has c_i = 1, so x_B = 1ᵀX as in
// docs/model.md; every formula of docs/model.md holds with 1 replaced by c.
#pragma once

#include <optional>
#include <vector>

#include <Eigen/Dense>

#include "vibro/harmonics.hpp"
#include "vibro/scene.hpp"

namespace vibro {

// Modes of the structure held at B (docs/model.md §4.2): A = Ω − T_B (c∘w2)ᵀ/s_B has the spectrum
// {0} ∪ {ω'_k²}. X(t) = x0·static_shape + Σ_k vectors.col(k) ξ_k(t) while sticking, with
// ξ̈_k + ω'_k² ξ_k = modal_forcing_k f sin ωt (undamped).
struct ConstrainedModes {
  Eigen::VectorXd frequencies;    // ω'_k, ascending, shape (n−1)
  Eigen::MatrixXd vectors;        // right eigenvectors v_k of A (columns), shape (n, n−1)
  Eigen::MatrixXd left;           // rows l_kᵀ with l_kᵀ v_j = δ_kj, l_kᵀ v_0 = 0, shape (n−1, n)
  Eigen::VectorXd modal_forcing;  // l_kᵀ F_c, F_c = T_A − (s_A/s_B) T_B, shape (n−1)
  Eigen::VectorXd reaction;       // ρ_k = (c∘w2)ᵀ v_k / s_B: R = R_static + ρᵀξ − (s_A/s_B) f sin ωt
  // ξ̈ + damping ξ̇ + diag(ω'²) ξ = modal_forcing f sin ωt when modal damping is present
  // (docs/model.md §7: damping = L Π D V, the projected damping in the constrained modes), shape
  // (n−1, n−1); zero when undamped.
  Eigen::MatrixXd damping;
};

// One contact of the model (docs/contacts.md): its gap g_j = c_jᵀX − e_j ≥ 0 in the modal
// coordinates of the System (MODEL (M2): c_j = σ_j Ψᵀw_j, e_j = σ_j d_j), T_j = μ⁻¹c_j the modal
// projection of a unit contact force, and what sticking on it alone needs: the constrained modes
// with contact j held (docs/model.md §4.2 with c → c_j). Contact 0 is the contact the modes are
// scaled to (unit c_0 on every mode it sees), so that for one contact every formula is the single
// stop's.
struct ContactModel {
  ContactSpec spec;             // as written (modal form: dof = partner = −1; [stop]: side below)
  Eigen::VectorXd shape;        // c_j, (n)
  Eigen::VectorXd contact;      // T_j, (n)
  double stop = 0;              // e_j: the contact is closed at c_jᵀX = e_j
  double restitution = 0;       // r_j
  double s_A = 0;               // c_jᵀT_A
  double s_B = 0;               // W_jj = c_jᵀT_j = 1/(effective mass of contact j)
  double flexibility = 0;       // Σ c_j,i T_j,i / ω_i²
  Eigen::VectorXd static_shape; // v0/(c_jᵀv0), v0 = Ω⁻¹T_j: at rest on contact j at e_j = 1
  ConstrainedModes constrained;
};

// Sticking on a set S of two or more contacts at once (docs/contacts.md, "Sticking on several
// contacts"): on {g_j = ġ_j = 0, j ∈ S} the state is X = base + vectors·y with
// ÿ_k + damping ẏ + ν_k² y_k = modal_forcing_k f sin ωt, y = left·(X − base), and the contact
// forces are λ = reaction_static + reaction·y + reaction_velocity·ẏ − reaction_forcing f sin ωt
// (rows in the order of `set`). `vectors` are orthonormal in the modal masses of the scaling, so `left` = Vᵀμ.
struct HeldSetModes {
  std::vector<int> set;            // the held contacts, ascending
  Eigen::VectorXd base;            // X_p: on every stop of S, the static response to the forces
  Eigen::VectorXd frequencies;     // ν_k, ascending, (n − |S|)
  Eigen::MatrixXd vectors;         // V, (n, n − |S|)
  Eigen::MatrixXd left;            // Vᵀμ, (n − |S|, n)
  Eigen::VectorXd modal_forcing;   // Vᵀμ T_A, (n − |S|)
  Eigen::VectorXd reaction_static;   // W_SS⁻¹ e_S-part: λ at y = 0 without forcing, (|S|)
  Eigen::MatrixXd reaction;          // W_SS⁻¹ C_S Ω V, (|S|, n − |S|)
  Eigen::VectorXd reaction_forcing;  // W_SS⁻¹ C_S T_A, (|S|)
  Eigen::MatrixXd reaction_velocity;  // W_SS⁻¹ C_S D V: damped, λ gains reaction_velocity·ẏ
  Eigen::MatrixXd damping;         // VᵀμDV, (n − |S|)²: zero when undamped
};

class System {
 public:
  // Builds the model of a scene. Precondition: Validate(scene) is empty (throws
  // std::invalid_argument naming the first problem otherwise).
  explicit System(const Scene& scene);

  // Indices of the `keep` lowest frequencies (all when keep <= 0) in ascending order of frequency:
  // the modes a scene keeps (structure.modes), as indices into its lists.
  static std::vector<int> KeptModes(const Eigen::VectorXd& omega, int keep);

  int dof() const { return static_cast<int>(omega_.size()); }  // n, modes in the model
  bool physical() const { return physical_; }

  const Eigen::VectorXd& omega() const { return omega_; }           // ω_i, (n)
  const Eigen::VectorXd& forcing() const { return forcing_; }       // T_A,i, (n)
  const Eigen::VectorXd& contact() const { return contact_; }       // T_B,i ≥ 0, (n)
  const Eigen::VectorXd& contact_shape() const { return shape_; }   // c_i ∈ {0, 1}, (n)
  const Eigen::VectorXd& damping() const { return zeta_; }          // ζ_i ∈ [0, 1), (n)
  bool damped() const { return damped_; }
  double s_A() const { return s_A_; }  // cᵀT_A
  double s_B() const { return s_B_; }  // cᵀT_B = 1/(effective mass at B) > 0

  double stop() const { return x0_; }              // x0
  double restitution() const { return r_; }       // r ∈ [0, 1]
  double amplitude() const { return f_; }          // f
  double frequency() const { return w_; }          // ω
  double period() const { return period_; }        // T = 2π/ω

  // Static flexibility at B: Σ c_i T_B,i / ω_i² = (K⁻¹)_BB.
  double flexibility() const { return flexibility_; }
  // Reaction in the static pressed equilibrium x0/flexibility (x0 ≥ 0), nullopt for clearance.
  std::optional<double> static_reaction() const;
  // Static equilibrium on the stop: X = x0 · static_shape(), static_shape = v0/(cᵀv0), v0 = Ω⁻¹T_B.
  const Eigen::VectorXd& static_shape() const { return static_shape_; }

  const ConstrainedModes& constrained() const { return constrained_; }

  // The m contacts, in scene order (contact 0 is the one the accessors above describe).
  int contact_count() const { return static_cast<int>(contacts_.size()); }
  const std::vector<ContactModel>& contacts() const { return contacts_; }
  // Delassus matrix W_jk = c_jᵀT_k (MODEL §11.1.3), (m, m).
  const Eigen::MatrixXd& delassus() const { return delassus_; }

  // The flow held on the contacts of `set` (two or more, independent; MODEL (S1)–(S2) in
  // docs/contacts_reference.md). Throws std::invalid_argument for dependent contacts.
  HeldSetModes HeldOn(const std::vector<int>& set) const;

  // The forcing as a sum of harmonics (docs/harmonics.md), one entry per harmonic: today's forcing
  // is one (n = 1, ψ = 0, T_A^(0) = forcing()), and harmonic_sum() is false for it, so that the
  // engines keep their single-harmonic closed forms to the bit. With a sum, frequency() is the base
  // pulsation ω_b, period() the common period and amplitude() f_0.
  const std::vector<Harmonic>& harmonics() const { return harmonics_; }
  bool harmonic_sum() const { return harmonic_sum_; }
  // Contact j under harmonic h: s_A,j^(h) = c_jᵀT_A^(h) and, sticking on j alone, the constrained
  // modal forcing l_kᵀF_c^(h), F_c^(h) = T_A^(h) − (s_A,j^(h)/W_jj) T_j (docs/model.md §4.2).
  double HarmonicSA(int j, int h) const { return harmonic_s_A_[static_cast<size_t>(j)][static_cast<size_t>(h)]; }
  const Eigen::VectorXd& HarmonicStickForcing(int j, int h) const {
    return harmonic_stick_[static_cast<size_t>(j)][static_cast<size_t>(h)];
  }

  // The d-th time derivative of the forcing at base phase φ: modal, Σ_h T_A^(h) f_h ω_h^d sin(φ_h + dπ/2)
  // with φ_h = n_h φ + ψ_h; and as contact j sees it (c_jᵀ of it). Every harmonic, sum or not.
  Eigen::VectorXd HarmonicForce(double phase, int d) const;
  double HarmonicContactForce(int j, double phase, int d) const;

  // Physical form only: mode shapes ψ_i (columns, unit component at B for contact modes), (N, n).
  const Eigen::MatrixXd& mode_shapes() const { return mode_shapes_; }
  // Physical form only: modal masses m_i = ψ_iᵀ M ψ_i, (n).
  const Eigen::VectorXd& modal_masses() const { return modal_masses_; }

  double ContactDisplacement(const Eigen::VectorXd& X) const { return shape_.dot(X); }
  double ContactVelocity(const Eigen::VectorXd& V) const { return shape_.dot(V); }
  // Contact reaction (the paper's eq. 5 with the damping term of §7) for a state on the stop:
  // R = (Σ c_i(ω_i² X_i + 2ζ_iω_i Ẋ_i) − s_A f sin φ)/s_B, φ = ωt.
  double Reaction(const Eigen::VectorXd& X, const Eigen::VectorXd& V, double phase) const;
  // The reaction of contact j held alone (the same formula with c → c_j, T_A → s_A,j, s_B → W_jj;
  // docs/contacts.md); j = 0 is Reaction.
  double ContactReaction(int j, const Eigen::VectorXd& X, const Eigen::VectorXd& V, double phase) const;
  // Rate Ṙ along the sticking flow (docs/model.md §4.2, with the damped constrained acceleration of §7).
  double ReactionRate(const Eigen::VectorXd& X, const Eigen::VectorXd& V, double phase) const;
  // Free acceleration of B: ẍ_B = −s_B R for the same state (docs/model.md §2).
  double FreeContactAcceleration(const Eigen::VectorXd& X, const Eigen::VectorXd& V,
                                 double phase) const {
    return -s_B_ * Reaction(X, V, phase);
  }
  // Restitution law (the paper's eq. 12): Ẋ⁺ = Ẋ⁻ + p T_B, p = −(1+r) ẋ_B⁻/s_B.
  void ApplyImpact(Eigen::VectorXd& V, double restitution) const;
  // Plastic projection onto the stop (docs/model.md §4.4): Ẋ ← Ẋ − T_B(cᵀẊ)/s_B and
  // X ← X − T_B(cᵀX − x0)/s_B, so that x_B = x0 and ẋ_B = 0 hold to rounding.
  void ProjectOntoStop(Eigen::VectorXd& X, Eigen::VectorXd& V) const;

  // Modal coordinates of a physical state (physical form): X_i = ψ_iᵀ M q / m_i.
  Eigen::VectorXd ModalFromPhysical(const Eigen::VectorXd& q) const;
  // The scene's initial state in modal coordinates (default: static equilibrium for x0 > 0, else
  // the origin); `sticking` is true when the state starts in contact with R > 0.
  struct InitialState {
    double time;
    Eigen::VectorXd X, V;
    bool sticking;
  };
  InitialState Initial(const Scene& scene) const;
  // Which tolerance decides "on the stop" for an initial state (docs/scenes.md): a state within
  // rounding of the stop is on it. Rounding of x_B = Σ c_i X_i (and of a physical-to-modal
  // conversion before it) is a few ulps of its terms, so
  //   displacement: 0 < x_B − x0 ≤ kStopUlps·ε·(|x0| + Σ|c_i X_i|)  → projected onto the stop,
  //   velocity, on the stop: |ẋ_B| ≤ kStopUlps·ε·Σ|c_i Ẋ_i|          → projected to rest (ẋ_B ≤ 0),
  // "on the stop" meaning x_B − x0 in [−BelowStopTolerance(), StopTolerance(X)].
  // Initial() applies both to the default and to a given state; beyond them a state keeps its
  // values (a gap above, a contact velocity into the stop, which the scene's check refuses).
  static constexpr double kStopUlps = 32;
  double StopTolerance(const Eigen::VectorXd& X) const;
  double RestTolerance(const Eigen::VectorXd& V) const;
  // How far below the stop a given state may lie and still be taken as on it (1e-12 of
  // max(1, |x0|)): the engines project it onto the stop; farther below it is refused.
  double BelowStopTolerance() const;

 private:
  void BuildConstrained();
  void BuildContacts(const Scene& scene);
  Eigen::VectorXd ModalMassesOfScaling() const;

  bool physical_ = false;
  bool damped_ = false;
  Eigen::VectorXd omega_, forcing_, contact_, shape_, zeta_;
  double s_A_ = 0, s_B_ = 0;
  double x0_ = 0, r_ = 0, f_ = 0, w_ = 1, period_ = 0;
  double flexibility_ = 0;
  Eigen::VectorXd static_shape_;
  ConstrainedModes constrained_;
  Eigen::MatrixXd mode_shapes_;
  Eigen::VectorXd modal_masses_;
  Eigen::MatrixXd mass_;    // physical M (physical form), for ModalFromPhysical
  std::vector<int> kept_;   // modal form: indices of the kept modes in the scene's lists
  std::vector<ContactModel> contacts_;
  Eigen::MatrixXd delassus_;
  // system_harmonics.cpp
  void BuildHarmonics(const Scene& scene);
  std::vector<Harmonic> harmonics_;
  bool harmonic_sum_ = false;
  std::vector<std::vector<double>> harmonic_s_A_;            // [contact][harmonic]
  std::vector<std::vector<Eigen::VectorXd>> harmonic_stick_;  // [contact][harmonic]
};

}  // namespace vibro
