// CVODE engine (SUNDIALS 6.4). The one file of vibro that includes SUNDIALS.
//
// Free flight: y = (ΔX, Ẋ) ∈ ℝ²ⁿ with ΔX = X − X(0) the increment from the segment start, so that
// the gap g = gap(0) + cᵀΔX keeps its relative accuracy during chattering (docs/model.md §8).
//   ΔX' = Ẋ,  Ẋ' = −Ω(X(0) + ΔX) − D Ẋ + T_A f sin(φ + ωσ),   Jacobian [[0, I], [−Ω, −D]].
// Roots: g/σᵐ (direction −1) and ẋ_B/σ^(m−1) (direction +1), where m is the order of the known
// zero of g at σ = 0 (docs/model.md §2.1: after an impact 1, after a plastic departure 2, after a release 3):
// the trivial root is divided out, never skipped with a time offset, and the velocity root ends a
// step at every gap minimum so that a crossing down and back up inside one step is not missed
// (BUILD-NOTES).
// Sticking (n ≥ 2): y = (ξ, ξ̇) ∈ ℝ^{2(n−1)} in the constrained modes of docs/model.md §4.2 (the reduced
// system), ξ'' + D'ξ' + Ω'ξ = F' f sin(φ + ωσ); roots R/σᵐ (−1) and Ṙ/σ^(m−1) (+1, minima of R).
// Each segment runs in local time σ from 0 with the forcing phase reduced; both instances are
// created once and re-initialised at every mode switch.
// Several contacts (docs/contacts.md): one pair of roots per contact j, (2j, 2j + 1). Free flight:
// every gap g_j = c_jᵀX − e_j and its rate, each divided by the order of its own known zero at
// σ = 0 as above. Sticking on contact a: the pair of a is R_a and Ṙ_a in a's constrained modes;
// the pair of every other contact k is its gap under the held flow, g_k = c_kᵀ(e_a v_a + V_a ξ)
// − e_k, and its rate (a free contact hits while a sticks). The pair of a contact that cannot
// have a root (the chattering tail's own contact, a gap the held flow does not move) is constant.
// Compliant stops (docs/compliant.md): their contact phase and relaxing flight are integrated by
// CvodeCompliant at the end of this file (MakeCvodeCompliant), with the same law as the exact
// engine's closed form.
// This file is the plugin libvibro_cvode.so (cvode_api.hpp), loaded on the first CVODE run of a
// process (cvode_loader.cpp): no other process maps SUNDIALS.
#include "dynamics/cvode_api.hpp"
#include "dynamics/cvode_engine.hpp"

#include "dynamics/flight_window.hpp"
#include "dynamics/model_t.hpp"
#include "dynamics/oscillator.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <exception>
#include <functional>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <cvode/cvode.h>
#include <fmt/format.h>
#include <nvector/nvector_serial.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

namespace vibro::detail {
namespace {

std::string FlagName(long flag) {
  char* name = CVodeGetReturnFlagName(flag);
  std::string s = name ? name : fmt::format("flag {}", flag);
  std::free(name);
  return s;
}

std::string Hint(int flag) {
  switch (flag) {
    case CV_TOO_MUCH_WORK: return "raise run.max_steps or set run.max_step";
    case CV_TOO_MUCH_ACC: return "loosen run.rtol / run.atol";
    case CV_ERR_FAILURE:
    case CV_CONV_FAILURE:
      return "use run.method = \"bdf\" for stiff structures, or loosen run.rtol";
    default: return "try other tolerances, or run.engine = \"exact\"";
  }
}

}  // namespace

// One CVODE instance with everything it owns.
struct Integrator {
  void* mem = nullptr;
  N_Vector y = nullptr, tmp = nullptr;
  SUNMatrix A = nullptr;
  SUNLinearSolver LS = nullptr;
  sunindextype size = 0;

  ~Integrator() {
    if (LS) SUNLinSolFree(LS);
    if (A) SUNMatDestroy(A);
    if (y) N_VDestroy(y);
    if (tmp) N_VDestroy(tmp);
    if (mem) CVodeFree(&mem);
  }
};

struct Context {
  SUNContext ctx = nullptr;
  Context() {
    if (SUNContext_Create(nullptr, &ctx) != 0) throw std::runtime_error("SUNContext_Create failed");
  }
  ~Context() { SUNContext_Free(&ctx); }
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;
};

struct CvodeEngine::Impl {
  const System& sys;
  const RunSpec& run;
  Context context;  // destroyed after the integrators that use it
  SUNContext ctx = context.ctx;
  Integrator free, stick;
  Integrator* active = nullptr;
  SolverStats totals;
  std::string last_error;
  std::exception_ptr pending;
  // Inside one CVode call (one step): a stop request and a work limit are checked in the
  // right-hand side, because a step whose error test keeps failing (an atol of 1e-308 on the
  // stiff chain) never returns to the stepping loop of Advance.
  std::function<bool()> poll;
  long rhs_in_call = 0;                 // right-hand-side evaluations in the current CVode call
  bool stopped_in_rhs = false;          // the poll said stop
  bool overworked_in_rhs = false;       // the work limit was hit
  static constexpr long kRhsPerStep = 100000;  // a normal step needs fewer than 100
  // False when the call must end: the right-hand side then returns an unrecoverable error.
  bool MayGoOn() {
    if (++rhs_in_call > kRhsPerStep) {
      overworked_in_rhs = true;
      return false;
    }
    if ((rhs_in_call & 255) == 0 && poll && poll()) {
      stopped_in_rhs = true;
      return false;
    }
    return true;
  }

  // What the engine keeps per contact j (docs/contacts.md): its gap c_jᵀX − e_j, and sticking on
  // it alone in its constrained modes (docs/model.md §4.2 with c → c_j), with the gaps of the
  // other contacts under that held flow, g_k = held_base[k] + held_weights[k]ᵀξ.
  struct ContactData {
    explicit ContactData(ModelT<double> m) : model(std::move(m)) {}
    ModelT<double> model;  // for the flight-start jets
    Eigen::VectorXd c;     // c_j, (n)
    double stop = 0;       // e_j
    Eigen::VectorXd stick_w2, stick_F, rho, rho_v;  // (n − 1)
    Eigen::MatrixXd stick_D;                        // (n − 1, n − 1)
    double react_f = 0, R_static = 0;
    bool stick_damped = false;
    // A sum of harmonics (docs/harmonics.md): per harmonic, l_kᵀF_c^(h) f_h and s_A^(h) f_h / s_B.
    std::vector<Eigen::VectorXd> stick_hF;
    std::vector<double> react_hf;
    std::vector<Eigen::VectorXd> held_weights;  // [k]: V_jᵀc_k, (n − 1)
    std::vector<double> held_base;              // [k]: e_j c_kᵀv_j − e_k
  };
  std::vector<ContactData> contacts;
  double cap = 0;  // largest step of the certified windows (all contacts)

  // One guard pair (a gap, or the held contact's reaction) in the current segment.
  struct Guard {
    double gap0 = 0;    // value at σ = 0 (gaps: the increments from σ = 0 are added to it)
    int order = 0;      // m: order of the known zero of the guard at σ = 0
    double window = 0;  // certified root-free (0, window): the limits are used there
    double g_lim = 0, v_lim = 0;  // limits of g/σᵐ and ẋ_B/σ^(m−1) (or R, Ṙ) at σ = 0
    bool off = false;   // no root possible: constant
  };

  // Segment data.
  Mode mode = Mode::kFree;
  double phase = 0;
  Eigen::VectorXd X0, V0;
  Eigen::VectorXd xi0;               // sticking: ξ at σ = 0
  int held = 0;                      // sticking: the held contact; free flight: the start contact
  const ContactData* hd = nullptr;   // contacts[held]
  std::vector<Guard> guards;         // one per contact
  std::string inadmissible;  // non-empty: the start is below a stop (Advance fails with it)
  int immediate = -1;        // a contact closing at σ = 0 (on its stop, moving into it)
  bool guards_off = false;   // Advance without events (an accumulation jump): no root finding
  double atol = 0;           // absolute tolerance of the current free flight

  // Model data common to every contact.
  Eigen::VectorXd w2, damp, TA_f;
  // A sum of harmonics (docs/harmonics.md): T_A^(h) f_h, ω_h, n_h, ψ_h; empty for one harmonic.
  std::vector<Eigen::VectorXd> h_TA;
  std::vector<double> h_w, h_psi;
  std::vector<int> h_n;
  // ω_h^d sin(φ_h(σ) + dπ/2) of harmonic h at local time t.
  double HarmonicWave(size_t h, double t, int d) const {
    const double p = h_n[h] * (phase + sys.frequency() * t) + h_psi[h];
    const double w = d == 0 ? 1.0 : d == 1 ? h_w[h] : h_w[h] * h_w[h];
    switch (d & 3) {
      case 0: return w * std::sin(p);
      case 1: return w * std::cos(p);
      default: return -w * std::sin(p);
    }
  }

  Impl(const System& s, const RunSpec& r) : sys(s), run(r) {}

  int Count() const { return static_cast<int>(contacts.size()); }

