// `vibro continue SCENE --param KEY --to B`: a branch of periodic orbits (docs/orbits.md).
#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>

#include <fmt/format.h>

#include "cli/cli_common.hpp"
#include "cli/progress.hpp"
#include "cli/stop_signals.hpp"
#include "frontend/switching.hpp"
#include "vibro/continuation.hpp"
#include "vibro/hdf5_branch.hpp"
#include "vibro/hdf5_store.hpp"
#include "vibro/rigid_model.hpp"
#include "vibro/scene_file.hpp"
#include "vibro/summary_json.hpp"
#include "vibro/system.hpp"

int RunContinue(const std::string& path, std::vector<std::string> sets, bool json,
                const std::string& key, double to, double step, int max_points,
                vibro::OrbitRequest orbit, const std::string& out, const std::string& restart_file,
                long long restart_point, const std::string& switch_side) {
  vibro::frontend::CheckContinuationOptions(vibro::frontend::Naming::kCli, to, step, max_points, orbit.period,
                                            orbit.transient_periods);
  std::optional<vibro::frontend::SwitchedStart> switched;
  if (!restart_file.empty()) {
    // Restart from a stored point: its parameter value, period and section state (Newton from
    // there, no transient).
    const auto pt = vibro::ReadBranchPoint(restart_file, restart_point);
    if (pt.param != key)
      throw vibro::InputError({fmt::format("--from {}: the branch varies {}, not --param {}", restart_file,
                                           pt.param, key)});
    sets.push_back(vibro::frontend::Assignment(key, pt.value));
    orbit.start = vibro::InitialOverride{pt.section_time, pt.X, pt.V};
    orbit.transient_periods = 0;
    orbit.period = pt.period;
  }
  auto loaded = vibro::LoadScene(path, sets);
  if (!restart_file.empty()) {
    // The stored state must be one this scene can start from, as [initial] is checked.
    const vibro::System at(loaded.scene);
    const auto& X = orbit.start->X;
    const auto& V = orbit.start->V;
    if (X.size() != at.dof())
      throw vibro::InputError({fmt::format("--from {}: /branch/X has {} columns (modal coordinates), the scene "
                                           "has {} mode(s): a branch of another scene",
                                           restart_file, X.size(), at.dof())});
    if (at.contact_count() == 1) {
      const double xB = at.ContactDisplacement(X), vB = at.ContactVelocity(V);
      const double x0 = loaded.scene.stop_position;
      const double tol = 1e-12 * std::max(1.0, std::abs(x0));
      if (xB < x0 - tol || (std::abs(xB - x0) <= tol && vB < 0))
        throw vibro::InputError({fmt::format("--from {}: /branch/X of point {}: expected an admissible state "
                                             "x_B ≥ x0 (moving away on the stop), found x_B = {}, ẋ_B = {}, x0 = {}",
                                             restart_file, restart_point, xB, vB, x0)});
    }
    for (int j = 0; j < at.contact_count() && at.contact_count() > 1; ++j) {
      const auto& c = at.contacts()[static_cast<size_t>(j)];
      const double g = c.shape.dot(X) - c.stop, gv = c.shape.dot(V);
      const double tol = 1e-12 * std::max(1.0, std::abs(c.stop));
      if (g < -tol || (std::abs(g) <= tol && gv < 0))
        throw vibro::InputError({fmt::format("--from {}: /branch/X of point {}: expected an admissible state "
                                             "(every gap ≥ 0, moving away where it is 0), found gap {} = {}, "
                                             "its velocity {}",
                                             restart_file, restart_point, j, g, gv)});
    }
  }
  if (!restart_file.empty() && !switch_side.empty()) {
    // The other branch through the bifurcation next to the stored point: its first orbit.
    try {
      switched = vibro::frontend::SwitchAtStoredPoint(
          [&](double v) { return vibro::frontend::SceneWith(path, sets, key, v); }, key, to, restart_file,
          restart_point, vibro::ReadBranchPoint(restart_file, restart_point), switch_side,
          vibro::frontend::Naming::kCli, &vibro::cli::StopFlag());
    } catch (const vibro::frontend::SwitchFailed& e) {
      fmt::print(stderr, "vibro: {}; nothing was written\n", e.what());
      return kExitNumerical;
    }
    sets.back() = vibro::frontend::Assignment(key, switched->value);
    orbit.start = vibro::InitialOverride{switched->section_time, switched->X, switched->V};
    orbit.period = switched->period;
    loaded = vibro::LoadScene(path, sets);
  }
  const auto from = vibro::SceneNumber(loaded.text_as_run, key);
  if (!from)
    throw vibro::InputError({key.find('[') == std::string::npos
                                 ? NotANumericKey("--param", key)
                                 : fmt::format("--param {}: not a numeric entry of the scene (give the "
                                               "array in the scene or with --set {}=[...])",
                                               key, key.substr(0, key.find('[')))});
  vibro::ContinuationRequest req;
  req.scene_at = [&](double v) { return vibro::frontend::SceneWith(path, sets, key, v); };
  req.from = *from;
  req.to = to;
  req.step = step;
  req.max_points = max_points;
  req.orbit = orbit;
  req.stop_requested = &vibro::cli::StopFlag();
  vibro::cli::Progress progress("continue", json);
  if (progress.active())
    req.progress = [&](size_t points, double value) {
      progress.Update(static_cast<long long>(points), max_points, fmt::format("{} = {:.10g}", key, value));
    };
  const vibro::System sys(loaded.scene);
  std::unique_ptr<vibro::Hdf5Store> store;
  if (!out.empty()) store = vibro::Hdf5Store::Create(out, vibro::frontend::HeaderOf(loaded, sys));  // fails early
  auto branch = vibro::Continue(req);
  branch.param = key;
  // A compliant stop: the rigid model's orbit beside every point (docs/compliant.md).
  if (vibro::HasCompliantContact(loaded.scene))
    vibro::AddRigidModelAlongBranch(branch, req.scene_at, req.orbit, &vibro::cli::StopFlag());
  // The file's status and the exit code say the same thing (docs/output.md).
  const vibro::RunStatus status = branch.status == "interrupted" ? vibro::RunStatus::kInterrupted
                                  : branch.status == "ok"        ? vibro::RunStatus::kOk
                                                                 : vibro::RunStatus::kNumericalFailure;
  if (store) {
    const vibro::cli::FinalWrite writing;
    store->WriteBranch(branch);
    vibro::RunResult r;
    r.status = status;
    r.message = branch.end;
    store->Finish(r, vibro::frontend::NoAttractor());  // a branch has no single attractor (the points are in /branch)
    store.reset();
  }
  if (branch.status == "no-orbit")
    fmt::print(stderr, "vibro: try {}--period Q, or --from FILE.h5 --point K to start from a stored branch point\n",
               orbit.kind == vibro::OrbitKind::kSticking   ? "--kind impact or --kind auto, "
               : orbit.kind == vibro::OrbitKind::kImpact ? "--kind sticking or --kind auto, "
                                                         : "--kind sticking|impact, ");
  if (switched && !json)
    fmt::print("switch       {} at {} = {:.15g}: the new branch (period {}) starts at {} = {:.15g}, {}\n",
               switched->kind, key, switched->at, switched->period, key, switched->value, switched->half);
  if (json) {
    if (switched)
      fmt::print("{}\n", vibro::BranchJson(branch, {switched->kind, switched->at, switched->value, switched->period,
                                                     switched->direction, switched->half, switched->x_B_offset,
                                                     switched->distance}));
    else
      fmt::print("{}\n", vibro::BranchJson(branch));
  } else {
    // Each point's exact mean contact force and normal work rate, per contact (docs/loads.md).
    size_t contacts = 0;
    for (const auto& p : branch.points) contacts = std::max(contacts, p.loads.size());
    std::string head;
    for (size_t j = 0; j < contacts; ++j)
      head += contacts == 1 ? fmt::format(" {:>12} {:>12}", "mean_force", "work_rate")
                            : fmt::format(" {:>12} {:>12}", fmt::format("mean_force{}", j), fmt::format("work_rate{}", j));
    // A compliant stop (docs/compliant.md, "Along a continued branch"): per contact the largest
    // certified peak force and the longest contact duration of the point's contact phases, and the
    // rigid model's distance.
    const bool compliant = std::any_of(branch.points.begin(), branch.points.end(),
                                       [](const auto& p) { return !p.contact_phases.empty(); });
    if (compliant) {
      for (size_t j = 0; j < contacts; ++j)
        head += contacts == 1 ? fmt::format(" {:>12} {:>12}", "peak_force", "duration")
                              : fmt::format(" {:>12} {:>12}", fmt::format("peak_force{}", j), fmt::format("duration{}", j));
      head += fmt::format(" {:>12}", "rigid_dist");
    }
    // Several contacts: the contact sequence of each point ("0:impact 1:impact") instead of the
    // one-stop event letters.
    const bool several = sys.contact_count() > 1;
    fmt::print("{:>16} {:>12} {:>8} {:>12}{}  {}\n", key, "SP", "stable", "max|mu|", head, several ? "sequence" : "events");
    for (const auto& p : branch.points) {
      double lead = 0;
      for (const auto& m : p.multipliers) lead = std::max(lead, std::abs(m));
      std::string loads;
      for (size_t j = 0; j < contacts; ++j) {
        const auto cell = [](double v) { return std::isfinite(v) ? fmt::format(" {:>12.6g}", v) : fmt::format(" {:>12}", "-"); };
        loads += j < p.loads.size() ? cell(p.loads[j].mean_force) + cell(p.loads[j].work_rate) : cell(std::nan("")) + cell(std::nan(""));
      }
      if (compliant) {
        const auto cell = [](double v) { return std::isfinite(v) ? fmt::format(" {:>12.6g}", v) : fmt::format(" {:>12}", "-"); };
        const vibro::ContactPhaseExtremes e = vibro::ExtremesOf(p.contact_phases, static_cast<int>(contacts));
        for (size_t j = 0; j < contacts; ++j) loads += cell(e.peak_force[j]) + cell(e.duration[j]);
        loads += cell(p.rigid_distance);
      }
      fmt::print("{:>16.10g} {:>12.8f} {:>8} {:>12.6g}{}  {}\n", p.value,
                 p.summary.sticking_fraction.value_or(0.0), p.stable ? "yes" : "no", lead, loads,
                 several ? p.sequence : p.signature);
    }
    for (const auto& b : branch.bifurcations)
      fmt::print("bifurcation  {} at {} = {:#.17g} (bracket {:.1e}): {}\n", b.kind, key, b.value, b.bracket, b.detail);
    for (const auto& r : branch.relabels)
      fmt::print("relabel      {} → {} at {} = {:#.17g} (bracket {:.1e}; no bifurcation): {}\n", r.from, r.to, key,
                 r.value, r.bracket, r.detail);
    fmt::print("end          {}\n", branch.end);
    if (!branch.corner.empty()) fmt::print("corner       {}\n", branch.corner);
    if (branch.quad_evaluations > 0)
      fmt::print("quad         {} map evaluations in quad precision (chattering sequences that double "
                 "leaves undetermined)\n", branch.quad_evaluations);
  }
  return ExitCode(status);
}
