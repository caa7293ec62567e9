// `vibro simulate SCENE [--out FILE.h5 [--resume | --extend N]]`: one run and its attractor
// (docs/cli.md). A resumed or extended run continues from the file's last checkpoint and writes
// the same bits as an uninterrupted run of its total length.
#include <cmath>
#include <memory>
#include <optional>

#include <fmt/format.h>

#include "cli/cli_common.hpp"
#include "cli/progress.hpp"
#include "cli/stop_signals.hpp"
#include "frontend/run_budget.hpp"
#include "frontend/run_output.hpp"
#include "vibro/attractor.hpp"
#include "vibro/hdf5_store.hpp"
#include "vibro/loads.hpp"
#include "vibro/lyapunov.hpp"
#include "vibro/rigid_model.hpp"
#include "vibro/scene_file.hpp"
#include "vibro/simulator.hpp"
#include "vibro/summary_json.hpp"
#include "vibro/system.hpp"

int RunSimulate(const std::string& path, const std::vector<std::string>& sets, bool json,
                const std::string& out, bool resume, long long extend, int blocks, double time_limit,
                bool rigid_beside) {
  vibro::frontend::RunContinuation how;
  how.resume = resume;
  if (extend > 0) how.extend = extend;
  const auto loaded =
      vibro::frontend::SceneToRun(vibro::LoadScene(path, sets), out, how, vibro::frontend::Naming::kCli);
  if (rigid_beside && !vibro::HasCompliantContact(loaded.scene))
    throw vibro::InputError({fmt::format("{}: --rigid-beside: the scene has no compliant stop (give a stop a "
                                         "stiffness, docs/compliant.md)", path)});
  const vibro::System sys(loaded.scene);
  vibro::AttractorRecorder recorder(sys, loaded.scene);
  vibro::SimulationOptions options;
  options.observers.push_back(&recorder);
  // Contact loads (docs/loads.md) over the run's periods, the first tenth left out (a resumed or
  // extended run: the whole run's, from the periods its file holds).
  vibro::LoadsRecorder loads(sys, loaded.scene.run.periods / 10);
  options.observers.push_back(&loads);
  std::optional<vibro::LyapunovObserver> lyapunov;
  // Compliant stops: no Lyapunov exponents (the tangent map has no contact phase yet, docs/compliant.md).
  if (loaded.scene.run.lyapunov && !vibro::HasCompliantContact(loaded.scene))
    options.observers.push_back(&lyapunov.emplace(sys, loaded.scene));
  options.stop_requested = &vibro::cli::StopFlag();
  // A new file, or the stored run taken up at its last checkpoint (frontend/run_output.hpp).
  std::optional<vibro::frontend::RunOutput> output(std::in_place, out, loaded, sys, how, recorder, &loads, options,
                                                   vibro::frontend::Naming::kCli);

  std::optional<vibro::cli::Progress> progress(std::in_place, "simulate", json);
  vibro::cli::PeriodProgress periods(*progress, loaded.scene.run.periods);
  if (progress->active()) options.observers.push_back(&periods);
  // The time and disk limits against the run's event rate: LimitError, exit 3 (main.cpp).
  vibro::frontend::RunBudget budget(sys, loaded.scene, time_limit, out, "--time-limit");
  options.observers.push_back(&budget);
  auto result = vibro::Simulate(sys, loaded.scene, options);
  output->NoteInterruption(result, vibro::frontend::Naming::kCli);
  progress.reset();
  const auto attractor = recorder.Classify();
  const vibro::LoadsSummary load_summary = loads.Summary(blocks);
  std::optional<vibro::LyapunovSpectrum> spectrum;
  if (lyapunov) spectrum = lyapunov->Spectrum();
  vibro::Hdf5Store::Stats written;
  if (output->store()) {
    const vibro::cli::FinalWrite writing;
    written = output->Finish(result, attractor);
  }
  output.reset();

  // The rigid model beside it (docs/compliant.md): both runs again, side by side.
  std::optional<vibro::RigidComparison> rigid;
  if (rigid_beside && result.status == vibro::RunStatus::kOk) rigid = vibro::CompareWithRigid(loaded.scene, blocks);
  if (json) {
    std::string summary = vibro::SimulationJson(loaded.scene, result, attractor, spectrum ? &*spectrum : nullptr,
                                                &load_summary);
    if (rigid) summary = summary.substr(0, summary.rfind('}')) + ",\"rigid_model\":" + vibro::RigidComparisonJson(*rigid) + "}";
    fmt::print("{}\n", summary);
  } else {
    fmt::print("scene        {}{}\n", path,
               loaded.scene.title.empty() ? "" : "  (" + loaded.scene.title + ")");
    fmt::print("engine       {}, {} precision, chatter {}\n",
               vibro::ToString(loaded.scene.run.engine),
               vibro::ToString(loaded.scene.run.precision),
               vibro::ToString(loaded.scene.run.chatter));
    fmt::print("status       {}{}\n", vibro::ToString(result.status),
               result.message.empty() ? "" : ": " + result.message);
    fmt::print("t_end        {:.10g} ({} periods)\n", result.t_end, result.end.period);
    fmt::print("events       {} impacts, {} accumulations, {} sticks, {} releases, {} grazings\n",
               result.counts.impacts, result.counts.accumulations, result.counts.sticks,
               result.counts.releases, result.counts.grazings);
    if (result.contact_counts.size() > 1) {
      const auto specs = vibro::Contacts(loaded.scene);
      for (size_t j = 0; j < result.contact_counts.size() && j < specs.size(); ++j) {
        const auto& c = result.contact_counts[j];
        const auto& k = specs[j];
        // Modal form: the contact's coordinate a_jᵀX (docs/contacts.md), named by its index.
        const std::string q = loaded.scene.modal       ? fmt::format("a{}·X", j)
                              : k.partner >= 0 ? fmt::format("q{} - q{}", k.dof, k.partner)
                                               : fmt::format("q{}", k.dof);
        fmt::print("  contact {}  {} {} {}: {} impacts ({} simultaneous), {} accumulations, {} sticks, "
                   "{} releases, {} grazings\n",
                   j, q, k.side == vibro::Side::kBelow ? ">=" : "<=", k.position,
                   c.impacts, c.simultaneous, c.accumulations, c.sticks, c.releases, c.grazings);
      }
    }
    // Only when a sequence chattered: impacts followed while no prediction was good enough are
    // those of every ordinary impact run too.
    if (result.chatter.accumulations_predicted > 0)
      fmt::print("chattering   {} accumulation points predicted (largest estimated error {:.2g} T, "
                 "target {:.2g} T), {} impacts followed before a prediction was good enough\n",
                 result.chatter.accumulations_predicted, result.chatter.max_estimated_error,
                 vibro::ChatterTolerance(loaded.scene.run), result.chatter.impacts_followed);
    // Several contacts: each impact has its contact's restitution (the sequence names the contacts).
    PrintAttractor(attractor, loaded.scene.contacts.size() > 1 ? std::nan("") : loaded.scene.restitution,
                   !loaded.scene.contacts.empty());
    PrintLoads(load_summary);
    if (rigid) PrintRigidComparison(*rigid);
    if (spectrum) PrintLyapunov(*spectrum);
    if (loaded.scene.run.engine == vibro::Engine::kCvode)
      fmt::print("cvode        {} ({}), rtol {:g}, atol {:g}: {} steps, {} rhs, {} root evals, "
                 "{} re-initialisations\n",
                 vibro::ToString(loaded.scene.run.method), "SUNDIALS 6.4", loaded.scene.run.rtol,
                 loaded.scene.run.atol, result.solver.steps, result.solver.rhs_evals,
                 result.solver.root_evals, result.solver.reinits);
    if (!out.empty())
      fmt::print("output       {}{} ({} flushes, {:.3f} s writing)\n", out,
                 extend > 0 ? fmt::format(" (extended by {} periods)", extend) : resume ? " (resumed)" : "",
                 written.flushes, written.flush_seconds);
  }
  if (result.status != vibro::RunStatus::kOk)
    fmt::print(stderr, "vibro: {}: {}\n", vibro::ToString(result.status), result.message);
  return ExitCode(result.status);
}