  // ---- right-hand sides, roots, Jacobians (reached through user data) ----
  static int FreeRhs(sunrealtype t, N_Vector y, N_Vector ydot, void* user) {
    auto* m = static_cast<Impl*>(user);
    if (!m->MayGoOn()) return -1;
    try {
      const auto n = m->sys.dof();
      const double* Y = N_VGetArrayPointer(y);
      double* D = N_VGetArrayPointer(ydot);
      const double s = std::sin(m->phase + m->sys.frequency() * t);
      for (int i = 0; i < n; ++i) {
        D[i] = Y[n + i];
        D[n + i] = -m->w2[i] * (m->X0[i] + Y[i]) - m->damp[i] * Y[n + i] + m->TA_f[i] * s;
      }
      for (size_t h = 0; h < m->h_TA.size(); ++h) {
        const double sh = m->HarmonicWave(h, t, 0);
        for (int i = 0; i < n; ++i) D[n + i] += m->h_TA[h][i] * sh;
      }
      return 0;
    } catch (...) {
      m->pending = std::current_exception();
      return -1;
    }
  }

  // Gap of contact j and its rate in free flight, from the increments y = (ΔX, Ẋ).
  void FreeGap(int j, const double* Y, double& gap, double& vB) const {
    const auto n = sys.dof();
    const Eigen::VectorXd& c = contacts[static_cast<size_t>(j)].c;
    gap = guards[static_cast<size_t>(j)].gap0;
    vB = 0;
    for (int i = 0; i < n; ++i) {
      gap += c[i] * Y[i];
      vB += c[i] * Y[n + i];
    }
  }

  static int FreeRoots(sunrealtype t, N_Vector y, sunrealtype* g, void* user) {
    auto* m = static_cast<Impl*>(user);
    const double* Y = N_VGetArrayPointer(y);
    for (int j = 0; j < m->Count(); ++j) {
      const Guard& gd = m->guards[static_cast<size_t>(j)];
      double gap = 1.0, vB = 1.0;
      if (!gd.off) m->FreeGap(j, Y, gap, vB);
      if (vB == 0 && m->Count() > 1) vB = m->OffZero(m->FreeGapAcceleration(j, t, Y));
      m->DividedRoots(gd, t, gap, vB, g + 2 * j);
    }
    return 0;
  }

  // Several contacts: a gap rate that rounds to exactly 0 takes the sign of the gap acceleration.
  // The rate roots of two contacts on one line (c_k = −c_j, a two-sided stop) cross together at
  // every apex, where CVODE returns for the one whose gap has a minimum; near a chattering
  // contact that rate changes by less than its rounding over CVODE's root tolerance, and a rate
  // that is exactly 0 at the root and just after it is refused as a root "at and very near" the
  // step's start. The sign of the next derivative is the side the rate takes just after.
  static double OffZero(double acceleration) {
    return acceleration == 0 ? 0.0 : std::copysign(1e-150, acceleration);
  }
  double FreeGapAcceleration(int j, double t, const double* Y) const {
    const auto n = sys.dof();
    const Eigen::VectorXd& c = contacts[static_cast<size_t>(j)].c;
    const double s = std::sin(phase + sys.frequency() * t);
    double a = 0;
    for (int i = 0; i < n; ++i) a += c[i] * (-w2[i] * (X0[i] + Y[i]) - damp[i] * Y[n + i] + TA_f[i] * s);
    for (size_t h = 0; h < h_TA.size(); ++h) a += c.dot(h_TA[h]) * HarmonicWave(h, t, 0);
    return a;
  }

  // Guard value/σᵐ and rate/σ^(m−1), m = order of the known zero at σ = 0. Inside the certified
  // window (docs/model.md §2.1) no root exists: the divided functions are their positive limits there,
  // free of the rounding of value/σᵐ at tiny σ.
  void DividedRoots(const Guard& gd, double t, double value, double rate, sunrealtype* g) const {
    if (guards_off || gd.off) {  // constant guards: CVODE sees no root (and none "at and very near" t0)
      g[0] = g[1] = 1.0;
    } else if (gd.order > 0 && t <= gd.window) {
      g[0] = gd.g_lim;
      g[1] = gd.order <= 1 ? rate : gd.v_lim;
    } else if (gd.order == 0) {
      g[0] = value;
      g[1] = rate;
    } else {
      g[0] = value / std::pow(t, gd.order);
      g[1] = gd.order <= 1 ? rate : rate / std::pow(t, gd.order - 1);
    }
    g[0] = AwayFromUnderflow(g[0]);
    g[1] = AwayFromUnderflow(g[1]);
  }

  // CVODE sees a sign change through the product g(t_lo)·g(t_hi), which underflows to −0 when
  // both are tiny (a start leaving the stop at ẋ_B = 5e-324 then falling back): the crossing
  // would be missed and the body pass through the stop. Magnitudes below 1e-150 keep their
  // sign and are raised to 1e-150, whose products stay normal numbers.
  static double AwayFromUnderflow(double g) {
    constexpr double kFloor = 1e-150;
    return g != 0 && std::abs(g) < kFloor ? std::copysign(kFloor, g) : g;
  }

  static int FreeJac(sunrealtype, N_Vector, N_Vector, SUNMatrix J, void* user, N_Vector, N_Vector,
                     N_Vector) {
    auto* m = static_cast<Impl*>(user);
    const auto n = m->sys.dof();
    SUNMatZero(J);
    for (int i = 0; i < n; ++i) {
      SM_ELEMENT_D(J, i, n + i) = 1.0;
      SM_ELEMENT_D(J, n + i, i) = -m->w2[i];
      SM_ELEMENT_D(J, n + i, n + i) = -m->damp[i];
    }
    return 0;
  }

  void StickAcc(double t, const double* Y, double* acc) const {
    const auto k = hd->stick_w2.size();
    const double s = std::sin(phase + sys.frequency() * t);
    for (Eigen::Index i = 0; i < k; ++i) {
      double a = -hd->stick_w2[i] * Y[i] + hd->stick_F[i] * s;
      for (size_t h = 0; h < hd->stick_hF.size(); ++h) a += hd->stick_hF[h][i] * HarmonicWave(h, t, 0);
      if (hd->stick_damped)
        for (Eigen::Index j = 0; j < k; ++j) a -= hd->stick_D(i, j) * Y[k + j];
      acc[i] = a;
    }
  }

  static int StickRhs(sunrealtype t, N_Vector y, N_Vector ydot, void* user) {
    auto* m = static_cast<Impl*>(user);
    if (!m->MayGoOn()) return -1;
    try {
      const auto k = m->hd->stick_w2.size();
      const double* Y = N_VGetArrayPointer(y);
      double* D = N_VGetArrayPointer(ydot);
      for (Eigen::Index i = 0; i < k; ++i) D[i] = Y[k + i];
      m->StickAcc(t, Y, D + k);
      if (k == 0) D[0] = 0.0;  // one DOF: the placeholder unknown (see the constructor)
      return 0;
    } catch (...) {
      m->pending = std::current_exception();
      return -1;
    }
  }

  // R = R_st + ρᵀξ + ρ_vᵀξ̇ − (s_A/s_B) f sin, Ṙ = ρᵀξ̇ + ρ_vᵀξ̈ − (s_A/s_B) f ω cos.
  void Reaction(double t, const double* Y, double& R, double& dR) const {
    const auto k = hd->stick_w2.size();
    const double w = sys.frequency();
    R = hd->R_static - hd->react_f * std::sin(phase + w * t);
    dR = -hd->react_f * w * std::cos(phase + w * t);
    for (size_t h = 0; h < hd->react_hf.size(); ++h) {
      R -= hd->react_hf[h] * HarmonicWave(h, t, 0);
      dR -= hd->react_hf[h] * HarmonicWave(h, t, 1);
    }
    std::vector<double> acc(static_cast<size_t>(k));
    StickAcc(t, Y, acc.data());
    for (Eigen::Index i = 0; i < k; ++i) {
      R += hd->rho[i] * Y[i] + hd->rho_v[i] * Y[k + i];
      dR += hd->rho[i] * Y[k + i] + hd->rho_v[i] * acc[static_cast<size_t>(i)];
    }
  }

  // R̈ = ρᵀξ̈ + ρ_vᵀξ⃛ + (s_A/s_B) f ω² sin, ξ⃛ = −Ω'ξ̇ − D'ξ̈ + F' f ω cos.
  double ReactionCurvature(double t, const double* Y) const {
    const auto k = hd->stick_w2.size();
    const double w = sys.frequency();
    std::vector<double> acc(static_cast<size_t>(k));
    StickAcc(t, Y, acc.data());
    double d2R = hd->react_f * w * w * std::sin(phase + w * t);
    for (size_t h = 0; h < hd->react_hf.size(); ++h) d2R -= hd->react_hf[h] * HarmonicWave(h, t, 2);
    for (Eigen::Index i = 0; i < k; ++i) {
      double jerk = -hd->stick_w2[i] * Y[k + i] + hd->stick_F[i] * w * std::cos(phase + w * t);
      for (size_t h = 0; h < hd->stick_hF.size(); ++h) jerk += hd->stick_hF[h][i] * HarmonicWave(h, t, 1);
      for (Eigen::Index j = 0; j < k; ++j) jerk -= hd->stick_D(i, j) * acc[static_cast<size_t>(j)];
      d2R += hd->rho[i] * acc[static_cast<size_t>(i)] + hd->rho_v[i] * jerk;
    }
    return d2R;
  }

