// Opening a run's or a study's output to create, resume or extend it (run_output.hpp).
#include "frontend/run_output.hpp"

#include <sys/resource.h>
#include <sys/stat.h>

#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "frontend/frontend.hpp"

namespace vibro::frontend {

namespace {
// "--out FILE.h5" or "out=FILE.h5".
std::string OutOption(Naming naming) { return naming == Naming::kCli ? "--out FILE.h5" : "out=FILE.h5"; }

// Every occurrence of `from` in `text` replaced by `to`.
std::string Replaced(std::string text, const std::string& from, const std::string& to) {
  for (size_t at = text.find(from); at != std::string::npos; at = text.find(from, at + to.size()))
    text.replace(at, from.size(), to);
  return text;
}

// The refusals of Hdf5Store::Resume, Extend and ResumeStudy (src/io) name the command line's
// options; from Python they name its arguments: --set KEY=VALUE → set={"KEY": VALUE}, --extend N
// → extend=N, --set overrides → set= overrides, --x-range → x_range, ...
InputError InTermsOf(Naming naming, const InputError& e) {
  if (naming == Naming::kCli) return e;
  std::vector<std::string> messages;
  for (std::string m : e.messages()) {
    m = Replaced(m, "--set overrides", "set= overrides");
    for (size_t at = m.find("--set "); at != std::string::npos; at = m.find("--set ", at + 1)) {
      const size_t eq = m.find('=', at), end = m.find_first_of(",;) ", eq);
      if (eq == std::string::npos) break;
      const std::string key = m.substr(at + 6, eq - at - 6);
      const std::string value = m.substr(eq + 1, end == std::string::npos ? std::string::npos : end - eq - 1);
      m.replace(at, (end == std::string::npos ? m.size() : end) - at, fmt::format("set={{\"{}\": {}}}", key, value));
    }
    // The options of a study's grid (ResumeStudy), longest first.
    for (const auto& [cli, python] : {std::pair{"--extend N", "extend=N"}, {"--x-range", "x_range"},
                                      {"--y-range", "y_range"}, {"--full-periods", "full_periods"},
                                      {"--grid", "grid"}, {"--x ", "x "}, {"--y ", "y "}})
      m = Replaced(m, cli, python);
    messages.push_back(m);
  }
  return InputError(messages);
}
}  // namespace

LoadedScene SceneToRun(const LoadedScene& given, const std::string& out, const RunContinuation& how, Naming naming) {
  if (how.resume && how.extend)
    throw InputError({fmt::format("{} and {}: give one (an extension also takes up an interrupted run)",
                                  OptionName(naming, "--resume"), OptionName(naming, "--extend"))});
  if ((how.resume || how.extend) && out.empty())
    throw InputError({fmt::format("{} needs {} (the file to continue)",
                                  OptionName(naming, how.extend ? "--extend" : "--resume"), OutOption(naming))});
  if (!how.extend) return given;
  // An extension runs the scene for the stored periods plus N (the file's run.periods becomes
  // that total).
  return ExtendedScene(given, out, *how.extend, OptionName(naming, "--extend").c_str());
}

namespace {
// A stored run taken up under a file-size limit (ulimit -f) that leaves it no room: refused before
// anything is changed (the first writes rewrite the file's metadata, and one cut short by the limit
// leaves a file no reader can open). Room: a megabyte past the file's size.
void CheckFileSizeLimit(const std::string& out) {
  struct rlimit limit {};
  struct stat st {};
  if (getrlimit(RLIMIT_FSIZE, &limit) != 0 || limit.rlim_cur == RLIM_INFINITY || stat(out.c_str(), &st) != 0) return;
  constexpr long long kRoom = 1LL << 20;
  if (static_cast<long long>(st.st_size) + kRoom > static_cast<long long>(limit.rlim_cur))
    throw WriteError(fmt::format("{}: the file-size limit of this process (ulimit -f, {} bytes) leaves no room to "
                                 "take up the run stored there ({} bytes); nothing was changed",
                                 out, static_cast<long long>(limit.rlim_cur), static_cast<long long>(st.st_size)));
}
}  // namespace

RunOutput::RunOutput(const std::string& out, const LoadedScene& loaded, const System& sys,
                     const RunContinuation& how, AttractorRecorder& recorder, LoadsRecorder* loads,
                     SimulationOptions& options, Naming naming) {
  if (out.empty()) return;
  const auto header = HeaderOf(loaded, sys);
  if (!how.resume && !how.extend) {
    store_ = Hdf5Store::Create(out, header);
  } else {
    CheckFileSizeLimit(out);
    try {
      store_ = how.extend ? Hdf5Store::Extend(out, header, stored_) : Hdf5Store::Resume(out, header, stored_);
    } catch (const InputError& e) {
      throw InTermsOf(naming, e);
    }
    options.resume_from = &*stored_.checkpoint;
    // Give the classification the history it would have had.
    for (size_t i = 0; i < stored_.tail_section_clocks.size(); ++i) {
      const auto& c = stored_.tail_section_clocks[i];
      recorder.OnSection({c, loaded.scene.initial_time + static_cast<double>(c.period) * sys.period(),
                          stored_.tail_section_X[i], stored_.tail_section_V[i],
                          sys.ContactDisplacement(stored_.tail_section_X[i]), stored_.tail_section_modes[i],
                          stored_.tail_section_modes[i] == Mode::kSticking ? -1 : 0});  // held: from the state
    }
    for (const auto& e : stored_.tail_events) recorder.OnEvent(e);
    // The loads of the periods before the checkpoint, as the run that went through summed them
    // (runs start at period 0).
    if (loads) {
      loads->Resumed(0, stored_.loads_known_from, *stored_.checkpoint);
      store_->ReplayLoads([&](const std::vector<LoadsRow>& rows) { loads->ReplayPeriod(rows); });
    }
  }
  if (loads) loads->SetSink(store_.get());
  options.observers.push_back(store_.get());
}

void RunOutput::NoteInterruption(RunResult& result, Naming naming) const {
  if (result.status != RunStatus::kInterrupted) return;
  result.message += store_ ? fmt::format("; everything so far is kept, continue with {}",
                                         naming == Naming::kCli ? "--resume" : "resume=True")
                           : fmt::format("; the results so far are reported (without {} there is nothing to resume)",
                                         OutOption(naming));
}

Hdf5Store::Stats RunOutput::Finish(const RunResult& result, const Attractor& attractor) {
  if (!store_) return {};
  store_->Finish(result, attractor);
  const auto written = store_->stats();
  store_.reset();
  return written;
}

void CheckStudyResume(const std::string& out, bool resume, Naming naming) {
  if (resume && out.empty())
    throw InputError({fmt::format("{} needs {} (the study to continue)", OptionName(naming, "--resume"),
                                  OutOption(naming))});
}

std::unique_ptr<Hdf5Store> OpenStudyOutput(const std::string& out, const StoreHeader& header,
                                           const Hdf5Store::StudyGrid& grid, bool resume,
                                           std::vector<CellResult>& cells, Naming naming) {
  CheckStudyResume(out, resume, naming);
  if (out.empty()) return nullptr;
  if (resume) try {
      return Hdf5Store::ResumeStudy(out, header, grid, cells);
    } catch (const InputError& e) {
      throw InTermsOf(naming, e);
    }
  auto store = Hdf5Store::Create(out, header);
  store->BeginStudy(grid);
  return store;
}

}  // namespace vibro::frontend
