// Where `vibro plot` finds its plotting code: relative to the running program, so that an
// installed vibro (P/bin/vibro → P/share/vibro/vibro_plot.py) and a build tree
// (build/vibro → build/share/vibro/vibro_plot.py) both work wherever they are moved.
#pragma once

#include <string>
#include <vector>

namespace vibro::cli {

// The candidates, in the order tried, for the program at `exe` (an absolute path).
std::vector<std::string> PlotScriptCandidates(const std::string& exe);
// The first candidate that exists for the running program (/proc/self/exe), or "" when none does;
// `tried` receives the candidates.
std::string FindPlotScript(std::vector<std::string>& tried);

}  // namespace vibro::cli