  // Gap of contact j (not held) under the held flow and its rate: the start value plus the
  // increments wᵀ(ξ − ξ(0)), so that a gap starting at its known zero is 0 there.
  void HeldGap(int j, const double* Y, double& gap, double& rate) const {
    const Eigen::VectorXd& w = hd->held_weights[static_cast<size_t>(j)];
    const auto k = w.size();
    gap = guards[static_cast<size_t>(j)].gap0;
    rate = 0;
    for (Eigen::Index q = 0; q < k; ++q) {
      gap += w[q] * (Y[q] - xi0[q]);
      rate += w[q] * Y[k + q];
    }
  }

  double HeldGapAcceleration(int j, double t, const double* Y) const {
    const Eigen::VectorXd& w = hd->held_weights[static_cast<size_t>(j)];
    std::vector<double> acc(static_cast<size_t>(w.size()));
    StickAcc(t, Y, acc.data());
    double a = 0;
    for (Eigen::Index q = 0; q < w.size(); ++q) a += w[q] * acc[static_cast<size_t>(q)];
    return a;
  }

  static int StickRoots(sunrealtype t, N_Vector y, sunrealtype* g, void* user) {
    auto* m = static_cast<Impl*>(user);
    const double* Y = N_VGetArrayPointer(y);
    double R, dR;
    m->Reaction(t, Y, R, dR);
    m->DividedRoots(m->guards[static_cast<size_t>(m->held)], t, R, dR, g + 2 * m->held);
    for (int j = 0; j < m->Count(); ++j) {
      if (j == m->held) continue;
      const Guard& gd = m->guards[static_cast<size_t>(j)];
      double gap = 1.0, rate = 1.0;
      if (!gd.off) m->HeldGap(j, Y, gap, rate);
      if (rate == 0) rate = OffZero(m->HeldGapAcceleration(j, t, Y));
      m->DividedRoots(gd, t, gap, rate, g + 2 * j);
    }
    return 0;
  }

  static int StickJac(sunrealtype, N_Vector, N_Vector, SUNMatrix J, void* user, N_Vector, N_Vector,
                      N_Vector) {
    auto* m = static_cast<Impl*>(user);
    const auto k = m->hd->stick_w2.size();
    SUNMatZero(J);
    for (Eigen::Index i = 0; i < k; ++i) {
      SM_ELEMENT_D(J, i, k + i) = 1.0;
      SM_ELEMENT_D(J, k + i, i) = -m->hd->stick_w2[i];
      for (Eigen::Index j = 0; j < k; ++j) SM_ELEMENT_D(J, k + i, k + j) = -m->hd->stick_D(i, j);
    }
    return 0;
  }

  static void ErrHandler(int, const char* module, const char* function, char* msg, void* user) {
    auto* m = static_cast<Impl*>(user);
    m->last_error = fmt::format("{}/{}: {}", module ? module : "", function ? function : "",
                                msg ? msg : "");
  }

  void Create(Integrator& in, sunindextype size, CVRhsFn rhs, CVRootFn roots, CVLsJacFn jac) {
    in.size = size;
    in.y = N_VNew_Serial(size, ctx);
    in.tmp = N_VNew_Serial(size, ctx);
    N_VConst(0.0, in.y);
    in.mem = CVodeCreate(run.method == CvodeMethod::kBdf ? CV_BDF : CV_ADAMS, ctx);
    if (!in.y || !in.tmp || !in.mem) throw std::runtime_error("CVODE: allocation failed");
    CVodeSetErrHandlerFn(in.mem, &Impl::ErrHandler, this);
    if (CVodeInit(in.mem, rhs, 0.0, in.y) < 0) throw std::runtime_error("CVodeInit failed");
    CVodeSetUserData(in.mem, this);
    CVodeSStolerances(in.mem, run.rtol, run.atol);
    in.A = SUNDenseMatrix(size, size, ctx);
    in.LS = SUNLinSol_Dense(in.y, in.A, ctx);
    if (CVodeSetLinearSolver(in.mem, in.LS, in.A) < 0) throw std::runtime_error("CVODE linear solver");
    CVodeSetJacFn(in.mem, jac);
    // Per contact, the value (direction −1) and the rate (+1: a minimum that did not cross ends a
    // step, so that a crossing down and back up inside one step is not missed).
    const int count = 2 * Count();
    CVodeRootInit(in.mem, count, roots);
    std::vector<int> dirs(static_cast<size_t>(count));
    for (size_t i = 0; i < dirs.size(); ++i) dirs[i] = i % 2 == 0 ? -1 : +1;
    CVodeSetRootDirection(in.mem, dirs.data());
    CVodeSetNoInactiveRootWarn(in.mem);
    if (run.max_step > 0) CVodeSetMaxStep(in.mem, run.max_step);
    CVodeSetMaxNumSteps(in.mem, run.max_steps);
  }

  void Collect(Integrator& in) {
    long v = 0;
    if (CVodeGetNumSteps(in.mem, &v) == CV_SUCCESS) totals.steps += v;
    if (CVodeGetNumRhsEvals(in.mem, &v) == CV_SUCCESS) totals.rhs_evals += v;
    if (CVodeGetNumGEvals(in.mem, &v) == CV_SUCCESS) totals.root_evals += v;
    if (CVodeGetNumJacEvals(in.mem, &v) == CV_SUCCESS) totals.jac_evals += v;
    if (CVodeGetNumErrTestFails(in.mem, &v) == CV_SUCCESS) totals.error_test_failures += v;
  }

  // The start of the gap guard of contact j, of value `gap` and derivatives `jet` at σ = 0
  // (docs/model.md §2.1): the known zero of a flight start is divided out. A generic start on the
  // stop (or rounded below it) gets the order of its first non-zero derivative like after an
  // impact, a departure or a release, or closes at once when it moves into the stop: CVODE ignores
  // a root function that is zero at t0, so a state leaving the stop by a hair (ẋ_B = 5e-324) and
  // falling back would pass through the wall unseen (BUILD-NOTES: the start must be admissible).
  void StartGuard(int j, FlightStart start, double gap, const FlightJet& jet) {
    Guard& gd = guards[static_cast<size_t>(j)];
    gd.gap0 = gap;
    gd.order = static_cast<int>(start);  // kGeneric 0, kAfterImpact 1, kDeparture 2, kAfterRelease 3
    bool closes = false;
    if (gd.order == 0 && gap <= 0) {
      const double stop = contacts[static_cast<size_t>(j)].stop;
      const double tol = 1e-12 * std::max(1.0, std::abs(stop));
      if (gap < -tol) {
        if (inadmissible.empty())
          inadmissible = Count() == 1
                             ? fmt::format("start below the stop (x_B − x0 = {:.3g} < 0): not an "
                                           "admissible state of the impact oscillator",
                                           gap)
                             : fmt::format("start below the stop of contact {} (gap {:.3g} < 0): not "
                                           "an admissible state of the impact oscillator",
                                           j, gap);
      } else {
        const double d[3] = {jet.g1, jet.g2, jet.g3};
        int k = 0;
        while (k < 3 && d[k] == 0) ++k;
        if (k == 3 || d[k] < 0) {
          closes = true;
        } else {
          gd.order = k + 1;
          gd.gap0 = 0.0;
        }
      }
    }
    gd.window = CertifiedWindow(static_cast<FlightStart>(gd.order), jet, cap);
    // Leaving the stop so slowly that the flight (≈ 2g'/|g''|) is shorter than the clock can
    // resolve: a touch at σ = 0, as the exact engine finds it. Integrating it instead would end in
    // impacts at speeds of order 1e-300 that never reach the chattering treatment.
    if (gd.order == 1 && jet.g2 < 0 &&
        2 * jet.g1 / -jet.g2 <= 4 * std::numeric_limits<double>::epsilon() * sys.period())
      closes = true;
    if (closes && immediate < 0) immediate = j;
    switch (gd.order) {
      case 1: gd.g_lim = jet.g1; gd.v_lim = jet.g1; break;
      case 2: gd.g_lim = jet.g2 / 2; gd.v_lim = jet.g2; break;
      case 3: gd.g_lim = jet.g3 / 6; gd.v_lim = jet.g3 / 2; break;
      default: break;
    }
  }

