// Branch switching at a branch point or a flip (see include/vibro/branch_switch.hpp).
#include "vibro/branch_switch.hpp"

#include <cmath>
#include <optional>

#include <fmt/format.h>

#include "vibro/poincare.hpp"
#include "vibro/system.hpp"

namespace vibro {
namespace {

// G(y) = F^p(z; λ) − z on the section ωt0 = phase, with D_zG and ∂_λG (central differences in λ,
// as continuation takes them: λ is any numeric scene key).
class SectionMap {
 public:
  SectionMap(const SwitchRequest& req, double phase) : req_(req), phase_(phase) {}

  std::optional<Scene> SceneAt(double lambda) const {
    try {
      return req_.scene_at(lambda);
    } catch (const std::exception&) {
      return std::nullopt;  // λ left the key's valid range
    }
  }
  double phase() const { return phase_; }

  // F^p(z) at λ (and DF^p when jac is given); none when the map fails or has no derivative there.
  std::optional<Eigen::VectorXd> Map(const Eigen::VectorXd& z, double lambda, int p, Eigen::MatrixXd* jac) const {
    auto scene = SceneAt(lambda);
    if (!scene) return std::nullopt;
    const System sys(*scene);
    const auto n = sys.dof();
    const double t0 = phase_ / scene->frequency;
    MapValue m = StroboscopicMap(sys, *scene, t0, z.head(n), z.tail(n), p);
    // A chattering sequence double cannot decide: the exact engine decides it in quad (as
    // continuation does, docs/chattering.md).
    if (m.status == RunStatus::kUndetermined && scene->run.precision == Precision::kDouble &&
        scene->run.engine == Engine::kExact) {
      scene->run.precision = Precision::kQuad;
      m = StroboscopicMap(sys, *scene, t0, z.head(n), z.tail(n), p);
    }
    if (m.status != RunStatus::kOk || m.singular || (jac && !m.undefined.empty())) return std::nullopt;
    if (jac) *jac = m.jacobian;
    Eigen::VectorXd out(2 * n);
    out << m.X, m.V;
    return out;
  }

  struct Value {
    Eigen::VectorXd G;   // F^p(z) − z
    Eigen::MatrixXd Jz;  // DF^p − I
    Eigen::VectorXd Jl;  // ∂F^p/∂λ
  };
  std::optional<Value> Evaluate(const Eigen::VectorXd& y, int p) const {
    const auto N = y.size() - 1;
    const Eigen::VectorXd z = y.head(N);
    const double lambda = y[N];
    Eigen::MatrixXd DF;
    const auto F = Map(z, lambda, p, &DF);
    if (!F) return std::nullopt;
    const double h = 1e-6 * std::max(1.0, std::abs(lambda));
    const auto Fp = Map(z, lambda + h, p, nullptr), Fm = Map(z, lambda - h, p, nullptr);
    if (!Fp && !Fm) return std::nullopt;
    Value v;
    v.G = *F - z;
    v.Jz = DF - Eigen::MatrixXd::Identity(N, N);
    v.Jl = Fp && Fm ? Eigen::VectorXd((*Fp - *Fm) / (2 * h))
           : Fp     ? Eigen::VectorXd((*Fp - *F) / h)
                    : Eigen::VectorXd((*F - *Fm) / h);
    return v;
  }

  // Newton on {G(y) = 0, normalᵀ(y − anchor) = 0} from y, to the tolerance continuation uses.
  std::optional<Eigen::VectorXd> Correct(Eigen::VectorXd y, const Eigen::VectorXd& normal,
                                         const Eigen::VectorXd& anchor, int p) const {
    const auto N = y.size();
    double last = 0;
    for (int it = 0; it < 16; ++it) {
      if (req_.stop_requested && req_.stop_requested->load()) return std::nullopt;
      const auto e = Evaluate(y, p);
      if (!e) return std::nullopt;
      const double res = e->G.cwiseAbs().maxCoeff() / (1.0 + y.head(N - 1).cwiseAbs().maxCoeff());
      if (res < 1e-13 || (res < 1e-11 && it > 0 && res > 0.1 * last)) return y;
      last = res;
      Eigen::MatrixXd J(N, N);
      J.topLeftCorner(N - 1, N - 1) = e->Jz;
      J.topRightCorner(N - 1, 1) = e->Jl;
      J.bottomRows(1) = normal.transpose();
      Eigen::VectorXd r(N);
      r << e->G, normal.dot(y - anchor);
      y -= J.fullPivLu().solve(r);
      if (!y.allFinite()) return std::nullopt;
    }
    return std::nullopt;
  }

