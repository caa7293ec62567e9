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
#include "dynamics/cvode_engine.hpp"

#include "dynamics/flight_window.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <exception>
#include <functional>
#include <limits>
#include <string>
#include <utility>

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

  // Segment data.
  Mode mode = Mode::kFree;
  double phase = 0, gap0 = 0;
  Eigen::VectorXd X0, V0;
  int order = 0;            // m: order of the known zero of the guard at σ = 0
  std::string inadmissible;  // non-empty: the start is below the stop (Advance fails with it)
  bool immediate_contact = false;  // on the stop moving into it: contact at σ = 0
  double window = 0;        // certified root-free (0, window): the limits are used there
  double g_lim = 0, v_lim = 0;  // limits of g/σᵐ and ẋ_B/σ^(m−1) (or R, Ṙ) at σ = 0
  bool guards_off = false;  // Advance without events (an accumulation jump): no root finding
  double atol = 0;          // absolute tolerance of the current free flight

  // Model data.
  Eigen::VectorXd w2, damp, TA_f, c;
  Eigen::VectorXd stick_w2, stick_F, rho, rho_v;
  Eigen::MatrixXd stick_D;
  double react_f = 0, R_static = 0;
  bool stick_damped = false;

  Impl(const System& s, const RunSpec& r) : sys(s), run(r) {}

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
      return 0;
    } catch (...) {
      m->pending = std::current_exception();
      return -1;
    }
  }

  static int FreeRoots(sunrealtype t, N_Vector y, sunrealtype* g, void* user) {
    auto* m = static_cast<Impl*>(user);
    const auto n = m->sys.dof();
    const double* Y = N_VGetArrayPointer(y);
    double gap = m->gap0, vB = 0;
    for (int i = 0; i < n; ++i) {
      gap += m->c[i] * Y[i];
      vB += m->c[i] * Y[n + i];
    }
    m->DividedRoots(t, gap, vB, g);
    return 0;
  }

  // Guard value/σᵐ and rate/σ^(m−1), m = order of the known zero at σ = 0. Inside the certified
  // window (docs/model.md §2.1) no root exists: the divided functions are their positive limits there,
  // free of the rounding of value/σᵐ at tiny σ.
  void DividedRoots(double t, double value, double rate, sunrealtype* g) const {
    if (guards_off) {  // constant guards: CVODE sees no root (and none "at and very near" t0)
      g[0] = g[1] = 1.0;
    } else if (order > 0 && t <= window) {
      g[0] = g_lim;
      g[1] = order <= 1 ? rate : v_lim;
    } else if (order == 0) {
      g[0] = value;
      g[1] = rate;
    } else {
      g[0] = value / std::pow(t, order);
      g[1] = order <= 1 ? rate : rate / std::pow(t, order - 1);
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
    const auto k = stick_w2.size();
    const double s = std::sin(phase + sys.frequency() * t);
    for (Eigen::Index i = 0; i < k; ++i) {
      double a = -stick_w2[i] * Y[i] + stick_F[i] * s;
      if (stick_damped)
        for (Eigen::Index j = 0; j < k; ++j) a -= stick_D(i, j) * Y[k + j];
      acc[i] = a;
    }
  }

  static int StickRhs(sunrealtype t, N_Vector y, N_Vector ydot, void* user) {
    auto* m = static_cast<Impl*>(user);
    if (!m->MayGoOn()) return -1;
    try {
      const auto k = m->stick_w2.size();
      const double* Y = N_VGetArrayPointer(y);
      double* D = N_VGetArrayPointer(ydot);
      for (Eigen::Index i = 0; i < k; ++i) D[i] = Y[k + i];
      m->StickAcc(t, Y, D + k);
      return 0;
    } catch (...) {
      m->pending = std::current_exception();
      return -1;
    }
  }

  // R = R_st + ρᵀξ + ρ_vᵀξ̇ − (s_A/s_B) f sin, Ṙ = ρᵀξ̇ + ρ_vᵀξ̈ − (s_A/s_B) f ω cos.
  void Reaction(double t, const double* Y, double& R, double& dR) const {
    const auto k = stick_w2.size();
    const double w = sys.frequency();
    R = R_static - react_f * std::sin(phase + w * t);
    dR = -react_f * w * std::cos(phase + w * t);
    std::vector<double> acc(static_cast<size_t>(k));
    StickAcc(t, Y, acc.data());
    for (Eigen::Index i = 0; i < k; ++i) {
      R += rho[i] * Y[i] + rho_v[i] * Y[k + i];
      dR += rho[i] * Y[k + i] + rho_v[i] * acc[static_cast<size_t>(i)];
    }
  }

  // R̈ = ρᵀξ̈ + ρ_vᵀξ⃛ + (s_A/s_B) f ω² sin, ξ⃛ = −Ω'ξ̇ − D'ξ̈ + F' f ω cos.
  double ReactionCurvature(double t, const double* Y) const {
    const auto k = stick_w2.size();
    const double w = sys.frequency();
    std::vector<double> acc(static_cast<size_t>(k));
    StickAcc(t, Y, acc.data());
    double d2R = react_f * w * w * std::sin(phase + w * t);
    for (Eigen::Index i = 0; i < k; ++i) {
      double jerk = -stick_w2[i] * Y[k + i] + stick_F[i] * w * std::cos(phase + w * t);
      for (Eigen::Index j = 0; j < k; ++j) jerk -= stick_D(i, j) * acc[static_cast<size_t>(j)];
      d2R += rho[i] * acc[static_cast<size_t>(i)] + rho_v[i] * jerk;
    }
    return d2R;
  }

  static int StickRoots(sunrealtype t, N_Vector y, sunrealtype* g, void* user) {
    auto* m = static_cast<Impl*>(user);
    double R, dR;
    m->Reaction(t, N_VGetArrayPointer(y), R, dR);
    m->DividedRoots(t, R, dR, g);
    return 0;
  }

  static int StickJac(sunrealtype, N_Vector, N_Vector, SUNMatrix J, void* user, N_Vector, N_Vector,
                      N_Vector) {
    auto* m = static_cast<Impl*>(user);
    const auto k = m->stick_w2.size();
    SUNMatZero(J);
    for (Eigen::Index i = 0; i < k; ++i) {
      SM_ELEMENT_D(J, i, k + i) = 1.0;
      SM_ELEMENT_D(J, k + i, i) = -m->stick_w2[i];
      for (Eigen::Index j = 0; j < k; ++j) SM_ELEMENT_D(J, k + i, k + j) = -m->stick_D(i, j);
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
    CVodeRootInit(in.mem, 2, roots);
    int dirs[2] = {-1, +1};
    CVodeSetRootDirection(in.mem, dirs);
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
};

CvodeEngine::CvodeEngine(const System& sys, const RunSpec& run)
    : impl_(std::make_unique<Impl>(sys, run)) {
  auto& m = *impl_;
  const auto n = sys.dof();
  m.w2 = sys.omega().cwiseAbs2();
  m.damp = 2.0 * sys.damping().cwiseProduct(sys.omega());
  m.TA_f = sys.forcing() * sys.amplitude();
  m.c = sys.contact_shape();
  const auto& cm = sys.constrained();
  m.stick_w2 = cm.frequencies.cwiseAbs2();
  m.stick_F = cm.modal_forcing * sys.amplitude();
  m.stick_D = cm.damping;
  m.stick_damped = cm.damping.size() > 0 && cm.damping.cwiseAbs().maxCoeff() > 0;
  m.rho = cm.reaction;
  // Velocity part of R (docs/model.md §7): Σ c_i 2ζ_iω_i Ẋ_i / s_B with Ẋ = V ξ̇.
  m.rho_v = cm.vectors.transpose() * (m.c.cwiseProduct(m.damp)) / sys.s_B();
  m.react_f = sys.s_A() / sys.s_B() * sys.amplitude();
  m.R_static = sys.stop() / sys.flexibility();
  m.Create(m.free, 2 * n, &Impl::FreeRhs, &Impl::FreeRoots, &Impl::FreeJac);
  if (n >= 2) m.Create(m.stick, 2 * (n - 1), &Impl::StickRhs, &Impl::StickRoots, &Impl::StickJac);
}

CvodeEngine::~CvodeEngine() = default;

void CvodeEngine::Begin(const SegmentStart& s) {
  auto& m = *impl_;
  m.mode = s.mode;
  m.phase = s.phase;
  m.gap0 = s.gap;
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
    m.order = static_cast<int>(s.flight_start);  // kGeneric 0, kAfterImpact 1, kDeparture 2, kAfterRelease 3
    // Limits at σ = 0 of g/σᵐ and ẋ_B/σ^(m−1): g', g''/2, g'''/6 and g', g'', g'''/2.
    const double cap = StepCap(m.sys);
    const FlightJet jet = StartJet(m.sys, s.X, s.V, s.phase, cap);
    m.inadmissible.clear();
    m.immediate_contact = false;
    if (m.order == 0 && s.gap <= 0) {
      // A generic start on the stop (or rounded below it). CVODE ignores a root function that is
      // zero at t0, so a state leaving the stop by a hair (ẋ_B = 5e-324) and falling back would
      // pass through the wall unseen (BUILD-NOTES: the start must be admissible). Divide out the
      // known zero like after an impact, a departure or a release: the order is that of the first
      // non-zero derivative of g; a negative one means the state moves into the stop at once.
      const double tol = 1e-12 * std::max(1.0, std::abs(m.sys.stop()));
      if (s.gap < -tol) {
        m.inadmissible = fmt::format("start below the stop (x_B − x0 = {:.3g} < 0): not an admissible "
                                     "state of the impact oscillator", s.gap);
      } else {
        const double d[3] = {jet.g1, jet.g2, jet.g3};
        int k = 0;
        while (k < 3 && d[k] == 0) ++k;
        if (k == 3 || d[k] < 0) {
          m.immediate_contact = true;
        } else {
          m.order = k + 1;
          m.gap0 = 0.0;
        }
      }
    }
    m.window = CertifiedWindow(static_cast<FlightStart>(m.order), jet, cap);
    // Leaving the stop so slowly that the flight (≈ 2g'/|g''|) is shorter than the clock can
    // resolve: a touch at σ = 0, as the exact engine finds it. Integrating it instead would end in
    // impacts at speeds of order 1e-300 that never reach the chattering treatment.
    if (m.order == 1 && jet.g2 < 0 &&
        2 * jet.g1 / -jet.g2 <= 4 * std::numeric_limits<double>::epsilon() * m.sys.period())
      m.immediate_contact = true;
    // A flight of a chattering sequence rises only u²/(2|a|) above the stop: an absolute
    // tolerance above rtol times that height would locate its landing to δg/u at best, and the
    // accumulated landing errors would dominate the sequence (measured: 2e-9 T at rtol 1e-12).
    m.atol = m.run.atol;
    if (s.flight_start == FlightStart::kAfterImpact && jet.g1 > 0 && jet.g2 < 0)
      m.atol = std::clamp(m.run.rtol * jet.g1 * jet.g1 / (-2.0 * jet.g2), 1e-300, m.run.atol);
    switch (m.order) {
      case 1: m.g_lim = jet.g1; m.v_lim = jet.g1; break;
      case 2: m.g_lim = jet.g2 / 2; m.v_lim = jet.g2; break;
      case 3: m.g_lim = jet.g3 / 6; m.v_lim = jet.g3 / 2; break;
      default: break;
    }
  } else {
    const auto& cm = m.sys.constrained();
    const Eigen::VectorXd xi = cm.left * s.X, eta = cm.left * s.V;
    const auto k = xi.size();
    for (Eigen::Index i = 0; i < k; ++i) {
      Y[i] = xi[i];
      Y[k + i] = eta[i];
    }
    m.order = static_cast<int>(s.stick_start);  // kGeneric 0, kRising 1, kTangent 2
    // No rigorous bound is at hand for the coupled damped sticking flow: the limits are used on
    // a short fixed window (a millionth of the period) after a rising or tangent start.
    m.window = m.order > 0 ? 1e-6 * m.sys.period() : 0.0;
    double R, dR;
    m.Reaction(0.0, Y, R, dR);
    if (m.order == 1) {
      m.g_lim = dR;
      m.v_lim = dR;
    } else if (m.order == 2) {
      m.g_lim = m.ReactionCurvature(0.0, Y) / 2;
      m.v_lim = 2 * m.g_lim;
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
  if (m.mode == Mode::kFree && !m.inadmissible.empty()) return {SegmentEnd::kFailure, 0.0, m.inadmissible};
  if (m.mode == Mode::kFree && m.immediate_contact && detect_events) return {SegmentEnd::kContact, 0.0, {}};
  m.guards_off = !detect_events;
  CVodeSetStopTime(in.mem, sigma_max);
  double t_prev = 0.0;
  long steps = 0;
  m.poll = [this] { return StopRequested(); };
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
    // A root at and very near the start of a free flight: the gap vanishes to CVODE's resolution
    // over its first step, as after an impact whose speed is at the √rtol floor of a chattering
    // sequence. Whether that contact ends the sequence is not decided at this precision.
    if (flag == CV_ILL_INPUT && m.mode == Mode::kFree && m.last_error.find("very near") != std::string::npos) {
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
      int found[2] = {0, 0};
      CVodeGetRootInfo(in.mem, found);
      if (detect_events && found[0] != 0)
        return {m.mode == Mode::kFree ? SegmentEnd::kContact : SegmentEnd::kRelease, t, {}};
      // A minimum of the gap (or of R) that did not cross: the rest of the step is still
      // covered by the dense output of this step.
      double tn = t;
      CVodeGetCurrentTime(in.mem, &tn);
      if (on_stretch && tn > t_prev) on_stretch(t_prev, tn);
      t_prev = std::max(t_prev, tn);
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
  const auto& cm = m.sys.constrained();
  const auto k = cm.frequencies.size();
  const Eigen::Map<const Eigen::VectorXd> xi(Y, k), eta(Y + k, k);
  X = m.sys.stop() * m.sys.static_shape() + cm.vectors * xi;
  V = cm.vectors * eta;
}

double CvodeEngine::Gap(double sigma) const {
  auto& m = *impl_;
  if (m.mode != Mode::kFree) return 0.0;
  double tn = 0.0;
  CVodeGetCurrentTime(m.active->mem, &tn);
  if (tn <= 0.0) return m.gap0;  // no step since Begin (see Evaluate)
  if (CVodeGetDky(m.active->mem, sigma, 0, m.active->tmp) < 0) return 0.0;
  const double* Y = N_VGetArrayPointer(m.active->tmp);
  double gap = m.gap0;
  for (int i = 0; i < m.sys.dof(); ++i) gap += m.c[i] * Y[i];
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
