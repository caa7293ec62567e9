// Forcing as a sum of harmonics (docs/scenes.md, "Sums of harmonics"; docs/harmonics.md):
//   F(t) = Σ_h f_h v_h sin(ω_h t + ψ_h),   h = 0..H−1,
// v_h the forcing vector of harmonic h (the structure's forced DOF, or an explicit vector). The
// engines need one forcing phase: the frequencies must be commensurate, ω_h = n_h ω_b with whole
// multiples n_h, and the scalar phase they carry is the base phase φ = ω_b t, each harmonic's phase
// being n_h φ + ψ_h; the common period is T = 2π/ω_b.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Dense>

namespace vibro {

struct InputIssue;

// One harmonic as written in [excitation] (lists: amplitude = [...], frequency = [...],
// phase = [...], vectors = [[...], ...]).
struct HarmonicSpec {
  double amplitude = 0;    // f_h ≥ 0
  double frequency = 1;    // ω_h > 0
  double phase = 0;        // ψ_h (rad)
  // Physical form: the force on every DOF per unit amplitude (N); modal form: T_A,i per listed mode
  // (n). Empty: the structure's (e_A, or structure.forcing).
  Eigen::VectorXd vector;
};

// How commensurability is detected: ω_h/ω_0 is taken as p/q when a continued fraction with
// q ≤ kMaxDenominator matches it within kRatioTolerance (relative); the multiples n_h of the base
// pulsation ω_b = ω_0/n_0 must not exceed kMaxMultiple (the common period holds at most
// kMaxMultiple periods of the fastest harmonic).
inline constexpr int kMaxDenominator = 100;
inline constexpr int kMaxMultiple = 1000;
inline constexpr double kRatioTolerance = 1e-12;

struct CommonPeriod {
  bool commensurate = false;
  double base = 0;             // ω_b
  std::vector<int> multiples;  // n_h, gcd 1
  std::string why;             // when not commensurate: the harmonic and the ratio that failed
};
// The base pulsation of the frequencies ω_h (all > 0 and finite).
CommonPeriod FindCommonPeriod(const std::vector<double>& frequencies);

// Every violated constraint of the harmonics of a scene (keys excitation.amplitude[h] etc.);
// `forcing_size` is the length a forcing vector must have (N DOFs, or the listed modes).
std::vector<InputIssue> ValidateHarmonics(const std::vector<HarmonicSpec>& harmonics, long forcing_size);

// The forcing of a built model (System::harmonics()): one entry per harmonic.
struct Harmonic {
  double amplitude = 0;     // f_h
  double frequency = 0;     // ω_h = n_h ω_b (the base's multiple, within kRatioTolerance of the scene's)
  double phase = 0;         // ψ_h
  int multiple = 1;         // n_h
  Eigen::VectorXd forcing;  // T_A^(h): modal projection of the harmonic's unit forcing vector, (n)
};

}  // namespace vibro