  // The unit null vector of [D_zG ∂_λG] at y (the branch's tangent where it is unique).
  std::optional<Eigen::VectorXd> Tangent(const Eigen::VectorXd& y, int p) const {
    const auto e = Evaluate(y, p);
    if (!e) return std::nullopt;
    Eigen::MatrixXd A(e->Jz.rows(), e->Jz.cols() + 1);
    A << e->Jz, e->Jl;
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(A, Eigen::ComputeFullV);
    return Eigen::VectorXd(svd.matrixV().col(A.cols() - 1));
  }

 private:
  const SwitchRequest& req_;
  double phase_;
};

Eigen::VectorXd Unit(Eigen::Index N, Eigen::Index k) {
  Eigen::VectorXd e = Eigen::VectorXd::Zero(N);
  e[k] = 1.0;
  return e;
}

}  // namespace

SwitchResult SwitchBranch(const SwitchRequest& req) {
  SwitchResult out;
  if (req.kind != "branch-point" && req.kind != "flip") {
    out.message = fmt::format("cannot switch at a {}: only at a branch-point or a flip", req.kind);
    return out;
  }
  const auto scene_k = [&]() -> std::optional<Scene> {
    try {
      return req.scene_at(req.from_value);
    } catch (const std::exception&) {
      return std::nullopt;
    }
  }();
  if (!scene_k) {
    out.message = "the scene is not valid at the stored point's parameter value";
    return out;
  }
  const int q = req.period, p = req.kind == "flip" ? 2 * req.period : req.period;
  const double cycle = 2.0 * M_PI * q;
  const double phase = std::fmod(scene_k->frequency * req.section_time, cycle);
  const SectionMap map(req, phase < 0 ? phase + cycle : phase);
  const auto n = req.X.size();
  const auto n2 = 2 * n, N = n2 + 1;
  const Eigen::VectorXd e_lambda = Unit(N, n2);
  const auto stopped = [&] { return req.stop_requested && req.stop_requested->load(); };

  // 1. Two points of the old branch at λ* ∓ δ, on the stored point's side first; their midpoint
  // and chord stand for the bifurcation point and the old branch's tangent there.
  Eigen::VectorXd yk(N);
  yk << req.X, req.V, req.from_value;
  const double lstar = req.value;
  const double side = lstar >= req.from_value ? 1.0 : -1.0;
  const double delta = std::max(1e-3 * std::abs(lstar - req.from_value), 1e-8 * std::max(1.0, std::abs(lstar)));
  const auto old_at = [&](const Eigen::VectorXd& from, double lambda) -> std::optional<Eigen::VectorXd> {
    const auto t = map.Tangent(from, p);
    if (!t || std::abs((*t)[n2]) < 1e-12) return std::nullopt;
    Eigen::VectorXd pred = from + ((lambda - from[n2]) / (*t)[n2]) * *t;
    pred[n2] = lambda;
    return map.Correct(pred, e_lambda, pred, p);
  };
  const auto ym = old_at(yk, lstar - side * delta);
  const auto yp = ym ? old_at(*ym, lstar + side * delta) : std::nullopt;
  if (stopped()) {
    out.message = "interrupted";
    return out;
  }
  if (!ym || !yp) {
    out.message = fmt::format("the old branch could not be corrected at λ = {:.15g} ± {:.1e} (its orbit near the "
                              "bifurcation)", lstar, delta);
    return out;
  }
  const Eigen::VectorXd ystar = 0.5 * (*ym + *yp);
  const Eigen::VectorXd chord = (*yp - *ym).normalized();
  out.located = ystar[n2];

  // 2. The kernel φ of D_zG at y*: the second direction d = (φ, 0) − ((φ, 0)·t) t.
  const auto es = map.Evaluate(ystar, p);
  if (!es) {
    out.message = "the map could not be evaluated at the bifurcation";
    return out;
  }
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(es->Jz, Eigen::ComputeFullV);
  const Eigen::VectorXd phi = svd.matrixV().col(n2 - 1);
  Eigen::VectorXd d = Eigen::VectorXd::Zero(N);
  d.head(n2) = phi;
  d -= d.dot(chord) * chord;
  if (d.norm() < 1e-6) {
    out.message = "the kernel at the bifurcation is the old branch's own tangent (a fold, not a branch point)";
    return out;
  }
  d.normalize();
  Eigen::VectorXd e_phi = Eigen::VectorXd::Zero(N);  // the predictor's direction (φ, 0): exact at a pitchfork
  e_phi.head(n2) = phi;
  const auto sys_star = map.SceneAt(lstar);
  const System sys(*sys_star);
  const double scale = std::max(1.0, ystar.head(n2).cwiseAbs().maxCoeff());

  // 3. From y* ± h (φ, 0) (scaled so that its d-component is h) onto the new branch, on the
  // hyperplane normal to d through the predictor.
  for (const double sigma : {1.0, -1.0}) {
    if (req.kind == "flip" && !out.starts.empty()) break;  // the other half is the same orbit, q periods on
    for (const double rel : {1e-4, 1e-3, 1e-5, 1e-2, 3e-2}) {
      if (stopped()) {
        out.message = "interrupted";
        return out;
      }
      const double h = rel * scale;
      const Eigen::VectorXd pred = ystar + sigma * (h / d.dot(e_phi)) * e_phi;
      const auto ys = map.Correct(pred, d, pred, p);
      if (!ys || ((*ys) - pred).norm() > 0.3 * h) continue;
      // Off the old branch (its chord through y*), and at a flip no orbit of period q.
      const double lambda = (*ys)[n2];
      const Eigen::VectorXd old = ystar + ((lambda - ystar[n2]) / chord[n2]) * chord;
      const double dist = ((*ys) - old).head(n2).cwiseAbs().maxCoeff();
      if (dist < 0.25 * h * phi.cwiseAbs().maxCoeff()) continue;
      if (req.kind == "flip") {
        const auto Fq = map.Map(ys->head(n2), lambda, q, nullptr);
        if (!Fq || (*Fq - ys->head(n2)).cwiseAbs().maxCoeff() < 0.1 * h * phi.cwiseAbs().maxCoeff()) continue;
      }
      auto t = map.Tangent(*ys, p);
      if (!t) continue;
      if (t->dot(d) * sigma < 0) *t = -*t;
      SwitchStart s;
      s.value = lambda;
      const auto sc = map.SceneAt(lambda);
      s.section_time = map.phase() / sc->frequency;
      s.X = ys->head(n);
      s.V = ys->segment(n, n);
      s.period = p;
      const double off = lambda - ystar[n2];
      s.direction = std::abs(off) > 1e-12 * std::max(1.0, std::abs(lstar)) ? (off > 0 ? 1 : -1)
                                                                             : ((*t)[n2] >= 0 ? 1 : -1);
      s.x_B_offset = sys.ContactDisplacement(s.X) - sys.ContactDisplacement(old.head(n));
      s.distance = dist;
      out.starts.push_back(std::move(s));
      break;
    }
  }
  out.ok = !out.starts.empty();
  out.message = out.ok ? fmt::format("{} new half-branch(es) from the {} at {:.15g}", out.starts.size(), req.kind,
                                     out.located)
                       : fmt::format("no second branch found through the {} at {:.15g} (Newton from y* ± h d "
                                     "returned to the old branch or failed for every h)",
                                     req.kind, out.located);
  return out;
}

}  // namespace vibro
