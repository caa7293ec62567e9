// `vibro plot FILE.h5`: pictures of a vibro HDF5 file, drawn by vibro_plot.py (docs/cli.md).
#include <sys/wait.h>

#include <cstdlib>

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
  const int rc = std::system(cmd.c_str());
  // The script exits with 2 for bad input (an overlay that is not a continuation branch).
  if (WIFEXITED(rc) && WEXITSTATUS(rc) == kExitBadInput) return kExitBadInput;
  if (rc != 0) {
    fmt::print(stderr, "vibro: plotting failed (python exit status {})\n", rc);
    return kExitInternal;
  }
  return 0;
}
