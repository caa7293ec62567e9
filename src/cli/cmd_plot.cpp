// `vibro plot FILE.h5`: pictures of a vibro HDF5 file, drawn by vibro_plot.py (docs/cli.md).
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <set>

#include <fmt/format.h>

#include "cli/cli_common.hpp"
#include "cli/plot_script.hpp"
#include "vibro/child_process.hpp"
#include "vibro/hdf5_store.hpp"

int RunPlot(const std::string& path, const std::string& prefix, const std::string& overlay,
            const std::vector<std::string>& options) {
  vibro::ReadStoredRun(path);  // a clear error (exit 2) for a file that is not a vibro run
  std::vector<std::string> tried;
  const std::string script = vibro::cli::FindPlotScript(tried);
  if (script.empty()) {
    fmt::print(stderr, "vibro: plotting code not found (looked for {}); reinstall vibro\n",
               fmt::join(tried, " and "));
    return kExitInternal;
  }
  std::vector<std::string> argv{VIBRO_PYTHON, script, path};
  if (!prefix.empty()) argv.insert(argv.end(), {"--out", prefix});
  if (!overlay.empty()) argv.insert(argv.end(), {"--overlay", overlay});
  argv.insert(argv.end(), options.begin(), options.end());
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
  const auto remove_new = [&] {
    std::error_code ec;
    for (const auto& f : ours())
      if (!before.count(f)) fs::remove(f, ec);
  };
  int rc = 0;
  try {
    // A stop request kills the plotting process: its pictures are removed (a half-written one is
    // worth nothing), exit 130.
    rc = vibro::RunChild(argv, "plotting " + path);
  } catch (const vibro::Interrupted&) {
    remove_new();
    throw;
  }
  // The script exits with 2 for bad input (an option the file cannot honour, an overlay that is
  // not a continuation branch), having checked every option before drawing; whatever it may
  // have written all the same goes: a refused plot leaves nothing.
  if (WIFEXITED(rc) && WEXITSTATUS(rc) == kExitBadInput) {
    remove_new();
    return kExitBadInput;
  }
  // Killed by a signal: h5py's HDF5 library crashed on a file that vibro's own contained read
  // survived. That is the file's damage: bad input, nothing kept.
  if (WIFSIGNALED(rc)) {
    remove_new();
    throw vibro::InputError({fmt::format(
        "{}: a corrupt HDF5 file: reading it makes the HDF5 library crash in the plotting process "
        "(signal {}); nothing was written",
        path, WTERMSIG(rc))});
  }
  if (rc != 0) {
    fmt::print(stderr, "vibro: plotting failed (python exit status {})\n", WEXITSTATUS(rc));
    return kExitInternal;
  }
  return 0;
}
