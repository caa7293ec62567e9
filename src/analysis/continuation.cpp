// Pseudo-arclength continuation of periodic orbits (see include/vibro/continuation.hpp).
#include "vibro/continuation.hpp"

#include <algorithm>
#include <cmath>
#include <optional>

#include <fmt/format.h>

namespace vibro {
namespace {

struct Evaluation {
  Eigen::VectorXd G;   // F(z; λ) − z
  Eigen::MatrixXd Jz;  // DF − I
  Eigen::VectorXd Jl;  // ∂F/∂λ
  bool ok = false;
};

class Problem {
 public:
  Problem(const ContinuationRequest& req, double t0, int q) : req_(req), t0_(t0), q_(q) {}

  std::optional<Scene> SceneAt(double lambda) const {
    try {
      return req_.scene_at(lambda);
    } catch (const std::exception&) {
      return std::nullopt;  // λ left the valid range of the key
    }
  }

  std::optional<Eigen::VectorXd> Map(const Eigen::VectorXd& z, double lambda,
                                     Eigen::MatrixXd* jac) const {
    const auto scene = SceneAt(lambda);
    if (!scene) return std::nullopt;
    const System sys(*scene);
    const auto n = sys.dof();
    const MapValue m = StroboscopicMap(sys, *scene, t0_, z.head(n), z.tail(n), q_);
    if (m.status != RunStatus::kOk || m.singular) return std::nullopt;
    if (jac) *jac = m.jacobian;
    Eigen::VectorXd out(2 * n);
    out << m.X, m.V;
    return out;
  }

  Evaluation Evaluate(const Eigen::VectorXd& z, double lambda) const {
    Evaluation e;
    Eigen::MatrixXd DF;
    const auto F = Map(z, lambda, &DF);
    const double h = 1e-6 * std::max(1.0, std::abs(lambda));
    const auto Fp = Map(z, lambda + h, nullptr), Fm = Map(z, lambda - h, nullptr);
    if (!F || !Fp || !Fm) return e;
    e.G = *F - z;
    e.Jz = DF - Eigen::MatrixXd::Identity(z.size(), z.size());
    e.Jl = (*Fp - *Fm) / (2 * h);
    e.ok = true;
    return e;
  }

  // The orbit at (z, λ): summary and multipliers.
  OrbitResult Characterized(const Eigen::VectorXd& z, double lambda) const {
    OrbitResult o;
    const auto scene = SceneAt(lambda);
    if (!scene) return o;
    const System sys(*scene);
    const auto n = sys.dof();
    o.status = "converged";
    o.period = q_;
    o.section_time = t0_;
    o.X = z.head(n);
    o.V = z.tail(n);
    o.monodromy = StroboscopicMap(sys, *scene, t0_, o.X, o.V, q_).jacobian;
    Characterize(sys, *scene, o);
    return o;
  }