  // Derivatives at σ = 0 of the gap of contact j under the held flow (Y: ξ, ξ̇ at σ = 0), with
  // bounds of its third and fourth derivatives over [0, cap] from the amplitudes of the undamped
  // constrained modes (docs/model.md §2.1). `certified` is false for a damped held flow, whose
  // coupled modes have no such bound at hand.
  FlightJet HeldJet(int j, const double* Y, bool& certified) const {
    const Eigen::VectorXd& w = hd->held_weights[static_cast<size_t>(j)];
    const auto k = w.size();
    std::vector<double> acc(static_cast<size_t>(k));
    StickAcc(0.0, Y, acc.data());
    FlightJet jet{0, 0, 0, 0, 0};
    const double fw = sys.frequency(), cp = std::cos(phase);
    for (Eigen::Index q = 0; q < k; ++q) {
      const OscillatorT<double> o{std::sqrt(hd->stick_w2[q]), 0.0, hd->stick_F[q]};
      jet.g1 += w[q] * Y[k + q];
      jet.g2 += w[q] * acc[static_cast<size_t>(q)];
      jet.g3 += w[q] * (-hd->stick_w2[q] * Y[k + q] + hd->stick_F[q] * fw * cp);
      for (size_t h = 0; h < hd->stick_hF.size(); ++h) jet.g3 += w[q] * hd->stick_hF[h][q] * HarmonicWave(h, 0.0, 1);
      const auto b = Bounds<double>(o, fw, Amplitude<double>(o, Y[q], Y[k + q]) + std::abs(o.F) * cap);
      jet.M3 += std::abs(w[q]) * b.d3;
      jet.M4 += std::abs(w[q]) * b.d4;
    }
    const double margin = 1 + 1e-9;  // rounding of the evaluated jets
    jet.M3 *= margin;
    jet.M4 *= margin;
    certified = !hd->stick_damped && hd->stick_hF.empty();  // a sum of harmonics: no bound at hand
    return jet;
  }
};

CvodeEngine::CvodeEngine(const System& sys, const RunSpec& run)
    : impl_(std::make_unique<Impl>(sys, run)) {
  auto& m = *impl_;
  const auto n = sys.dof();
  m.w2 = sys.omega().cwiseAbs2();
  m.damp = 2.0 * sys.damping().cwiseProduct(sys.omega());
  const double f = sys.harmonic_sum() ? 0.0 : sys.amplitude();  // a sum: its harmonics below
  m.TA_f = sys.forcing() * f;
  if (sys.harmonic_sum())
    for (const Harmonic& h : sys.harmonics()) {
      m.h_TA.push_back(h.forcing * h.amplitude);
      m.h_w.push_back(h.frequency);
      m.h_psi.push_back(h.phase);
      m.h_n.push_back(h.multiple);
    }
  // Contact 0 is the single stop, with the accessors' data (docs/contacts.md).
  const auto& all = sys.contacts();
  for (size_t j = 0; j < all.size(); ++j) {
    const ContactModel& k = all[j];
    Impl::ContactData cd(ModelT<double>(sys, k));
    cd.c = k.shape;
    cd.stop = k.stop;
    const auto& cm = k.constrained;
    cd.stick_w2 = cm.frequencies.cwiseAbs2();
    cd.stick_F = cm.modal_forcing * f;
    cd.stick_D = cm.damping;
    cd.stick_damped = cm.damping.size() > 0 && cm.damping.cwiseAbs().maxCoeff() > 0;
    cd.rho = cm.reaction;
    // Velocity part of R (docs/model.md §7): Σ c_i 2ζ_iω_i Ẋ_i / s_B with Ẋ = V ξ̇.
    cd.rho_v = cm.vectors.transpose() * (cd.c.cwiseProduct(m.damp)) / k.s_B;
    cd.react_f = k.s_A / k.s_B * f;
    if (sys.harmonic_sum())
      for (size_t h = 0; h < sys.harmonics().size(); ++h) {
        const double fh = sys.harmonics()[h].amplitude;
        cd.stick_hF.push_back(sys.HarmonicStickForcing(static_cast<int>(j), static_cast<int>(h)) * fh);
        cd.react_hf.push_back(sys.HarmonicSA(static_cast<int>(j), static_cast<int>(h)) / k.s_B * fh);
      }
    cd.R_static = k.stop / k.flexibility;
    // Gaps of the other contacts while j is held: X = e_j v_j + V_j ξ.
    cd.held_weights.resize(all.size());
    cd.held_base.resize(all.size());
    for (size_t o = 0; o < all.size(); ++o) {
      if (o == j) continue;
      cd.held_weights[o] = cm.vectors.transpose() * all[o].shape;
      cd.held_base[o] = k.stop * all[o].shape.dot(k.static_shape) - all[o].stop;
    }
    m.contacts.push_back(std::move(cd));
  }
  m.cap = StepCap<double>(m.contacts.front().model);
  for (const auto& cd : m.contacts) m.cap = std::min(m.cap, StepCap<double>(cd.model));
  m.guards.resize(m.contacts.size());
  m.hd = &m.contacts.front();
  m.Create(m.free, 2 * n, &Impl::FreeRhs, &Impl::FreeRoots, &Impl::FreeJac);
  // Sticking: the reduced system of 2(n − 1) unknowns. One DOF held on its stop has none: its
  // reaction is a function of time alone, which matters only under a sum of harmonics (one harmonic
  // rests in closed form, automaton.hpp's RestingStick; a sum's release is searched by the engine,
  // docs/harmonics.md). CVODE then integrates one placeholder unknown with ẏ = 0, so that its root
  // finding locates the release on R(σ); its steps are capped at a 32nd of the fastest period
  // (nothing else bounds them: the placeholder has no error).
  m.Create(m.stick, n >= 2 ? 2 * (n - 1) : 1, &Impl::StickRhs, &Impl::StickRoots, &Impl::StickJac);
  if (n < 2) CVodeSetMaxStep(m.stick.mem, run.max_step > 0 ? std::min(run.max_step, m.cap / 8) : m.cap / 8);
}

CvodeEngine::~CvodeEngine() = default;

void CvodeEngine::Begin(const SegmentStart& s) {
  auto& m = *impl_;
  m.mode = s.mode;
  m.phase = s.phase;
  m.held = s.contact;
  m.hd = &m.contacts[static_cast<size_t>(s.contact)];
  m.inadmissible.clear();
  m.immediate = -1;
  const int count = m.Count();
  // Every contact's start: the start contact's are `gap` and `flight_start`; with several
  // contacts the others' are `gaps` and `starts` (generic, and from the state, without them).
  const auto gap_of = [&](int j) {
    if (j == s.contact) return s.gap;
    const auto& cd = m.contacts[static_cast<size_t>(j)];
    return s.gaps ? (*s.gaps)[static_cast<size_t>(j)] : cd.c.dot(s.X) - cd.stop;
  };
  // Another contact's start kind is a known zero only while its gap is 0 (the automaton resets the
  // kind once the gap has opened): a gap divided out from a non-zero value would be tracked from 0.
  const auto start_of = [&](int j) {
    if (j == s.contact) return s.flight_start;
    const FlightStart k = s.starts ? (*s.starts)[static_cast<size_t>(j)] : FlightStart::kGeneric;
    return gap_of(j) == 0 ? k : FlightStart::kGeneric;
  };
  for (auto& gd : m.guards) gd = Impl::Guard{};
  const auto n = m.sys.dof();
  Integrator& in = s.mode == Mode::kFree ? m.free : m.stick;
  double* Y = N_VGetArrayPointer(in.y);
  if (s.mode == Mode::kFree) {
    m.X0 = s.X;
    m.V0 = s.V;
    for (int i = 0; i < n; ++i) {
      Y[i] = 0.0;
      Y[n + i] = s.V[i];
    }
    m.atol = m.run.atol;
    for (int j = 0; j < count; ++j) {
      if (j == s.skip) {
        m.guards[static_cast<size_t>(j)].off = true;
        continue;
      }
      const FlightStart start = start_of(j);
      // Limits at σ = 0 of g/σᵐ and ẋ_B/σ^(m−1): g', g''/2, g'''/6 and g', g'', g'''/2.
      const FlightJet jet = StartJet<double>(m.contacts[static_cast<size_t>(j)].model, s.X, s.V, s.phase, m.cap);
      m.StartGuard(j, start, gap_of(j), jet);
      // A flight of a chattering sequence rises only u²/(2|a|) above the stop: an absolute
      // tolerance above rtol times that height would locate its landing to δg/u at best, and the
      // accumulated landing errors would dominate the sequence (measured: 2e-9 T at rtol 1e-12).
      if (start == FlightStart::kAfterImpact && jet.g1 > 0 && jet.g2 < 0)
        m.atol = std::min(m.atol, std::clamp(m.run.rtol * jet.g1 * jet.g1 / (-2.0 * jet.g2), 1e-300,
                                             m.run.atol));
    }
  } else if (in.mem) {
    const auto& cm = m.sys.contacts()[static_cast<size_t>(s.contact)].constrained;
    const Eigen::VectorXd xi = cm.left * s.X, eta = cm.left * s.V;
    const auto k = xi.size();
    for (Eigen::Index i = 0; i < k; ++i) {
      Y[i] = xi[i];
      Y[k + i] = eta[i];
    }
    if (k == 0) Y[0] = 0.0;  // one DOF: the placeholder unknown (see the constructor)
    m.xi0 = xi;
    Impl::Guard& gd = m.guards[static_cast<size_t>(s.contact)];
    gd.order = static_cast<int>(s.stick_start);  // kGeneric 0, kRising 1, kTangent 2
    // No rigorous bound is at hand for the coupled damped sticking flow: the limits are used on
    // a short fixed window (a millionth of the period) after a rising or tangent start.
    gd.window = gd.order > 0 ? 1e-6 * m.sys.period() : 0.0;
    double R, dR;
    m.Reaction(0.0, Y, R, dR);
    if (gd.order == 1) {
      gd.g_lim = dR;
      gd.v_lim = dR;
    } else if (gd.order == 2) {
      gd.g_lim = m.ReactionCurvature(0.0, Y) / 2;
      gd.v_lim = 2 * gd.g_lim;
    }
    // The other contacts' gaps under the held flow (a free contact hits while this one sticks,
    // docs/contacts.md). A gap the held flow cannot change (zero weights, e.g. the other side of
    // a one-DOF clearance) has no root; one that starts at zero (an impact or a departure there
    // while this contact was held) divides out its known zero as a flight does. The damped held
    // flow has no bound of g''' at hand: its window is then half the first-order estimate, at
    // most a millionth of the period, like the release search's.
    for (int j = 0; j < count; ++j) {
      if (j == s.contact) continue;
      const Eigen::VectorXd& w = m.hd->held_weights[static_cast<size_t>(j)];
      Impl::Guard& gj = m.guards[static_cast<size_t>(j)];
      FlightStart start = start_of(j);
      if (start == FlightStart::kAfterRelease) start = FlightStart::kGeneric;
      // Its value at σ = 0 from the held state, g_k = e_a c_kᵀv_a − e_k + (V_aᵀc_k)ᵀξ (the
      // automaton's gaps are not kept up to date while a contact sticks), or 0 at a known zero.
      const bool known_zero = start == FlightStart::kAfterImpact || start == FlightStart::kDeparture;
      const double gap = known_zero ? 0.0 : m.hd->held_base[static_cast<size_t>(j)] + w.dot(xi);
      if (j == s.skip || w.size() == 0 || w.cwiseAbs().maxCoeff() == 0) {
        gj.off = true;
        gj.gap0 = gap;
        continue;
      }
      bool certified = false;
      FlightJet jet = m.HeldJet(j, Y, certified);
      if (!certified) jet.M3 = jet.M4 = 0;
      m.StartGuard(j, start, gap, jet);
      if (!certified && gj.order > 0) gj.window = std::min(1e-6 * m.sys.period(), 0.5 * gj.window);
    }
  }
  if (in.mem) {
    m.Collect(in);
    ++m.totals.reinits;
    CVodeReInit(in.mem, 0.0, in.y);
    CVodeSStolerances(in.mem, m.run.rtol, s.mode == Mode::kFree ? m.atol : m.run.atol);
  }
  m.active = &in;
}

SegmentResult CvodeEngine::Advance(double sigma_max, bool detect_events,
                                   const StretchCallback& on_stretch) {
  auto& m = *impl_;
  Integrator& in = *m.active;
  if (!in.mem) return {SegmentEnd::kFailure, 0.0, "no sticking integrator for one DOF"};
  if (!m.inadmissible.empty()) return {SegmentEnd::kFailure, 0.0, m.inadmissible};
  if (m.immediate >= 0 && detect_events) {
    SegmentResult now{SegmentEnd::kContact, 0.0, {}};
    now.contact = m.immediate;
    return now;
  }
  m.guards_off = !detect_events;
  CVodeSetStopTime(in.mem, sigma_max);
  double t_prev = 0.0;
  long steps = 0;
  m.poll = [this] { return StopRequested(); };
  std::vector<int> found(static_cast<size_t>(2 * m.Count()));
  while (true) {
    if (StopRequested()) {
      SegmentResult stop{SegmentEnd::kFailure, t_prev,
                         fmt::format("stop requested inside a segment (local time {:.6g})", t_prev)};
      stop.stopped = true;
      return stop;
    }
    double t = 0.0;
    m.last_error.clear();
    m.rhs_in_call = 0;
    m.stopped_in_rhs = m.overworked_in_rhs = false;
    const int flag = CVode(in.mem, sigma_max, in.y, &t, CV_ONE_STEP);
    if (m.pending) std::rethrow_exception(std::exchange(m.pending, nullptr));
    if (m.stopped_in_rhs) {
      SegmentResult stop{SegmentEnd::kFailure, t_prev,
                         fmt::format("stop requested inside a CVODE step (local time {:.6g})", t_prev)};
      stop.stopped = true;
      return stop;
    }
    if (m.overworked_in_rhs)
      return {SegmentEnd::kFailure, t_prev,
              fmt::format("CVODE made more than {} right-hand-side evaluations in one step at local "
                          "time {:.6g} without completing it (the tolerances cannot be met: raise "
                          "run.atol or run.rtol)",
                          Impl::kRhsPerStep, t_prev)};
    // A root at and very near the start of a segment: a gap vanishes to CVODE's resolution over
    // its first step, as after an impact whose speed is at the √rtol floor of a chattering
    // sequence (in free flight, or at a free contact while another sticks). Whether that contact
    // ends the sequence is not decided at this precision.
    if (flag == CV_ILL_INPUT && (m.mode == Mode::kFree || m.Count() > 1) &&
        m.last_error.find("very near") != std::string::npos) {
      SegmentResult undecided{SegmentEnd::kFailure, t_prev,
                              fmt::format("the contact after an impact is not resolved at local time {:.6g} "
                                          "(CVODE {}: {}): a chattering sequence is undetermined at this "
                                          "precision; use run.engine = \"exact\" or move the parameter",
                                          t_prev, FlagName(flag), m.last_error)};
      undecided.undetermined = true;
      return undecided;
    }
    if (flag < 0)
      return {SegmentEnd::kFailure, t_prev,
              fmt::format("CVODE {} at local time {:.6g}{}; {}", FlagName(flag), t_prev,
                          m.last_error.empty() ? "" : " (" + m.last_error + ")", Hint(flag))};
    if (++steps > m.run.max_steps)
      return {SegmentEnd::kFailure, t_prev,
              fmt::format("CVODE CV_TOO_MUCH_WORK: more than run.max_steps = {} steps in one "
                          "segment (local time {:.6g}); {}",
                          m.run.max_steps, t_prev, Hint(CV_TOO_MUCH_WORK))};
    if (on_stretch && t > t_prev) on_stretch(t_prev, t);
    t_prev = std::max(t_prev, t);
    if (flag == CV_TSTOP_RETURN || t >= sigma_max) return {SegmentEnd::kLimit, sigma_max, {}};
    if (flag == CV_ROOT_RETURN) {
      CVodeGetRootInfo(in.mem, found.data());
      // The first contact whose guard crossed; contacts closing at the same instant are gathered
      // by the automaton from their gaps (docs/contacts.md).
      int hit = -1;
      for (int j = 0; j < m.Count() && hit < 0; ++j)
        if (found[static_cast<size_t>(2 * j)] != 0) hit = j;
      if (detect_events && hit >= 0) {
        const bool release = m.mode == Mode::kSticking && hit == m.held;
        SegmentResult r{release ? SegmentEnd::kRelease : SegmentEnd::kContact, t, {}};
        r.contact = hit;
        return r;
      }
      // A minimum of a gap (or of R) that did not cross: the stretch is covered up to the root only.
      // The rest of the step, (t, tn], comes with the next call, which returns first any later root
      // of the same step (a crossing there ends the segment before it) and then tn itself
      // (CV_ONE_STEP returns tn once): covering up to tn here put samples and sections past a
      // crossing found next (found by the surfaces campaign on a compliant stop's exit).
      if (on_stretch && t > t_prev) on_stretch(t_prev, t);
      t_prev = std::max(t_prev, t);
    }
  }
}

void CvodeEngine::Evaluate(double sigma, Eigen::VectorXd& X, Eigen::VectorXd& V) const {
  auto& m = *impl_;
  Integrator& in = *m.active;
  const auto n = m.sys.dof();
  X.resize(n);
  V.resize(n);
  // Dense output lives on the last step [tn − hu, tn]; clamp the rounding of sample times.
  double tn = sigma, hu = 0;
  CVodeGetCurrentTime(in.mem, &tn);
  CVodeGetLastStep(in.mem, &hu);
  sigma = std::clamp(sigma, tn - hu, tn);
  // No step since Begin (a contact at σ = 0): the start values, still in y. CVodeGetDky would
  // divide by the step size h = 0 and return NaN (found by the automaton's invariant checks).
  const bool at_start = tn <= 0.0;
  if (!at_start && CVodeGetDky(in.mem, sigma, 0, in.tmp) < 0)
    throw std::logic_error(fmt::format("CVodeGetDky outside the last step (σ = {})", sigma));
  const double* Y = N_VGetArrayPointer(at_start ? in.y : in.tmp);
  if (m.mode == Mode::kFree) {
    for (int i = 0; i < n; ++i) {
      X[i] = m.X0[i] + Y[i];
      V[i] = Y[n + i];
    }
    return;
  }
  // X = e_a v_a + V_a ξ, in the constrained modes of the held contact a.
  const ContactModel& held = m.sys.contacts()[static_cast<size_t>(m.held)];
  const auto& cm = held.constrained;
  const auto k = cm.frequencies.size();
  const Eigen::Map<const Eigen::VectorXd> xi(Y, k), eta(Y + k, k);
  X = held.stop * held.static_shape + cm.vectors * xi;
  V = cm.vectors * eta;
}

double CvodeEngine::Gap(double sigma) const { return GapOf(impl_->held, sigma); }

double CvodeEngine::GapOf(int j, double sigma) const {
  auto& m = *impl_;
  Integrator& in = *m.active;
  if (m.mode != Mode::kFree && (j == m.held || !in.mem)) return 0.0;
  const Impl::Guard& gd = m.guards[static_cast<size_t>(j)];
  double tn = 0.0;
  CVodeGetCurrentTime(in.mem, &tn);
  if (tn <= 0.0) return gd.gap0;  // no step since Begin (see Evaluate)
  if (CVodeGetDky(in.mem, sigma, 0, in.tmp) < 0) return 0.0;
  const double* Y = N_VGetArrayPointer(in.tmp);
  double gap = 0, rate = 0;
  if (m.mode == Mode::kFree) m.FreeGap(j, Y, gap, rate);
  else m.HeldGap(j, Y, gap, rate);
  return gap;
}

SolverStats CvodeEngine::stats() const {
  auto& m = *impl_;
  SolverStats s = m.totals;
  for (Integrator* in : {&m.free, &m.stick}) {
    if (!in->mem) continue;
    long v = 0;
    if (CVodeGetNumSteps(in->mem, &v) == CV_SUCCESS) s.steps += v;
    if (CVodeGetNumRhsEvals(in->mem, &v) == CV_SUCCESS) s.rhs_evals += v;
    if (CVodeGetNumGEvals(in->mem, &v) == CV_SUCCESS) s.root_evals += v;
    if (CVodeGetNumJacEvals(in->mem, &v) == CV_SUCCESS) s.jac_evals += v;
    if (CVodeGetNumErrTestFails(in->mem, &v) == CV_SUCCESS) s.error_test_failures += v;
  }
  return s;
}

}  // namespace vibro::detail

