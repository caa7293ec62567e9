// `vibro plot FILE.h5`: pictures of a vibro HDF5 file, drawn by vibro_plot.py (docs/cli.md).
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <set>

#include <fmt/format.h>

#include "cli/cli_common.hpp"
#include "cli/plot_script.hpp"
#include "vibro/hdf5_store.hpp"

int RunPlot(const std::string& path, const std::string& prefix, const std::string& overlay,
            const std::string& options) {
  for (const auto* name : {&path, &prefix, &overlay, &options})
    if (name->find('\'') != std::string::npos)
      throw vibro::InputError({"vibro plot: file names with a single quote are not supported"});
  vibro::ReadStoredRun(path);  // a clear error (exit 2) for a file that is not a vibro run
  std::vector<std::string> tried;
  const std::string script = vibro::cli::FindPlotScript(tried);
  if (script.empty()) {
    fmt::print(stderr, "vibro: plotting code not found (looked for {}); reinstall vibro\n",
               fmt::join(tried, " and "));
    return kExitInternal;
  }
  if (script.find('\'') != std::string::npos) {
    fmt::print(stderr, "vibro: cannot run the plotting code from a directory with a single quote: {}\n", script);
    return kExitInternal;
  }
  std::string cmd = fmt::format("'{}' '{}' '{}'", VIBRO_PYTHON, script, path);
  if (!prefix.empty()) cmd += fmt::format(" --out '{}'", prefix);
  if (!overlay.empty()) cmd += fmt::format(" --overlay '{}'", overlay);
  cmd += options;
  // The pictures written so far are named from the prefix (or the file): noted first, so that a
  // crash of the plotting process leaves nothing new behind.
  namespace fs = std::filesystem;
  const fs::path stem = prefix.empty() ? fs::path(path).replace_extension() : fs::path(prefix);
  const fs::path dir = stem.has_parent_path() ? stem.parent_path() : fs::path(".");
  const auto ours = [&] {
    std::set<fs::path> found;
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(dir, ec))
      if (e.path().filename().string().rfind(stem.filename().string(), 0) == 0) found.insert(e.path());
    return found;
  };
  const std::set<fs::path> before = ours();
  const int rc = std::system(cmd.c_str());
  // The script exits with 2 for bad input (an overlay that is not a continuation branch).
  if (WIFEXITED(rc) && WEXITSTATUS(rc) == kExitBadInput) return kExitBadInput;
  // Killed by a signal (the shell reports 128 + signal): h5py's HDF5 library crashed on a file
  // that vibro's own contained read survived. That is the file's damage: bad input, nothing kept.
  if (WIFSIGNALED(rc) || (WIFEXITED(rc) && WEXITSTATUS(rc) > 128)) {
    std::error_code ec;
    for (const auto& f : ours())
      if (!before.count(f)) fs::remove(f, ec);
    throw vibro::InputError({fmt::format(
        "{}: a corrupt HDF5 file: reading it makes the HDF5 library crash in the plotting process "
        "(signal {}); nothing was written",
        path, WIFSIGNALED(rc) ? WTERMSIG(rc) : WEXITSTATUS(rc) - 128)});
  }
  if (rc != 0) {
    fmt::print(stderr, "vibro: plotting failed (python exit status {})\n", rc);
    return kExitInternal;
  }
  return 0;
}
