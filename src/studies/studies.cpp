// Basins and coexisting attractors: many independent simulations in parallel (oneTBB).
#include "vibro/studies.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <random>

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/global_control.h>
#include <oneapi/tbb/parallel_for.h>

#include "vibro/simulator.hpp"

namespace vibro {
namespace {

constexpr double kSame = 1e-6;  // phases and sticking fractions closer than this: same attractor

std::optional<InitialOverride> StartOf(const System& sys, const Scene& scene, const Coordinate& a,
                                       double va, const Coordinate& b, double vb) {
  const auto init = sys.Initial(scene);
  InitialOverride s{scene.initial_time, init.X, init.V};
  for (const auto& [c, v] : {std::pair{&a, va}, std::pair{&b, vb}}) {
    if (c->name == "x_B") {
      s.X = sys.static_shape() * v;
    } else if (c->name == "v_B") {
      s.V = sys.contact() * (v / sys.s_B());
    } else {
      const int i = std::stoi(c->name.substr(1)) - 1;
      (c->name[0] == 'X' ? s.X : s.V)[i] = v;
    }
  }
  const double gap = sys.ContactDisplacement(s.X) - sys.stop();
  if (gap < 0 || (gap == 0 && sys.ContactVelocity(s.V) < 0)) return std::nullopt;
  return s;
}

std::vector<double> Folded(const std::vector<double>& phases) {
  std::vector<double> out;
  for (double p : phases) {
    double q = std::fmod(p, 2 * M_PI);
    if (q < 0) q += 2 * M_PI;
    out.push_back(q);
  }
  std::sort(out.begin(), out.end());
  return out;
}

bool Close(const std::vector<double>& x, const std::vector<double>& y) {
  if (x.size() != y.size()) return false;
  for (size_t i = 0; i < x.size(); ++i) {
    const double d = std::abs(x[i] - y[i]);
    if (std::min(d, 2 * M_PI - d) > kSame) return false;
  }
  return true;
}

bool SameAttractor(const Attractor& x, const Attractor& y) {
  if (x.kind != y.kind || x.period != y.period || x.impacts_per_period != y.impacts_per_period)
    return false;
  if (x.sticking_fraction && y.sticking_fraction &&
      std::abs(*x.sticking_fraction - *y.sticking_fraction) > kSame)
    return false;
  std::vector<double> sx, sy;
  for (const auto& [s, e] : x.stick_phases) sx.push_back(s);
  for (const auto& [s, e] : y.stick_phases) sy.push_back(s);
  return Close(Folded(sx), Folded(sy)) && Close(Folded(x.impact_phases), Folded(y.impact_phases));
}

}  // namespace

std::string CheckCoordinate(const System& sys, const std::string& name) {
  if (name == "x_B" || name == "v_B") return {};
  if (name.size() >= 2 && (name[0] == 'X' || name[0] == 'V') &&
      std::all_of(name.begin() + 1, name.end(), [](char ch) { return std::isdigit(static_cast<unsigned char>(ch)); })) {
    const int i = std::stoi(name.substr(1));
    if (i >= 1 && i <= sys.dof()) return {};
    return "modal index out of range: 1 ≤ i ≤ " + std::to_string(sys.dof());
  }
  return "expected x_B, v_B, X<i> or V<i> (modal coordinate i, 1-based)";
}

std::vector<std::pair<double, double>> GridPoints(const Coordinate& a, const Coordinate& b, int nx,
                                                  int ny) {
  std::vector<std::pair<double, double>> pts;
  pts.reserve(static_cast<size_t>(nx) * static_cast<size_t>(ny));
  for (int iy = 0; iy < ny; ++iy)
    for (int ix = 0; ix < nx; ++ix)
      pts.emplace_back(a.from + (ix + 0.5) * (a.to - a.from) / nx,
                       b.from + (iy + 0.5) * (b.to - b.from) / ny);
  return pts;
}

std::vector<std::pair<double, double>> RandomPoints(const Coordinate& a, const Coordinate& b,
                                                    long long n, unsigned long long seed) {
  std::mt19937_64 gen(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<std::pair<double, double>> pts;
  for (long long i = 0; i < n; ++i) {
    const double x = a.from + u(gen) * (a.to - a.from);
    const double y = b.from + u(gen) * (b.to - b.from);
    pts.emplace_back(x, y);
  }
  return pts;
}

StudyResult RunStudy(const System& sys, const Scene& scene, const Coordinate& a, const Coordinate& b,
                     const std::vector<std::pair<double, double>>& points, const StudyOptions& opt) {
  const auto n = static_cast<long long>(points.size());
  std::vector<std::optional<Attractor>> found(points.size());
  std::vector<char> admissible(points.size(), 1);
  std::atomic<long long> done{0};
  Scene sc = scene;
  sc.run.samples_per_period = 0;
  const auto cell = [&](size_t i) {
    if (opt.stop_requested && opt.stop_requested->load()) return;
    const auto start = StartOf(sys, sc, a, points[i].first, b, points[i].second);
    if (!start) {
      admissible[i] = 0;
    } else {
      AttractorRecorder rec(sys, sc);
      SimulationOptions so;
      so.initial = &*start;
      so.observers = {&rec};
      const RunResult r = Simulate(sys, sc, so);
      if (r.status == RunStatus::kOk) found[i] = rec.Classify();
    }
    const long long d = ++done;
    if (opt.progress) opt.progress(d, n);
  };
  {
    std::optional<tbb::global_control> limit;
    if (opt.threads > 0)
      limit.emplace(tbb::global_control::max_allowed_parallelism, static_cast<size_t>(opt.threads));
    tbb::parallel_for(tbb::blocked_range<size_t>(0, points.size()),
                      [&](const tbb::blocked_range<size_t>& r) {
                        for (size_t i = r.begin(); i != r.end(); ++i) cell(i);
                      });
  }
  // Labels in cell order: the same for any thread count.
  StudyResult out;
  out.cells = n;
  out.labels.assign(points.size(), -1);
  long long unresolved = 0, inadmissible = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    if (!admissible[i]) {
      out.labels[i] = -2;
      ++inadmissible;
      continue;
    }
    if (!found[i] || found[i]->kind == "not-periodic") {
      ++unresolved;
      continue;
    }
    int label = -1;
    for (size_t k = 0; k < out.attractors.size() && label < 0; ++k)
      if (SameAttractor(out.attractors[k].attractor, *found[i])) label = static_cast<int>(k);
    if (label < 0) {
      label = static_cast<int>(out.attractors.size());
      out.attractors.push_back({*found[i], 0, 0, 0, {points[i].first, points[i].second}});
    }
    ++out.attractors[static_cast<size_t>(label)].cells;
    out.labels[i] = label;
  }
  for (auto& f : out.attractors) {
    const double p = static_cast<double>(f.cells) / static_cast<double>(std::max(n, 1LL));
    f.basin_fraction = p;
    f.basin_fraction_error = std::sqrt(p * (1 - p) / static_cast<double>(std::max(n, 1LL)));
  }
  out.unresolved_fraction = static_cast<double>(unresolved) / static_cast<double>(std::max(n, 1LL));
  out.inadmissible_fraction = static_cast<double>(inadmissible) / static_cast<double>(std::max(n, 1LL));
  return out;
}

namespace {

// Keeps the last `keep` section points.
struct SectionTail final : Observer {
  size_t keep;
  const System& sys;
  std::vector<double> x, v;
  Eigen::VectorXd X, V;
  SectionTail(size_t k, const System& s) : keep(k), sys(s) {}
  void OnSection(const Sample& s) override {
    x.push_back(s.x_B);
    v.push_back(sys.ContactVelocity(s.V));
    if (x.size() > keep) {
      x.erase(x.begin());
      v.erase(v.begin());
    }
  }
};

}  // namespace

std::vector<SweepPoint> Sweep(const SweepRequest& req, const std::atomic<bool>* stop) {
  std::vector<SweepPoint> out;
  std::vector<double> values;
  for (int i = 0; i <= req.steps; ++i)
    values.push_back(req.from + (req.to - req.from) * i / std::max(req.steps, 1));
  const size_t up = values.size();
  if (req.both_ways)
    for (int i = req.steps - 1; i >= 0; --i) values.push_back(values[static_cast<size_t>(i)]);
  std::optional<InitialOverride> state;
  for (size_t i = 0; i < values.size(); ++i) {
    if (stop && stop->load()) break;
    Scene sc = req.scene_at(values[i]);
    sc.run.samples_per_period = 0;
    const System sys(sc);
    AttractorRecorder rec(sys, sc);
    SectionTail tail(static_cast<size_t>(req.record), sys);
    SimulationOptions opt;
    if (state) {
      state->time = sc.initial_time;  // phase kept: every run starts at the same forcing phase
      opt.initial = &*state;
    }
    opt.observers = {&rec, &tail};
    const RunResult r = Simulate(sys, sc, opt);
    out.push_back({values[i], i < up, rec.Classify(), tail.x, tail.v});
    if (r.status != RunStatus::kOk) break;
    // The next run continues from this one's final state, at a whole number of periods later.
    state = InitialOverride{sc.initial_time, r.X, r.V};
    if (r.mode == Mode::kSticking || sys.ContactDisplacement(r.X) <= sys.stop()) {
      // On the stop: re-enter through the automaton's classification of a state on the stop.
      state->X -= sys.contact() * ((sys.ContactDisplacement(r.X) - sys.stop()) / sys.s_B());
    }
  }
  return out;
}

}  // namespace vibro
