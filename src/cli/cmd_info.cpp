// `vibro info FILE.h5`: what a vibro HDF5 file holds (docs/output.md).
#include <algorithm>
#include <set>

#include <fmt/format.h>

#include "cli/cli_common.hpp"
#include "vibro/hdf5_store.hpp"
#include "vibro/summary_json.hpp"

int RunInfo(const std::string& path, bool json) {
  const auto run = vibro::ReadStoredRun(path);
  if (json) {
    fmt::print("{}\n", vibro::StoredRunJson(run));
    return 0;
  }
  fmt::print("file         {}\n", path);
  fmt::print("created      {} by vibro {}{}{}\n", run.created, run.version,
             run.git_commit.empty() ? "" : " (commit " + run.git_commit + ")",
             run.command.empty() ? "" : ", command '" + run.command + "'");
  fmt::print("groups       {}\n", fmt::join(run.groups, ", "));
  for (size_t i = 0; i < run.groups.size(); ++i)  // the results a file holds besides the run
    if (!run.group_notes[i].empty() &&
        !std::set<std::string>{"checkpoint", "attractor", "events", "samples", "section"}.count(run.groups[i]))
      fmt::print("  /{:<13} {}\n", run.groups[i], run.group_notes[i]);
  fmt::print("engine       {}, chatter {}\n", run.engine, run.chatter);
  fmt::print("status       {}{}\n", run.status, run.message.empty() ? "" : ": " + run.message);
  fmt::print("rows         {} events, {} samples, {} section points\n", run.events, run.samples,
             run.sections);
  if (run.checkpoint)
    fmt::print("checkpoint   period {} ({} impacts, {} accumulations, {} sticks, {} releases)\n",
               run.checkpoint->clock.period, run.checkpoint->counts.impacts,
               run.checkpoint->counts.accumulations, run.checkpoint->counts.sticks,
               run.checkpoint->counts.releases);
  if (!run.attractor.kind.empty())
    PrintAttractor(run.attractor, std::nan(""), run.scene_text.find("[[contact]]") != std::string::npos);
  else if (std::find(run.groups.begin(), run.groups.end(), "attractor") == run.groups.end())
    fmt::print("attractor    none (a study, branch or partition: see the groups above)\n");
  else
    fmt::print("attractor    (not classified: the run did not finish)\n");
  fmt::print("scene:\n{}", run.scene_text);
  return 0;
}
