// Basins and coexisting attractors: many independent simulations in parallel (oneTBB).
#include "vibro/studies.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <random>
#include <exception>

#include "analysis/parallel_for.hpp"
#include "vibro/poincare.hpp"
#include "vibro/simulator.hpp"
#include "vibro/stop_request.hpp"

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
    // Compared as text first: an index of more digits than any DOF count would overflow stoi.
    const auto digits = name.find_first_not_of('0', 1);
    const int i = digits == std::string::npos ? 0 : name.size() - digits > 6 ? -1 : std::stoi(name.substr(1));
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

namespace {

// Stops a cell's run once its motion has settled (AttractorRecorder::Settled) or reached a known
// orbit, and passes a stop request of the whole study on. Polled by the automaton between events.
class SettleWatch final : public Observer {
 public:
  SettleWatch(const AttractorRecorder& rec, const StudyOptions& opt) : rec_(rec), opt_(opt) {
    for (const KnownOrbit& o : opt_.known)
      for (const Eigen::VectorXd& z : o.points) known_amax_.push_back(z.cwiseAbs().maxCoeff());
  }
  void OnEvent(const Event&) override { Poll(); }
  void OnSection(const Sample& s) override {
    Poll();
    if (opt_.settle_remainder <= 0 || reason_ != 0) return;
    // A known orbit reached at two consecutive periods.
    const int near = Near(s);
    if (near >= 0 && near == last_near_) {
      reason_ = 2;
    } else if (rec_.Settled(opt_.settle_remainder)) {
      reason_ = 1;
    }
    last_near_ = near;
    if (reason_ != 0) stop_.store(true, std::memory_order_relaxed);
  }
  const std::atomic<bool>* flag() const { return &stop_; }
  int reason() const { return reason_; }
  int known() const { return last_near_; }

 private:
  void Poll() {
    if (opt_.stop_requested && opt_.stop_requested->load(std::memory_order_relaxed))
      stop_.store(true, std::memory_order_relaxed);
  }
  int Near(const Sample& s) const {
    const auto n = s.X.size();
    const double here = std::max(s.X.cwiseAbs().maxCoeff(), s.V.cwiseAbs().maxCoeff());
    size_t point = 0;  // index into known_amax_
    for (size_t k = 0; k < opt_.known.size(); ++k) {
      const KnownOrbit& o = opt_.known[k];
      for (size_t j = 0; j < o.points.size(); ++j, ++point) {
        if (o.modes[j] != s.mode) continue;
        const Eigen::VectorXd& z = o.points[j];
        const double scale = 1.0 + std::max(known_amax_[point], here);
        const double d = std::max((s.X - z.head(n)).cwiseAbs().maxCoeff(),
                                  (s.V - z.tail(n)).cwiseAbs().maxCoeff());
        if (d <= o.radius * scale) return static_cast<int>(k);
      }
    }
    return -1;
  }
  const AttractorRecorder& rec_;
  const StudyOptions& opt_;
  std::vector<double> known_amax_;  // |z|∞ of every known orbit's points, in order
  std::atomic<bool> stop_{false};
  int reason_ = 0, last_near_ = -1;
};

// The Lyapunov exponents of a run of scene.run.periods periods from a cell's final state `z` at
// t0 + periods·T (a state on the stop re-enters through the automaton's classification of a
// state on the stop, as a sweep's next run). A run that does not end ok has none, and says why.
LyapunovSpectrum LyapunovFrom(const System& sys, const Scene& scene, const CellResult& c) {
  Scene sc = scene;
  sc.run.samples_per_period = 0;
  const auto n = c.z.size() / 2;
  InitialOverride start{scene.initial_time + static_cast<double>(c.periods) * sys.period(), c.z.head(n),
                        c.z.tail(n)};
  if (sys.ContactDisplacement(start.X) <= sys.stop())
    start.X -= sys.contact() * ((sys.ContactDisplacement(start.X) - sys.stop()) / sys.s_B());
  LyapunovObserver ly(sys, sc);
  SimulationOptions so;
  so.initial = &start;
  so.observers = {&ly};
  const RunResult r = Simulate(sys, sc, so);
  if (r.status == RunStatus::kOk) return ly.Spectrum();
  LyapunovSpectrum none;
  none.undefined = std::string("the run that measures them ended ") + ToString(r.status) +
                   (r.message.empty() ? std::string() : ": " + r.message);
  return none;
}

// Section points and modes of one period (q sections) from a state at time t.
struct SectionLog final : Observer {
  std::vector<Eigen::VectorXd> z;
  std::vector<Mode> modes;
  void OnSection(const Sample& s) override {
    Eigen::VectorXd v(2 * s.X.size());
    v << s.X, s.V;
    z.push_back(std::move(v));
    modes.push_back(s.mode);
  }
};

// Cell order of first appearance → label.
std::vector<int> Renumber(std::vector<int>& labels, size_t classes) {
  std::vector<int> map(classes, -1);
  int next = 0;
  for (int& l : labels) {
    if (l < 0) continue;
    int& m = map[static_cast<size_t>(l)];
    if (m < 0) m = next++;
    l = m;
  }
  return map;
}

}  // namespace

