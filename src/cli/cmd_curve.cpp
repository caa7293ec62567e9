// `vibro curve SCENE --param KEY1,KEY2 --kind KIND ...`: two-parameter curves of bifurcations
// (docs/diagram.md, "Two-parameter curves"). The checks, the start and the tracing are
// frontend/curves.hpp's, shared with Python's vibro.curve.
#include <algorithm>
#include <cmath>
#include <memory>

#include <fmt/format.h>

#include "cli/cli_common.hpp"
#include "cli/progress.hpp"
#include "cli/stop_signals.hpp"
#include "vibro/curve_output.hpp"
#include "vibro/hdf5_store.hpp"
#include "vibro/scene_file.hpp"
#include "vibro/system.hpp"

int RunCurve(const std::string& path, const std::vector<std::string>& sets, bool json, const CurveArgs& a) {
  const vibro::frontend::SceneOrigin origin{path, std::nullopt, path, sets};
  const auto loaded = origin.Load();
  const vibro::System sys(loaded.scene);
  vibro::cli::Progress progress("curve", json);
  const auto plan = vibro::frontend::PlanCurves(origin, loaded, a.spec, vibro::frontend::Naming::kCli);
  std::unique_ptr<vibro::Hdf5Store> store;
  if (!a.out.empty()) store = vibro::Hdf5Store::Create(a.out, vibro::frontend::HeaderOf(loaded, sys));  // fails early
  const auto curves = vibro::frontend::TraceCurves(plan, &vibro::cli::StopFlag(), [&](size_t c, size_t n, double x, double y) {
    if (progress.active())
      progress.Update(static_cast<long long>(n), a.spec.max_points, fmt::format("curve {}: ({:.8g}, {:.8g})", c, x, y));
  });
  const bool interrupted = vibro::cli::StopRequested();
  bool found = false;
  for (const auto& c : curves) found = found || c.status != "no-start";
  if (store) {
    const vibro::cli::FinalWrite writing;
    vibro::WriteCurves(*store, a.spec.params[0], a.spec.params[1], curves);
    vibro::RunResult r;
    r.status = interrupted ? vibro::RunStatus::kInterrupted : found ? vibro::RunStatus::kOk : vibro::RunStatus::kNumericalFailure;
    r.message = interrupted ? "interrupted" : found ? "ok" : "no curve was started";
    store->Finish(r, vibro::frontend::NoAttractor());
    store.reset();
  }
  const auto& k1 = a.spec.params[0];
  const auto& k2 = a.spec.params[1];
  if (json) {
    fmt::print("{}\n", vibro::CurvesJson(k1, k2, curves));
  } else {
    const bool several = sys.contact_count() > 1;
    for (size_t i = 0; i < curves.size(); ++i) {
      const auto& c = curves[i];
      fmt::print("curve {}      {}{} in ({}, {}), period {}: {} points ({} corrector lines), {}\n", i, c.kind,
                 c.contact >= 0 ? fmt::format(" on contact {}", c.contact) : "", k1, k2, c.period, c.points.size(),
                 c.corrections, c.status);
      if (!c.points.empty())
        fmt::print("{:>22} {:>22} {:>9} {:>7} {:>10}  {}\n", k1, k2, "bracket", "stable", "max|mu|",
                   several ? "sequence" : "events");
      for (const auto& p : c.points) {
        double lead = 0;
        for (const auto& m : p.multipliers) lead = std::max(lead, std::abs(m));
        fmt::print("{:>22.17g} {:>22.17g} {:>9.1e} {:>7} {:>10.6g}  {}\n", p.value1, p.value2, p.bracket,
                   p.stable ? "yes" : "no", lead, several ? p.sequence : p.signature);
      }
      for (const auto& s : c.special)
        fmt::print("codim-2      {} at ({:.12g}, {:.12g}) (bracket {:.1e}, between points {} and {}): {}\n", s.kind,
                   s.value1, s.value2, s.bracket, s.after, s.after + 1, s.detail);
      fmt::print("end          start side: {}\n", c.end_start);
      fmt::print("end          other side: {}\n", c.end_finish);
    }
  }
  if (interrupted) return kExitInterrupted;
  return found ? 0 : kExitNumerical;
}