namespace vibro::detail {

// ---- a compliant contact integrated by CVODE (docs/compliant.md, "CVODE") ----
//
// Contact phase on compliant contact j: y = (ΔX, Ẋ, G, E) ∈ ℝ^{2n+2}, ΔX = X − X(0) as in free
// flight, with the spring–dashpot force on the structure,
//   Ẋ' = −Ω X − D Ẋ + T_A f sin(φ + ωσ) + T_j λ,  λ = −k g − c ġ,  g = g(0) + c_jᵀΔX,  ġ = c_jᵀẊ,
// and two quadratures for the loads, G' = g (∫λ dt = −k G − c (g(σ) − g(0))) and E' = ġ² (the
// dashpot's work c E); they are left out of the error test (an absolute tolerance of 1e300), as
// CVODES leaves its quadratures by default. Roots: the exit (g upward, rule "gap" or c = 0; −λ
// upward, rule "force"), λ̇ downward (a peak of the force), ġ upward (the largest penetration), and
// every other contact's gap (downward) and its rate (upward, a minimum ends a step, as in free
// flight). At the entry the gap's known zero is set to exactly 0 (CVODE takes a root function
// that is 0 at t0 as no root, and the gap moves in at once).
// Relaxing flight after a force-rule exit: the free flow in y = (ΔX, Ẋ), with the gap to the
// surface d = g − y₀e^(−kσ/c) as contact j's root (downward) and its rate (upward). A flight that
// starts at the exit itself has d = ḋ = 0 there: d/σ² and ḋ/σ are the root functions, their
// limits d̈(0)/2 and d̈(0) on a short window (a millionth of the period, at most a thousandth of
// the relaxation time c/k), as the sticking flow's known zeros above.
class CvodeCompliant final : public CompliantPhase {
 public:
  using Vec = Eigen::VectorXd;

