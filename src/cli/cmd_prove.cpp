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
    const auto table = vibro::ReadTable(args.from, "/orbit");
    const auto* X = table.Find("X");
    const auto* V = table.Find("V");
    const auto* t = table.Find("section_time");
    if (X == nullptr || V == nullptr || t == nullptr || t->data.size() != 1 ||
        X->data.size() != static_cast<std::size_t>(sys.dof()) || V->data.size() != X->data.size())
      throw vibro::InputError({args.from + ": /orbit: expected section_time, X and V of " + std::to_string(sys.dof()) +
                               " modes (a file of `vibro orbit --out` for this scene)"});
    req.start = vibro::InitialOverride{t->data[0], Eigen::Map<const Eigen::VectorXd>(X->data.data(), sys.dof()),
                                       Eigen::Map<const Eigen::VectorXd>(V->data.data(), sys.dof())};
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
    fmt::print("verdict      {}\n", result.proven ? "proven" : "not proven");
    fmt::print("reason       {}\n", result.reason);
    if (!args.out.empty()) fmt::print("certificate  {} (check it: vibro_check_proof.py {})\n", args.out, args.out);
    if (result.proven) fmt::print("summary      {}\n", result.summary_json);
  }
  return result.proven ? 0 : kExitDisagree;
}