 private:
  const ContinuationRequest& req_;
  double t0_;
  int q_;
};

// Unit null vector of the 2n × (2n+1) matrix [Jz Jλ], oriented like `previous`.
Eigen::VectorXd Tangent(const Evaluation& e, const Eigen::VectorXd& previous) {
  Eigen::MatrixXd A(e.Jz.rows(), e.Jz.cols() + 1);
  A << e.Jz, e.Jl;
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(A, Eigen::ComputeFullV);
  Eigen::VectorXd t = svd.matrixV().col(A.cols() - 1);
  if (previous.size() == t.size() && t.dot(previous) < 0) t = -t;
  return t;
}

// Newton on {G(y) = 0, tᵀ(y − y_pred) = 0}.
std::optional<Eigen::VectorXd> Correct(const Problem& p, Eigen::VectorXd y, const Eigen::VectorXd& t,
                                       int& iterations) {
  const auto N = y.size();
  const Eigen::VectorXd pred = y;
  for (iterations = 0; iterations < 10; ++iterations) {
    const Evaluation e = p.Evaluate(y.head(N - 1), y[N - 1]);
    if (!e.ok) return std::nullopt;
    const double res = e.G.cwiseAbs().maxCoeff() / (1.0 + y.head(N - 1).cwiseAbs().maxCoeff());
    if (res < 1e-11) return y;
    Eigen::MatrixXd J(N, N);
    J.topLeftCorner(N - 1, N - 1) = e.Jz;
    J.topRightCorner(N - 1, 1) = e.Jl;
    J.bottomRows(1) = t.transpose();
    Eigen::VectorXd r(N);
    r << e.G, t.dot(y - pred);
    y -= J.fullPivLu().solve(r);
  }
  return std::nullopt;
}

bool Sticks(const OrbitResult& o) { return !o.summary.stick_phases.empty(); }

// The most negative real multiplier (the flip test), or 0 when there is none.
double MostNegativeReal(const std::vector<std::complex<double>>& mu) {
  double best = 0;
  for (const auto& m : mu)
    if (std::abs(m.imag()) < 1e-9 && m.real() < best) best = m.real();
  return best;
}

double LeadingComplex(const std::vector<std::complex<double>>& mu) {
  double best = 0;
  for (const auto& m : mu)
    if (std::abs(m.imag()) >= 1e-9) best = std::max(best, std::abs(m));
  return best;
}

}  // namespace

Branch Continue(const ContinuationRequest& req) {
  Branch br;
  const auto first_scene = req.scene_at(req.from);
  const System first_sys(first_scene);
  const OrbitResult start = FindOrbit(first_sys, first_scene, req.orbit);
  if (start.status != "converged") {
    br.status = "no-orbit";
    br.end = "no orbit at the start: " + start.message;
    return br;
  }
  const Problem p(req, start.section_time, start.period);
  const auto n2 = start.X.size() * 2;
  Eigen::VectorXd y(n2 + 1);
  y << start.X, start.V, req.from;
  const double span = req.to - req.from;
  double ds = req.step > 0 ? req.step : std::abs(span) / 50.0;
  const double ds_max = req.max_step > 0 ? req.max_step : std::abs(span) / 10.0;
  const double ds_min = 1e-10 * std::max(1.0, std::abs(span));
  const auto record = [&](const OrbitResult& o, double value) {
    br.points.push_back({value, o.summary, o.multipliers, o.stable});
  };
  record(start, req.from);
  Evaluation e = p.Evaluate(y.head(n2), y[n2]);
  if (!e.ok) {
    br.end = "the map could not be evaluated at the start";
    return br;
  }
  // Initial tangent towards `to`.
  Eigen::VectorXd t = Tangent(e, Eigen::VectorXd());
  if (t[n2] * span < 0) t = -t;
  OrbitResult prev = start;

  while (static_cast<int>(br.points.size()) < req.max_points) {
    int iterations = 0;
    std::optional<Eigen::VectorXd> next = Correct(p, y + ds * t, t, iterations);
    std::optional<OrbitResult> orbit;
    if (next) orbit = p.Characterized(next->head(n2), (*next)[n2]);
    const bool same_kind = orbit && orbit->summary.kind == prev.summary.kind && Sticks(*orbit) == Sticks(prev);
    if (!next || !same_kind) {
      if (ds > ds_min * 1e3) {
        ds *= 0.5;
        continue;
      }
      // The orbit cannot be continued: sticking lost if the sticking fraction was vanishing.
      if (Sticks(prev)) {
        // SP vanishes linearly (MODEL §6.3): secant iterations on SP(λ) = 0 from the last points.
        const auto& pts = br.points;
        double l1 = pts[pts.size() - 2].value, s1 = *pts[pts.size() - 2].summary.sticking_fraction;
        double l2 = pts.back().value, s2 = *pts.back().summary.sticking_fraction;
        Eigen::VectorXd z = y.head(n2);
        for (int it = 0; it < 30 && std::abs(s2) > 1e-14 && s2 != s1; ++it) {
          double l3 = l2 - s2 * (l2 - l1) / (s2 - s1);
          if (!std::isfinite(l3)) break;
          // Stay on the sticking side: approach the root from inside.
          const double guard = 1e-13 * std::max(1.0, std::abs(l3));
          l3 = l3 - std::copysign(guard, l3 - l2);
          const auto scene = p.SceneAt(l3);
          if (!scene) break;
          const System sys(*scene);
          // Natural-parameter Newton at λ = l3 from the last orbit.
          Eigen::VectorXd zz = z;
          bool ok = false;
          for (int k = 0; k < 12; ++k) {
            const MapValue m = StroboscopicMap(sys, *scene, start.section_time, zz.head(n2 / 2),
                                               zz.tail(n2 / 2), start.period);
            if (m.status != RunStatus::kOk) break;
            Eigen::VectorXd F(n2);
            F << m.X, m.V;
            const Eigen::VectorXd r = F - zz;
            if (r.cwiseAbs().maxCoeff() < 1e-13 * (1 + zz.cwiseAbs().maxCoeff())) {
              ok = true;
              break;
            }
            zz -= (m.jacobian - Eigen::MatrixXd::Identity(n2, n2)).fullPivLu().solve(r);
          }
          if (!ok) break;
          const OrbitResult o = p.Characterized(zz, l3);
          if (!Sticks(o)) break;
          l1 = l2;
          s1 = s2;
          l2 = l3;
          s2 = *o.summary.sticking_fraction;
          z = zz;
        }
        const double at = (s2 != s1 && std::isfinite(s1)) ? l2 - s2 * (l2 - l1) / (s2 - s1) : l2;
        br.bifurcations.push_back({"sticking-lost", at,
                                   fmt::format("the sticking phase shrinks to zero (SP = {:.1e} at "
                                               "the last orbit)", s2)});
        br.end = "sticking-lost";
      } else {
        br.end = !next ? "the corrector failed (the orbit ends or becomes non-smooth)"
                       : "the orbit changed kind to " + orbit->summary.kind;
      }
      return br;
    }
    // Accept the point.
    const Eigen::VectorXd y_new = *next;
    const Evaluation en = p.Evaluate(y_new.head(n2), y_new[n2]);
    if (!en.ok) {
      br.end = "the map could not be evaluated";
      return br;
    }
    const Eigen::VectorXd t_new = Tangent(en, t);
    // Bifurcations between the last point and this one, located by bisection of the arclength
    // (each trial point corrected onto the branch) on the sign of a test function.
    const double l_old = y[n2], l_new = y_new[n2];
    const auto locate = [&](const std::function<double(const Eigen::VectorXd&, const Eigen::VectorXd&)>& test,
                            double fallback) {
      double lo = 0.0, hi = ds, value = fallback;
      const double sign_lo = test(y, t);
      for (int it = 0; it < 80; ++it) {
        const double mid = 0.5 * (lo + hi);
        int iters = 0;
        const auto yc = Correct(p, y + mid * t, t, iters);
        if (!yc) break;
        const Evaluation ec = p.Evaluate(yc->head(n2), (*yc)[n2]);
        if (!ec.ok) break;
        const double v = test(*yc, Tangent(ec, t));
        value = (*yc)[n2];
        ((v > 0) == (sign_lo > 0) ? lo : hi) = mid;
        if ((hi - lo) * std::abs(t[n2]) < 1e-12 * std::max(1.0, std::abs(value)) && it > 10) break;
      }
      return value;
    };
    if (t[n2] * t_new[n2] < 0) {
      const double at = locate([&](const Eigen::VectorXd&, const Eigen::VectorXd& tc) { return tc[n2]; },
                               0.5 * (l_old + l_new));
      br.bifurcations.push_back({"fold", at, "the branch turns back (λ-tangent changes sign)"});
    }
    const auto multiplier_test = [&](auto score) {
      return [&, score](const Eigen::VectorXd& yc, const Eigen::VectorXd&) {
        return score(p.Characterized(yc.head(n2), yc[n2]).multipliers);
      };
    };
    const double flip_old = MostNegativeReal(prev.multipliers), flip_new = MostNegativeReal(orbit->multipliers);
    if ((flip_old + 1) * (flip_new + 1) < 0 && (flip_old < 0 || flip_new < 0)) {
      const double w = (flip_old + 1) / (flip_old - flip_new);
      const double at = locate(multiplier_test([](const auto& mu) { return MostNegativeReal(mu) + 1; }),
                               l_old + w * (l_new - l_old));
      br.bifurcations.push_back({"flip", at, "a real multiplier crosses −1"});
    }
    const double ns_old = LeadingComplex(prev.multipliers), ns_new = LeadingComplex(orbit->multipliers);
    if (ns_old > 0 && ns_new > 0 && (ns_old - 1) * (ns_new - 1) < 0) {
      const double w = (ns_old - 1) / (ns_old - ns_new);
      const double at = locate(multiplier_test([](const auto& mu) { return LeadingComplex(mu) - 1; }),
                               l_old + w * (l_new - l_old));
      br.bifurcations.push_back({"neimark-sacker", at, "a complex pair of multipliers crosses the unit circle"});
    }
    y = y_new;
    t = t_new;
    prev = *orbit;
    record(*orbit, l_new);
    if ((l_new - req.to) * span >= 0) {
      br.end = "reached the end value";
      return br;
    }
    if (iterations <= 3) ds = std::min(ds * 1.5, ds_max);
  }
  br.end = "max points";
  return br;
}

}  // namespace vibro