  CvodeCompliant(const RunSpec& run, const std::vector<const ModelT<double>*>& models, int j)
      : CompliantPhase(models[static_cast<size_t>(j)]->stiffness, models[static_cast<size_t>(j)]->damping),
        run_(run),
        models_(models),
        j_(j),
        m_(*models[static_cast<size_t>(j)]),
        n_(m_.dof()) {
    w2_ = m_.omega.cwiseAbs2();
    damp_ = 2.0 * m_.zeta.cwiseProduct(m_.omega);
    TAf_ = m_.forcing * m_.f;
    const int count = static_cast<int>(models_.size());
    std::vector<int> dirs{+1, -1, +1};
    for (int q = 0; q < count; ++q) dirs.insert(dirs.end(), {-1, +1});
    Create(contact_, 2 * n_ + 2, &CvodeCompliant::ContactRhs, &CvodeCompliant::ContactRoots, dirs,
           &CvodeCompliant::ContactJac);
    // The quadratures G and E are left out of the error test.
    N_Vector atol = N_VNew_Serial(2 * n_ + 2, context_.ctx);
    double* a = N_VGetArrayPointer(atol);
    for (Eigen::Index i = 0; i < 2 * n_; ++i) a[i] = run_.atol;
    a[2 * n_] = a[2 * n_ + 1] = 1e300;
    CVodeSVtolerances(contact_.mem, run_.rtol, atol);
    N_VDestroy(atol);
    dirs.clear();
    for (int q = 0; q < count; ++q) dirs.insert(dirs.end(), {-1, +1});
    Create(flight_, 2 * n_, &CvodeCompliant::FlightRhs, &CvodeCompliant::FlightRoots, dirs, &CvodeCompliant::FlightJac);
    gap0_.resize(models_.size());
  }

  void Begin(const SegmentStart& s) override {
    mode_ = s.mode;
    phase_ = s.phase;
    relaxed_ = false;
    immediate_ = SegmentEnd::kLimit;
    X0_ = s.X;
    for (size_t q = 0; q < models_.size(); ++q) gap0_[q] = models_[q]->shape.dot(s.X) - models_[q]->x0;
    scale_ = std::abs(m_.x0) + m_.shape.cwiseProduct(s.X).cwiseAbs().sum();
    Integrator& in = mode_ == Mode::kFree ? flight_ : contact_;
    double* Y = N_VGetArrayPointer(in.y);
    for (Eigen::Index i = 0; i < n_; ++i) {
      Y[i] = 0.0;
      Y[n_ + i] = s.V[i];
    }
    const double gd = m_.shape.dot(s.V);
    const double tol = 64 * std::numeric_limits<double>::epsilon() * (scale_ + 1e-300);
    divide_ = false;
    window_ = 0;
    if (mode_ == Mode::kSticking) {
      Y[2 * n_] = Y[2 * n_ + 1] = 0.0;
      double& g = gap0_[static_cast<size_t>(j_)];
      if (std::abs(g) <= tol) g = 0.0;  // the entry's known zero, exactly
      // The exit function and its rate at σ = 0: past its root already, the phase ends at once.
      const double lam = -stiffness_ * g - damping_ * gd;
      const double acc = m_.shape.dot(Acceleration(0.0, Y, lam));
      const bool by_gap = m_.separation == Separation::kGap || damping_ == 0;
      const double e0 = by_gap ? g : -lam, e1 = by_gap ? gd : stiffness_ * gd + damping_ * acc;
      if (e0 > 0 || (e0 == 0 && e1 > 0)) immediate_ = SegmentEnd::kRelease;
      peak_ = lam;
      peak_at_ = 0;
      penetration_ = -g;
      penetration_at_ = 0;
    } else {
      // The gap to the surface: d(0) = g(0) − y₀ (exactly 0 at the exit itself).
      if (at_exit_) {
        gap0_[static_cast<size_t>(j_)] = y0_;
        const double acc = m_.shape.dot(Acceleration(0.0, Y, 0.0));
        const double r = stiffness_ / damping_;
        d2_ = acc - r * r * y0_;  // d̈(0)
        divide_ = true;
        window_ = std::min(1e-6 * m_.period, 1e-3 / r);
        if (!(d2_ > 0)) immediate_ = SegmentEnd::kContact;  // the body does not lift off the surface
      } else if (!(gap0_[static_cast<size_t>(j_)] - y0_ > 0)) {
        immediate_ = SegmentEnd::kContact;
      }
    }
    Collect(in);
    ++totals_.reinits;
    CVodeReInit(in.mem, 0.0, in.y);
    active_ = &in;
  }