int KindCode(const std::string& kind) {
  if (kind == "sticking-periodic") return 1;
  if (kind == "impact-periodic") return 2;
  if (kind == "no-contact-periodic") return 3;
  if (kind == "permanent-contact") return 4;
  return 0;
}

std::string KindName(int code) {
  switch (code) {
    case 1: return "sticking-periodic";
    case 2: return "impact-periodic";
    case 3: return "no-contact-periodic";
    case 4: return "permanent-contact";
    default: return "not-periodic";
  }
}

// Layout: state, kind, period (0: none), impacts (−1: none), sticking fraction (NaN: none),
// periods, stop, #stick phases, pairs, #impacts, phases, velocities, contacts known (1 or 0),
// [stick contacts, impact contacts], #z, z.
void PackCell(const CellResult& c, std::vector<double>& out) {
  const Attractor& a = c.attractor;
  out.push_back(static_cast<double>(c.state));
  out.push_back(KindCode(a.kind));
  out.push_back(a.period.value_or(0));
  out.push_back(a.impacts_per_period ? static_cast<double>(*a.impacts_per_period) : -1.0);
  out.push_back(a.sticking_fraction.value_or(std::numeric_limits<double>::quiet_NaN()));
  out.push_back(static_cast<double>(c.periods));
  out.push_back(c.stop);
  out.push_back(static_cast<double>(a.stick_phases.size()));
  for (const auto& [s, e] : a.stick_phases) {
    out.push_back(s);
    out.push_back(e);
  }
  out.push_back(static_cast<double>(a.impact_phases.size()));
  out.insert(out.end(), a.impact_phases.begin(), a.impact_phases.end());
  out.insert(out.end(), a.impact_velocities.begin(), a.impact_velocities.end());
  // The contacts of the stick phases and impacts, or none (unknown).
  const bool contacts = a.stick_contacts.size() == a.stick_phases.size() &&
                        a.impact_contacts.size() == a.impact_phases.size();
  out.push_back(contacts ? 1.0 : 0.0);
  if (contacts) {
    out.insert(out.end(), a.stick_contacts.begin(), a.stick_contacts.end());
    out.insert(out.end(), a.impact_contacts.begin(), a.impact_contacts.end());
  }
  out.push_back(static_cast<double>(c.z.size()));
  out.insert(out.end(), c.z.data(), c.z.data() + c.z.size());
}

