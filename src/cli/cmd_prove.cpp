// `vibro prove SCENE`: a computer-assisted proof of a periodic orbit and its certificate
// (docs/prove.md). Exit 0 proven, 4 not proven (the reason names the inequality that failed), 2 bad input.
#include <cstdio>
#include <fstream>
#include <stdexcept>

#include <fmt/format.h>

#include "cli/cli_common.hpp"
#include "vibro/prove.hpp"
#include "vibro/scene_file.hpp"
#include "vibro/system.hpp"

int RunProve(const std::string& path, const std::vector<std::string>& sets, bool json, const ProveArgs& args) {
  const auto loaded = vibro::LoadScene(path, sets);
  const vibro::System sys(loaded.scene);
  vibro::ProofRequest req = args.request;
  if (!args.from.empty()) {
    req.start = vibro::ReadOrbitSection(args.from);
    if (req.start->X.size() != sys.dof())
      throw vibro::InputError({args.from + ": /orbit: an orbit of " + std::to_string(req.start->X.size()) +
                               " modes, the scene has " + std::to_string(sys.dof())});
  }
  vibro::ProofResult result;
  try {
    result = vibro::ProveOrbit(sys, loaded.scene, req);
  } catch (const std::invalid_argument& e) {
    throw vibro::InputError({path + ": " + e.what()});
  }
  if (!args.out.empty()) {
    std::ofstream file(args.out, std::ios::trunc);
    file << result.certificate_json << "\n";
    if (!file) throw vibro::WriteError(args.out + ": the certificate could not be written");
  }
  if (json) {
    fmt::print("{}\n", result.summary_json);
  } else {
    const auto range = [](const vibro::Enclosure& e) { return fmt::format("[{:.12g}, {:.12g}]", e.lo, e.hi); };
    fmt::print("verdict      {}\n", result.proven ? "proven" : "not proven");
    fmt::print("reason       {}\n", result.reason);
    if (result.proven) {
      fmt::print("period       {} ({} orbit, box width {:.1e})\n", result.period, result.kind, result.box_width);
      for (const auto& e : result.events)
        fmt::print("event        {:<8} phase {}  velocity before {}\n", e.kind, range(e.phase), range(e.velocity_before));
      for (const auto& [re, im] : result.multipliers) fmt::print("multiplier   {} + i {}\n", range(re), range(im));
      if (result.multipliers.empty()) fmt::print("multipliers  none (one-DOF sticking orbit)\n");
      fmt::print("stability    {}\n", result.stability);
    }
    if (!args.out.empty()) fmt::print("certificate  {} (check it: vibro_check_proof.py {})\n", args.out, args.out);
  }
  return result.proven ? 0 : kExitDisagree;
}
