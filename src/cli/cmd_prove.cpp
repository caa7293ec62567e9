// `vibro prove SCENE`: a computer-assisted proof of a periodic orbit and its certificate
// (docs/prove.md). Exit 0 proven, 4 not proven (the reason names the inequality that failed), 2 bad input.
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <algorithm>
#include <optional>
#include <stdexcept>

#include <fmt/format.h>

#include "cli/cli_common.hpp"
#include "vibro/hdf5_branch.hpp"
#include "vibro/prove.hpp"
#include "vibro/scene_file.hpp"
#include "vibro/system.hpp"

namespace {

// A string as a JSON string literal.
std::string Quoted(const std::string& s) {
  std::string q = "\"";
  for (const char c : s) {
    if (c == '"' || c == '\\') q += std::string("\\") + c;
    else if (static_cast<unsigned char>(c) < 0x20) q += fmt::format("\\u{:04x}", static_cast<unsigned char>(c));
    else q += c;
  }
  return q + "\"";
}

// `vibro prove SCENE --branch FILE.h5`: every stored point of a continuation branch, each from its
// stored section state at its parameter value. Exit 0 when every point is proven, 4 otherwise.
int RunProveBranch(const std::string& path, const std::vector<std::string>& sets, bool json, const ProveArgs& args) {
  const auto first = vibro::ReadBranchPoint(args.branch, 0);
  std::string points = "[", certificates = "[", segments = "[";
  long long proven = 0, segments_proven = 0;
  // The previous point, for the segment between it and the next (validated continuation).
  struct Point {
    vibro::Scene scene;
    vibro::ProofRequest request;
    bool proven = false;
    double value = 0;
  };
  std::optional<Point> previous;
  for (long long k = 0; k < first.points; ++k) {
    const auto pt = k == 0 ? first : vibro::ReadBranchPoint(args.branch, k);
    auto at = sets;
    at.push_back(vibro::frontend::Assignment(pt.param, pt.value));
    const auto loaded = vibro::LoadScene(path, at);
    vibro::frontend::RequireOneContact(loaded, "prove");
    const vibro::System sys(loaded.scene);
    if (pt.X.size() != sys.dof())
      throw vibro::InputError({fmt::format("--branch {}: point {} has {} modes, the scene has {}", args.branch, k,
                                           pt.X.size(), sys.dof())});
    vibro::ProofRequest req = args.request;
    req.start = vibro::InitialOverride{pt.section_time, pt.X, pt.V};
    req.period = pt.period;
    vibro::ProofResult r;
    try {
      r = vibro::ProveOrbit(sys, loaded.scene, req);
    } catch (const std::invalid_argument& e) {
      throw vibro::InputError({path + ": " + e.what()});
    }
    proven += r.proven ? 1 : 0;
    if (previous && previous->proven && r.proven && r.kind == "impact") {
      // Every parameter value between the two points: one box, one orbit (impacting orbits).
      const vibro::System sys_prev(previous->scene);
      const auto pieces = vibro::ProveOrbitOverInterval(sys_prev, previous->scene, previous->request, sys, loaded.scene, req);
      const bool seg_proven = pieces.front().proven;
      segments_proven += seg_proven ? 1 : 0;
      std::string summaries = "[";
      for (const auto& piece : pieces) {
        summaries += (summaries.size() > 1 ? ", " : "") + piece.summary_json;
        if (piece.proven) certificates += ", " + piece.certificate_json;  // a failed segment leaves the points' proofs
      }
      segments += fmt::format("{}{{\"from\": {}, \"to\": {}, \"proven\": {}, \"pieces\": {}]}}",
                              segments.size() > 1 ? ", " : "", previous->value, pt.value, seg_proven, summaries);
      if (!json)
        fmt::print("segment     {} in [{:.10g}, {:.10g}] {}: {}\n", pt.param, std::min(previous->value, pt.value),
                   std::max(previous->value, pt.value), seg_proven ? "proven    " : "not proven",
                   seg_proven ? fmt::format("{} piece(s), each with exactly one orbit in its box", pieces.size())
                              : pieces.front().reason);
    }
    previous = Point{loaded.scene, req, r.proven, pt.value};
    points += fmt::format("{}{{\"point\": {}, \"value\": {}, \"summary\": {}}}", k ? ", " : "", k, pt.value, r.summary_json);
    certificates += (k ? ", " : "") + r.certificate_json;
    if (!json)
      fmt::print("point {:>4}  {} = {:<12.10g} {}: {}\n", k, pt.param, pt.value, r.proven ? "proven    " : "not proven",
                 r.reason);
  }
  if (!args.out.empty()) {
    std::ofstream file(args.out, std::ios::trunc);
    file << "{\"branch\": " << Quoted(args.branch) << ", \"certificates\": " << certificates << "]}\n";
    if (!file) throw vibro::WriteError(args.out + ": the certificates could not be written");
  }
  if (json)
    fmt::print("{{\"branch\": {}, \"param\": {}, \"proven\": {}, \"total\": {}, \"points\": {}], "
               "\"segments_proven\": {}, \"segments\": {}]}}\n",
               Quoted(args.branch), Quoted(first.param), proven, first.points, points, segments_proven, segments);
  else
    fmt::print("proven       {} of {} points, {} of the segments between them\n", proven, first.points, segments_proven);
  return proven == first.points ? 0 : kExitDisagree;
}

}  // namespace

int RunProve(const std::string& path, const std::vector<std::string>& sets, bool json, const ProveArgs& args) {
  if (!args.out.empty()) {  // bad input before any work, and nothing created
    const auto dir = std::filesystem::path(args.out).parent_path();
    if (!dir.empty() && !std::filesystem::is_directory(dir))
      throw vibro::InputError({"--out " + args.out + ": no directory " + dir.string()});
    if (std::filesystem::is_directory(args.out)) throw vibro::InputError({"--out " + args.out + ": a directory"});
  }
  if (!args.branch.empty()) return RunProveBranch(path, sets, json, args);
  const auto loaded = vibro::LoadScene(path, sets);
  vibro::frontend::RequireOneContact(loaded, "prove");
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