CellResult UnpackCell(const double*& p) {
  CellResult c;
  const auto count = [&p] { return static_cast<size_t>(*p++); };
  c.state = static_cast<CellResult::State>(static_cast<int>(*p++));
  Attractor& a = c.attractor;
  a.kind = KindName(static_cast<int>(*p++));
  if (const int q = static_cast<int>(*p++); q > 0) a.period = q;
  if (const double k = *p++; k >= 0) a.impacts_per_period = static_cast<long long>(k);
  if (const double sp = *p++; !std::isnan(sp)) a.sticking_fraction = sp;
  c.periods = static_cast<long long>(*p++);
  c.stop = static_cast<std::int8_t>(*p++);
  for (size_t i = 0, n = count(); i < n; ++i, p += 2) a.stick_phases.emplace_back(p[0], p[1]);
  const size_t ni = count();
  a.impact_phases.assign(p, p + ni);
  a.impact_velocities.assign(p + ni, p + 2 * ni);
  p += 2 * ni;
  if (*p++ != 0.0) {
    for (size_t i = 0; i < a.stick_phases.size(); ++i) a.stick_contacts.push_back(static_cast<int>(*p++));
    for (size_t i = 0; i < ni; ++i) a.impact_contacts.push_back(static_cast<int>(*p++));
  }
  const size_t nz = count();
  c.z = Eigen::Map<const Eigen::VectorXd>(p, static_cast<Eigen::Index>(nz));
  p += nz;
  return c;
}

namespace {

// A worker thread gets its thread-local storage of the libraries loaded after the program started
// (Python loads libstdc++ and libvibro with dlopen) on first use, from malloc; glibc ends the whole
// process with "cannot allocate memory for thread-local data: ABORT", exit 127, when that malloc
// fails. The first use was the first throw (std::bad_alloc needs libstdc++'s exception globals),
// i.e. exactly when memory had run out. Touched at the start of each parallel task, before it
// allocates anything, a refused allocation later is a std::bad_alloc like any other (MemoryError
// in Python, exit 3 from the command line). Two thread-local reads per task.
void ThreadLocalsFirst() {
  // Both are pure functions: the volatile stores keep the compiler from dropping the calls.
  const volatile int uncaught = std::uncaught_exceptions();  // libstdc++'s exception globals
  const volatile void* stop = ProcessStopFlag();             // libvibro's thread-local block
  static_cast<void>(uncaught);
  static_cast<void>(stop);
}

}  // namespace

void RunCells(const System& sys, const Scene& scene, const Coordinate& a, const Coordinate& b,
              const std::vector<std::pair<double, double>>& points,
              const std::vector<size_t>& indices, std::vector<CellResult>& cells,
              const StudyOptions& opt) {
  const auto n = static_cast<long long>(indices.size());
  std::atomic<long long> done{0};
  Scene sc = scene;
  sc.run.samples_per_period = 0;
  const auto cell = [&](size_t i) {
    if (opt.stop_requested && opt.stop_requested->load()) return;
    CellResult out;
    const auto start = StartOf(sys, sc, a, points[i].first, b, points[i].second);
    if (!start) {
      out.state = CellResult::State::kInadmissible;
    } else {
      AttractorRecorder rec(sys, sc);
      SettleWatch watch(rec, opt);
      SimulationOptions so;
      so.initial = &*start;
      so.observers = {&rec, &watch};
      so.stop_requested = watch.flag();
      const RunResult r = Simulate(sys, sc, so);
      if (r.status == RunStatus::kInterrupted && watch.reason() == 0) return;  // the study stops
      out.state = r.status == RunStatus::kNumericalFailure || r.status == RunStatus::kUndetermined
                      ? CellResult::State::kFailed
                      : CellResult::State::kClassified;
      out.stop = static_cast<std::int8_t>(watch.reason());
      if (out.state == CellResult::State::kClassified)
        out.attractor = watch.reason() == 2 ? opt.known[static_cast<size_t>(watch.known())].attractor
                                            : rec.Classify();
      out.periods = r.end.period;
      out.z.resize(2 * sys.dof());
      out.z << r.X, r.V;
    }
    cells[i] = std::move(out);
    const long long d = ++done;
    if (opt.progress) opt.progress(d, n);
  };
  detail::ParallelFor(indices.size(), opt.threads, [&](size_t begin, size_t end) {
    ThreadLocalsFirst();
    for (size_t k = begin; k != end; ++k) cell(indices[k]);
  });
}