  SegmentResult Advance(double sigma_max, bool detect, const StretchCallback& on_stretch) override {
    Integrator& in = *active_;
    if (detect && immediate_ != SegmentEnd::kLimit) {
      SegmentResult now{immediate_, 0.0, {}};
      now.contact = j_;
      at_exit_ = false;
      last_ = 0;
      return now;
    }
    guards_off_ = !detect;
    double end = sigma_max;
    bool relaxing_end = false;
    if (mode_ == Mode::kFree && y0_ != 0) {
      const double back = RelaxedAfter(scale_);
      if (back < end) {
        end = std::max(back, 0.0);
        relaxing_end = true;
      }
    }
    at_exit_ = false;
    SegmentResult res{SegmentEnd::kLimit, end, {}};
    res.contact = j_;
    if (end <= 0) {
      relaxed_ = relaxing_end;
      last_ = 0;
      return res;
    }
    CVodeSetStopTime(in.mem, end);
    const int roots = mode_ == Mode::kFree ? 2 * Count() : 3 + 2 * Count();
    std::vector<int> found(static_cast<size_t>(roots));
    double t_prev = 0.0;
    long steps = 0;
    while (true) {
      if (StopRequested()) return Stopped(t_prev, "a segment");
      double t = 0.0;
      last_error_.clear();
      rhs_in_call_ = 0;
      stopped_in_rhs_ = overworked_ = false;
      const int flag = CVode(in.mem, end, in.y, &t, CV_ONE_STEP);
      if (pending_) std::rethrow_exception(std::exchange(pending_, nullptr));
      if (stopped_in_rhs_) return Stopped(t_prev, "a CVODE step");
      if (overworked_)
        return {SegmentEnd::kFailure, t_prev,
                fmt::format("CVODE made more than {} right-hand-side evaluations in one step of a compliant contact "
                            "at local time {:.6g} (the tolerances cannot be met: raise run.atol or run.rtol)",
                            kRhsPerStep, t_prev)};
      if (flag < 0)
        return {SegmentEnd::kFailure, t_prev,
                fmt::format("CVODE {} in a compliant contact at local time {:.6g}{}; {}", FlagName(flag), t_prev,
                            last_error_.empty() ? "" : " (" + last_error_ + ")", Hint(flag))};
      if (++steps > run_.max_steps)
        return {SegmentEnd::kFailure, t_prev,
                fmt::format("CVODE CV_TOO_MUCH_WORK: more than run.max_steps = {} steps in one segment of a "
                            "compliant contact (local time {:.6g}); {}",
                            run_.max_steps, t_prev, Hint(CV_TOO_MUCH_WORK))};
      if (flag == CV_ROOT_RETURN) {
        CVodeGetRootInfo(in.mem, found.data());
        const double* Y = N_VGetArrayPointer(in.y);  // the state at the root t
        if (on_stretch && t > t_prev) on_stretch(t_prev, t);
        t_prev = std::max(t_prev, t);
        if (mode_ == Mode::kSticking) {
          if (found[1] != 0) {  // a maximum of the force
            const double lam = Force(Y);
            if (lam > peak_) {
              peak_ = lam;
              peak_at_ = t;
            }
          }
          if (found[2] != 0) {  // a minimum of the gap
            const double pen = -OwnGap(Y);
            if (pen > penetration_) {
              penetration_ = pen;
              penetration_at_ = t;
            }
          }
          if (found[0] != 0) {
            res.end = SegmentEnd::kRelease;
            res.sigma = last_ = t;
            return res;
          }
        }
        const int base = mode_ == Mode::kFree ? 0 : 3;
        for (int q = 0; q < Count(); ++q)
          if (found[static_cast<size_t>(base + 2 * q)] != 0 && (q != j_ || mode_ == Mode::kFree)) {
            res.end = SegmentEnd::kContact;
            res.contact = q;
            res.sigma = last_ = t;
            return res;
          }
        // A minimum of a gap, or a peak, that ends no segment: covered up to the root only; the rest
        // of the step comes with the next call, after any later root of the step (the exit among
        // them), as in CvodeEngine::Advance.
        continue;
      }
      if (on_stretch && t > t_prev) on_stretch(t_prev, t);
      t_prev = std::max(t_prev, t);
      if (flag == CV_TSTOP_RETURN || t >= end) {
        relaxed_ = relaxing_end;
        res.sigma = last_ = end;
        return res;
      }
    }
  }

  void Evaluate(double sigma, Vec& X, Vec& V) const override {
    const double* Y = Dense(sigma);
    X.resize(n_);
    V.resize(n_);
    for (Eigen::Index i = 0; i < n_; ++i) {
      X[i] = X0_[i] + Y[i];
      V[i] = Y[n_ + i];
    }
  }
  double Gap(double sigma) const override { return GapOf(j_, sigma); }
  double GapOf(int q, double sigma) const override {
    const double* Y = Dense(sigma);
    const auto& c = models_[static_cast<size_t>(q)]->shape;
    double g = gap0_[static_cast<size_t>(q)];
    for (Eigen::Index i = 0; i < n_; ++i) g += c[i] * Y[i];
    if (q == j_ && mode_ == Mode::kFree) g -= SurfaceAt(sigma);
    return g;
  }

  PhaseLoads Loads(double sigma) const override {
    const double* Y = Dense(sigma);
    PhaseLoads L;
    const double g = OwnGap(Y);
    L.integral = -stiffness_ * Y[2 * n_] - damping_ * (g - gap0_[static_cast<size_t>(j_)]);
    L.dissipated = damping_ * Y[2 * n_ + 1];
    L.peak = peak_;
    L.peak_at = peak_at_;
    L.penetration = penetration_;
    L.penetration_at = penetration_at_;
    const double lam = Force(Y);
    if (lam > L.peak) {
      L.peak = lam;
      L.peak_at = sigma;
    }
    if (-g > L.penetration) {
      L.penetration = -g;
      L.penetration_at = sigma;
    }
    return L;
  }

  SolverStats stats() const override {
    SolverStats s = totals_;
    for (const Integrator* in : {&contact_, &flight_}) {
      long v = 0;
      if (CVodeGetNumSteps(in->mem, &v) == CV_SUCCESS) s.steps += v;
      if (CVodeGetNumRhsEvals(in->mem, &v) == CV_SUCCESS) s.rhs_evals += v;
      if (CVodeGetNumGEvals(in->mem, &v) == CV_SUCCESS) s.root_evals += v;
      if (CVodeGetNumJacEvals(in->mem, &v) == CV_SUCCESS) s.jac_evals += v;
      if (CVodeGetNumErrTestFails(in->mem, &v) == CV_SUCCESS) s.error_test_failures += v;
    }
    return s;
  }

 private:
  static constexpr long kRhsPerStep = 100000;

  int Count() const { return static_cast<int>(models_.size()); }

  // The structure's acceleration at local time t with the contact force `lam` on it (0 in flight),
  // in a scratch vector (no allocation per right-hand side).
  // A sum of harmonics (docs/harmonics.md): f is 0 and each harmonic's term is added.
  const Vec& Acceleration(double t, const double* Y, double lam) const {
    const double phi = phase_ + m_.w * t, s = std::sin(phi);
    acc_.resize(n_);
    for (Eigen::Index i = 0; i < n_; ++i)
      acc_[i] = -w2_[i] * (X0_[i] + Y[i]) - damp_[i] * Y[n_ + i] + TAf_[i] * s + m_.contact[i] * lam;
    if (!m_.harmonics.empty()) acc_ += m_.harmonics.Vector(phi);
    return acc_;
  }
  double OwnGap(const double* Y) const {
    double g = gap0_[static_cast<size_t>(j_)];
    for (Eigen::Index i = 0; i < n_; ++i) g += m_.shape[i] * Y[i];
    return g;
  }
  double OwnRate(const double* Y) const {
    double v = 0;
    for (Eigen::Index i = 0; i < n_; ++i) v += m_.shape[i] * Y[n_ + i];
    return v;
  }
  double Force(const double* Y) const { return -stiffness_ * OwnGap(Y) - damping_ * OwnRate(Y); }

  bool MayGoOn() {
    if (++rhs_in_call_ > kRhsPerStep) {
      overworked_ = true;
      return false;
    }
    if ((rhs_in_call_ & 255) == 0 && StopRequested()) {
      stopped_in_rhs_ = true;
      return false;
    }
    return true;
  }

  static int ContactRhs(sunrealtype t, N_Vector y, N_Vector ydot, void* user) {
    auto* m = static_cast<CvodeCompliant*>(user);
    if (!m->MayGoOn()) return -1;
    try {
      const double* Y = N_VGetArrayPointer(y);
      double* D = N_VGetArrayPointer(ydot);
      const Eigen::Index n = m->n_;
      const double g = m->OwnGap(Y), gd = m->OwnRate(Y);
      const Vec& a = m->Acceleration(t, Y, -m->stiffness_ * g - m->damping_ * gd);
      for (Eigen::Index i = 0; i < n; ++i) {
        D[i] = Y[n + i];
        D[n + i] = a[i];
      }
      D[2 * n] = g;
      D[2 * n + 1] = gd * gd;
      return 0;
    } catch (...) {
      m->pending_ = std::current_exception();
      return -1;
    }
  }

  static int FlightRhs(sunrealtype t, N_Vector y, N_Vector ydot, void* user) {
    auto* m = static_cast<CvodeCompliant*>(user);
    if (!m->MayGoOn()) return -1;
    try {
      const double* Y = N_VGetArrayPointer(y);
      double* D = N_VGetArrayPointer(ydot);
      const Eigen::Index n = m->n_;
      const Vec& a = m->Acceleration(t, Y, 0.0);
      for (Eigen::Index i = 0; i < n; ++i) {
        D[i] = Y[n + i];
        D[n + i] = a[i];
      }
      return 0;
    } catch (...) {
      m->pending_ = std::current_exception();
      return -1;
    }
  }

  // Every other contact's gap and its rate (contact j's own pair: constant, or `own`).
  void OtherGaps(const double* Y, sunrealtype* g) const {
    for (int q = 0; q < Count(); ++q) {
      sunrealtype* r = g + 2 * q;
      if (q == j_ || guards_off_) {
        r[0] = r[1] = 1.0;
        continue;
      }
      const auto& c = models_[static_cast<size_t>(q)]->shape;
      double gap = gap0_[static_cast<size_t>(q)], rate = 0;
      for (Eigen::Index i = 0; i < n_; ++i) {
        gap += c[i] * Y[i];
        rate += c[i] * Y[n_ + i];
      }
      r[0] = gap;
      r[1] = rate;
    }
  }

