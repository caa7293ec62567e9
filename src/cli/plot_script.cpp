#include "cli/plot_script.hpp"

#include <filesystem>
#include <system_error>

namespace vibro::cli {

std::vector<std::string> PlotScriptCandidates(const std::string& exe) {
  const std::filesystem::path dir = std::filesystem::path(exe).parent_path();
  return {(dir / ".." / "share" / "vibro" / "vibro_plot.py").lexically_normal().string(),
          (dir / "share" / "vibro" / "vibro_plot.py").lexically_normal().string()};
}

std::string FindPlotScript(std::vector<std::string>& tried) {
  std::error_code ec;
  const auto exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec) return "";
  tried = PlotScriptCandidates(exe.string());
  for (const auto& p : tried)
    if (std::filesystem::is_regular_file(p, ec)) return p;
  return "";
}

}  // namespace vibro::cli