StudyResult LabelCells(const System& sys, const Scene& scene,
                       const std::vector<std::pair<double, double>>& points,
                       const std::vector<CellResult>& cells, const StudyOptions& opt) {
  using State = CellResult::State;
  const auto n = static_cast<long long>(cells.size());
  StudyResult out;
  out.cells = n;
  out.labels.assign(cells.size(), -1);
  // 1. Classes of equal cell attractors, in cell order (the same for any thread count).
  std::vector<size_t> first_cell;  // of each class
  for (size_t i = 0; i < cells.size(); ++i) {
    const CellResult& c = cells[i];
    if (c.state == State::kPending) {
      out.labels[i] = -3;
      continue;
    }
    if (c.state == State::kInadmissible) {
      out.labels[i] = -2;
      continue;
    }
    if (c.state != State::kClassified || c.attractor.kind == "not-periodic") continue;
    int label = -1;
    for (size_t k = 0; k < out.attractors.size() && label < 0; ++k)
      if (SameAttractor(out.attractors[k].attractor, c.attractor)) label = static_cast<int>(k);
    if (label < 0) {
      label = static_cast<int>(out.attractors.size());
      out.attractors.push_back({c.attractor, 0, 0, 0, {points[i].first, points[i].second}, {}, {}});
      first_cell.push_back(i);
    }
    out.labels[i] = label;
  }
  // 2. Each class's orbit, solved from the final section point of its first cell; classes whose
  //    solved orbits are the same attractor are one (slow transients classified early).
  if (opt.solve_orbits && !out.attractors.empty()) {
    const size_t m = out.attractors.size();
    std::vector<std::optional<Attractor>> solved(m);
    std::vector<ClassOrbit> orbits(m);
    detail::ParallelFor(m, 0, [&](size_t begin, size_t end) {
      ThreadLocalsFirst();
      for (size_t k = begin; k != end; ++k) {
        const Attractor& a = out.attractors[k].attractor;
        if (a.kind != "sticking-periodic" && a.kind != "impact-periodic") continue;
        const CellResult& c = cells[first_cell[k]];
        OrbitRequest req;
        req.kind = a.kind == "impact-periodic" ? OrbitKind::kImpact : OrbitKind::kSticking;
        req.period = *a.period;
        req.transient_periods = 4 * *a.period + 4;
        const auto dof = c.z.size() / 2;
        req.start = InitialOverride{scene.initial_time + static_cast<double>(c.periods) * sys.period(),
                                    c.z.head(dof), c.z.tail(dof)};
        const OrbitResult r = FindOrbit(sys, scene, req);
        orbits[k].status = r.status;
        orbits[k].residual = r.residual;
        if (r.status != "converged") continue;
        orbits[k].multipliers = r.multipliers;
        orbits[k].stable = r.stable;
        solved[k] = r.summary;
      }
    });
    std::vector<int> merge(m);
    for (size_t k = 0; k < m; ++k) {
      merge[k] = static_cast<int>(k);
      for (size_t j = 0; j < k && solved[k]; ++j)
        if (merge[j] == static_cast<int>(j) && solved[j] && SameAttractor(*solved[j], *solved[k])) {
          merge[k] = static_cast<int>(j);
          ++orbits[j].merged;
          break;
        }
    }
    for (int& l : out.labels)
      if (l >= 0) l = merge[static_cast<size_t>(l)];
    std::vector<FoundAttractor> kept;
    const auto map = Renumber(out.labels, m);
    kept.resize(static_cast<size_t>(std::count_if(map.begin(), map.end(), [](int v) { return v >= 0; })));
    for (size_t k = 0; k < m; ++k) {
      if (map[k] < 0) continue;
      FoundAttractor& f = kept[static_cast<size_t>(map[k])];
      f = out.attractors[k];
      f.orbit = orbits[k];
      // A class is described by its solved orbit when there is one: its first cell may still be
      // a transient's width (up to run.period_tolerance) away from it, the orbit is not.
      if (solved[k] && solved[k]->kind == f.attractor.kind && solved[k]->period == f.attractor.period)
        f.attractor = *solved[k];
    }
    out.attractors = std::move(kept);
  }
  // 3. Counts and fractions.
  long long unresolved = 0, inadmissible = 0, pending = 0;
  for (int l : out.labels) {
    if (l >= 0) ++out.attractors[static_cast<size_t>(l)].cells;
    unresolved += l == -1;
    inadmissible += l == -2;
    pending += l == -3;
  }
  const double N = static_cast<double>(std::max(n, 1LL));
  for (auto& f : out.attractors) {
    const double p = static_cast<double>(f.cells) / N;
    f.basin_fraction = p;
    f.basin_fraction_error = std::sqrt(p * (1 - p) / N);
  }
  out.unresolved_fraction = static_cast<double>(unresolved) / N;
  out.inadmissible_fraction = static_cast<double>(inadmissible) / N;
  out.pending_fraction = static_cast<double>(pending) / N;
  // 4. Lyapunov exponents of each attractor, from its first cell's final state, and of the first
  //    not-periodic cell (deterministic: they depend only on `cells`). None for a study being
  //    stopped (its resumption measures them).
  const auto stopping = [](const std::atomic<bool>* flag) { return flag && flag->load(); };
  if (opt.lyapunov && scene.run.lyapunov && !stopping(opt.stop_requested) &&
      !stopping(ProcessStopFlag())) {
    std::vector<size_t> from(out.attractors.size() + 1, cells.size());  // the last: not-periodic
    for (size_t i = 0; i < cells.size(); ++i) {
      const int l = out.labels[i];
      if (l >= 0 && from[static_cast<size_t>(l)] == cells.size()) from[static_cast<size_t>(l)] = i;
      if (l == -1 && from.back() == cells.size() && cells[i].state == State::kClassified) from.back() = i;
    }
    std::vector<std::optional<LyapunovSpectrum>> spectra(from.size());
    detail::ParallelFor(from.size(), 0, [&](size_t begin, size_t end) {
      ThreadLocalsFirst();
      for (size_t k = begin; k != end; ++k)
        if (from[k] < cells.size()) spectra[k] = LyapunovFrom(sys, scene, cells[from[k]]);
    });
    for (size_t k = 0; k < out.attractors.size(); ++k) out.attractors[k].lyapunov = std::move(spectra[k]);
    out.unresolved_lyapunov = std::move(spectra.back());
    if (out.unresolved_lyapunov) out.unresolved_example = {points[from.back()].first, points[from.back()].second};
  }
  return out;
}