  static int ContactRoots(sunrealtype t, N_Vector y, sunrealtype* g, void* user) {
    auto* m = static_cast<CvodeCompliant*>(user);
    const double* Y = N_VGetArrayPointer(y);
    m->OtherGaps(Y, g + 3);
    if (m->guards_off_) {
      g[0] = g[1] = g[2] = 1.0;
      return 0;
    }
    const double gap = m->OwnGap(Y), gd = m->OwnRate(Y);
    const double lam = -m->stiffness_ * gap - m->damping_ * gd;
    const double gdd = m->m_.shape.dot(m->Acceleration(t, Y, lam));
    const bool by_gap = m->m_.separation == Separation::kGap || m->damping_ == 0;
    g[0] = by_gap ? gap : -lam;
    g[1] = -m->stiffness_ * gd - m->damping_ * gdd;
    g[2] = gd;
    return 0;
  }

  static int FlightRoots(sunrealtype t, N_Vector y, sunrealtype* g, void* user) {
    auto* m = static_cast<CvodeCompliant*>(user);
    const double* Y = N_VGetArrayPointer(y);
    m->OtherGaps(Y, g);
    sunrealtype* own = g + 2 * m->j_;
    if (m->guards_off_) return 0;
    const double r = m->stiffness_ / m->damping_, ys = m->SurfaceAt(t);
    const double d = m->OwnGap(Y) - ys, dd = m->OwnRate(Y) + r * ys;
    if (!m->divide_) {
      own[0] = d;
      own[1] = dd;
    } else if (t <= m->window_) {
      own[0] = m->d2_ / 2;
      own[1] = m->d2_;
    } else {
      own[0] = d / (t * t);
      own[1] = dd / t;
    }
    return 0;
  }

  static int ContactJac(sunrealtype, N_Vector y, N_Vector, SUNMatrix J, void* user, N_Vector, N_Vector, N_Vector) {
    auto* m = static_cast<CvodeCompliant*>(user);
    const Eigen::Index n = m->n_;
    const double gd = m->OwnRate(N_VGetArrayPointer(y));
    SUNMatZero(J);
    for (Eigen::Index i = 0; i < n; ++i) {
      SM_ELEMENT_D(J, i, n + i) = 1.0;
      SM_ELEMENT_D(J, n + i, i) = -m->w2_[i];
      SM_ELEMENT_D(J, n + i, n + i) = -m->damp_[i];
      for (Eigen::Index l = 0; l < n; ++l) {
        SM_ELEMENT_D(J, n + i, l) -= m->m_.contact[i] * m->stiffness_ * m->m_.shape[l];
        SM_ELEMENT_D(J, n + i, n + l) -= m->m_.contact[i] * m->damping_ * m->m_.shape[l];
      }
      SM_ELEMENT_D(J, 2 * n, i) = m->m_.shape[i];
      SM_ELEMENT_D(J, 2 * n + 1, n + i) = 2 * gd * m->m_.shape[i];
    }
    return 0;
  }

  static int FlightJac(sunrealtype, N_Vector, N_Vector, SUNMatrix J, void* user, N_Vector, N_Vector, N_Vector) {
    auto* m = static_cast<CvodeCompliant*>(user);
    const Eigen::Index n = m->n_;
    SUNMatZero(J);
    for (Eigen::Index i = 0; i < n; ++i) {
      SM_ELEMENT_D(J, i, n + i) = 1.0;
      SM_ELEMENT_D(J, n + i, i) = -m->w2_[i];
      SM_ELEMENT_D(J, n + i, n + i) = -m->damp_[i];
    }
    return 0;
  }

  static void ErrHandler(int, const char* module, const char* function, char* msg, void* user) {
    static_cast<CvodeCompliant*>(user)->last_error_ =
        fmt::format("{}/{}: {}", module ? module : "", function ? function : "", msg ? msg : "");
  }

  void Create(Integrator& in, sunindextype size, CVRhsFn rhs, CVRootFn roots, std::vector<int> dirs, CVLsJacFn jac) {
    in.size = size;
    in.y = N_VNew_Serial(size, context_.ctx);
    in.tmp = N_VNew_Serial(size, context_.ctx);
    N_VConst(0.0, in.y);
    in.mem = CVodeCreate(run_.method == CvodeMethod::kBdf ? CV_BDF : CV_ADAMS, context_.ctx);
    if (!in.y || !in.tmp || !in.mem) throw std::runtime_error("CVODE: allocation failed");
    CVodeSetErrHandlerFn(in.mem, &CvodeCompliant::ErrHandler, this);
    if (CVodeInit(in.mem, rhs, 0.0, in.y) < 0) throw std::runtime_error("CVodeInit failed");
    CVodeSetUserData(in.mem, this);
    CVodeSStolerances(in.mem, run_.rtol, run_.atol);
    in.A = SUNDenseMatrix(size, size, context_.ctx);
    in.LS = SUNLinSol_Dense(in.y, in.A, context_.ctx);
    if (CVodeSetLinearSolver(in.mem, in.LS, in.A) < 0) throw std::runtime_error("CVODE linear solver");
    CVodeSetJacFn(in.mem, jac);
    CVodeRootInit(in.mem, static_cast<int>(dirs.size()), roots);
    CVodeSetRootDirection(in.mem, dirs.data());
    CVodeSetNoInactiveRootWarn(in.mem);
    if (run_.max_step > 0) CVodeSetMaxStep(in.mem, run_.max_step);
    CVodeSetMaxNumSteps(in.mem, run_.max_steps);
  }

  void Collect(Integrator& in) {
    long v = 0;
    if (CVodeGetNumSteps(in.mem, &v) == CV_SUCCESS) totals_.steps += v;
    if (CVodeGetNumRhsEvals(in.mem, &v) == CV_SUCCESS) totals_.rhs_evals += v;
    if (CVodeGetNumGEvals(in.mem, &v) == CV_SUCCESS) totals_.root_evals += v;
    if (CVodeGetNumJacEvals(in.mem, &v) == CV_SUCCESS) totals_.jac_evals += v;
    if (CVodeGetNumErrTestFails(in.mem, &v) == CV_SUCCESS) totals_.error_test_failures += v;
  }

  // The state at σ from the last step's dense output (the start values before any step).
  const double* Dense(double sigma) const {
    Integrator& in = *active_;
    double tn = sigma, hu = 0;
    CVodeGetCurrentTime(in.mem, &tn);
    if (tn <= 0.0) return N_VGetArrayPointer(in.y);
    CVodeGetLastStep(in.mem, &hu);
    sigma = std::clamp(sigma, tn - hu, tn);
    if (CVodeGetDky(in.mem, sigma, 0, in.tmp) < 0)
      throw std::logic_error(fmt::format("CVodeGetDky outside the last step (σ = {}, compliant contact)", sigma));
    return N_VGetArrayPointer(in.tmp);
  }

  SegmentResult Stopped(double t, const char* where) const {
    SegmentResult stop{SegmentEnd::kFailure, t,
                       fmt::format("stop requested inside {} (local time {:.6g}, compliant contact)", where, t)};
    stop.stopped = true;
    return stop;
  }

  RunSpec run_;
  std::vector<const ModelT<double>*> models_;
  int j_;
  const ModelT<double>& m_;
  Eigen::Index n_;
  Vec w2_, damp_, TAf_;
  mutable Vec acc_;  // Acceleration's scratch
  Context context_;  // destroyed after the integrators that use it
  Integrator contact_, flight_;
  Integrator* active_ = &contact_;
  SolverStats totals_;
  std::string last_error_;
  std::exception_ptr pending_;
  long rhs_in_call_ = 0;
  bool stopped_in_rhs_ = false, overworked_ = false, guards_off_ = false;
  // The segment.
  Mode mode_ = Mode::kSticking;
  double phase_ = 0, scale_ = 1, last_ = 0;
  Vec X0_;
  std::vector<double> gap0_;  // every contact's gap at σ = 0 (contact j's to its stop)
  SegmentEnd immediate_ = SegmentEnd::kLimit;
  bool divide_ = false;
  double window_ = 0, d2_ = 0;
  double peak_ = 0, peak_at_ = 0, penetration_ = 0, penetration_at_ = 0;
};

std::unique_ptr<CompliantPhase> CreateCvodeCompliant(const RunSpec& run, const std::vector<const ModelT<double>*>& models,
                                                     int contact) {
  return std::make_unique<CvodeCompliant>(run, models, contact);
}

std::unique_ptr<Propagator> CreateCvodeEngine(const System& system, const RunSpec& run) {
  return std::make_unique<CvodeEngine>(system, run);
}

}  // namespace vibro::detail

// The plugin's entry point (cvode_api.hpp): libvibro's MakeCvodeEngine and MakeCvodeCompliant
// (cvode_loader.cpp) call through this table.
extern "C" __attribute__((visibility("default"))) const VibroCvodeApi* vibro_cvode_api() {
  static const VibroCvodeApi api{sizeof(vibro::RunSpec), sizeof(vibro::detail::ModelT<double>),
                                 &vibro::detail::CreateCvodeEngine, &vibro::detail::CreateCvodeCompliant};
  return &api;
}