std::vector<KnownOrbit> KnownOrbits(const System& sys, const Scene& scene, const Coordinate& a,
                                    const Coordinate& b, const StudyOptions& options) {
  StudyOptions opt = options;
  opt.known.clear();
  opt.progress = nullptr;
  opt.solve_orbits = true;
  opt.lyapunov = false;
  if (opt.settle_remainder <= 0) opt.settle_remainder = 1e-9;
  const auto pts = GridPoints(a, b, 8, 8);
  std::vector<CellResult> cells(pts.size());
  std::vector<size_t> all(pts.size());
  for (size_t i = 0; i < all.size(); ++i) all[i] = i;
  // The pilot runs at least a full record (4·max_period + 2 periods), so that a slowly attracting
  // orbit has shown that its transient has decayed (AttractorRecorder::Classify) and is known.
  Scene pilot_scene = scene;
  pilot_scene.run.periods = std::max<long long>(scene.run.periods, 4LL * scene.run.max_period + 2);
  RunCells(sys, pilot_scene, a, b, pts, all, cells, opt);
  if (opt.stop_requested && opt.stop_requested->load()) return {};
  const StudyResult pilot = LabelCells(sys, pilot_scene, pts, cells, opt);
  std::vector<KnownOrbit> known;
  for (size_t k = 0; k < pilot.attractors.size(); ++k) {
    const FoundAttractor& f = pilot.attractors[k];
    if (f.orbit.status != "converged" || !f.orbit.stable.value_or(false)) continue;
    double lead = 0;
    for (const auto& m : f.orbit.multipliers) lead = std::max(lead, std::abs(m));
    if (lead >= 0.9) continue;
    // The first cell of the class: its final state and the next period(s) of sections.
    size_t first = 0;
    while (pilot.labels[first] != static_cast<int>(k)) ++first;
    const CellResult& c = cells[first];
    const auto n = static_cast<Eigen::Index>(sys.dof());
    Scene sc = scene;
    sc.run.samples_per_period = 0;
    sc.run.periods = *f.attractor.period;
    const InitialOverride here{scene.initial_time + static_cast<double>(c.periods) * sys.period(),
                               c.z.head(n), c.z.tail(n)};
    SectionLog log;
    SimulationOptions so;
    so.initial = &here;
    so.observers = {&log};
    if (Simulate(sys, sc, so).status != RunStatus::kOk) continue;
    KnownOrbit o;
    o.attractor = c.attractor;
    o.points.assign(log.z.begin() + 1, log.z.end());  // the q section points after the start
    o.modes.assign(log.modes.begin() + 1, log.modes.end());
    known.push_back(std::move(o));
  }
  return known;
}

StudyResult RunStudy(const System& sys, const Scene& scene, const Coordinate& a, const Coordinate& b,
                     const std::vector<std::pair<double, double>>& points, const StudyOptions& options) {
  StudyOptions opt = options;
  if (opt.known.empty() && opt.settle_remainder > 0) opt.known = KnownOrbits(sys, scene, a, b, opt);
  std::vector<CellResult> cells(points.size());
  std::vector<size_t> all(points.size());
  for (size_t i = 0; i < all.size(); ++i) all[i] = i;
  RunCells(sys, scene, a, b, points, all, cells, opt);
  return LabelCells(sys, scene, points, cells, opt);
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
    // The classification checks that the transient has decayed and that the event log repeats
    // only on a full record (4·max_period + 1 periods): a sweep's run is never shorter, so that a
    // decaying free transient is not called periodic by aliasing (docs/reliability.md).
    sc.run.periods = std::max<long long>(sc.run.periods, 4LL * sc.run.max_period + 1);
    const System sys(sc);
    AttractorRecorder rec(sys, sc);
    SectionTail tail(static_cast<size_t>(req.record), sys);
    std::optional<LyapunovObserver> lyapunov;
    SimulationOptions opt;
    if (state) {
      state->time = sc.initial_time;  // phase kept: every run starts at the same forcing phase
      opt.initial = &*state;
    }
    opt.observers = {&rec, &tail};
      if (sc.run.lyapunov) opt.observers.push_back(&lyapunov.emplace(sys, sc));
    opt.stop_requested = stop;  // a run of many periods stops within the second too
    const RunResult r = Simulate(sys, sc, opt);
    if (r.status == RunStatus::kInterrupted) break;  // cut short: nothing to classify
    // A failed run ends the sweep; its partial record is not classified (it would be reported as
    // an attractor of a motion that was never computed to the end).
    const bool ok = r.status == RunStatus::kOk;
    out.push_back({values[i], i < up, ok ? rec.Classify() : Attractor{}, tail.x, tail.v,
                   ToString(r.status), ok ? std::string() : r.message,
                   ok && lyapunov ? std::optional(lyapunov->Spectrum()) : std::nullopt, {}, {}});
    if (!ok) break;
    // The next run continues from this one's final state, at a whole number of periods later.
    state = InitialOverride{sc.initial_time, r.X, r.V};
    if (r.mode == Mode::kSticking || sys.ContactDisplacement(r.X) <= sys.stop()) {
      // On the stop: re-enter through the automaton's classification of a state on the stop.
      state->X -= sys.contact() * ((sys.ContactDisplacement(r.X) - sys.stop()) / sys.s_B());
    }
    out.back().X = state->X;
    out.back().V = state->V;
  }
  return out;
}

}  // namespace vibro
