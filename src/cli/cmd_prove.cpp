// `vibro prove SCENE`: a computer-assisted proof of a periodic orbit and its certificate
// (docs/prove.md). Exit 0 proven, 4 not proven (the reason names the inequality that failed, or the
// time limit), 2 bad input, 3 out of memory, 130 interrupted (nothing proven, nothing written).
#include <algorithm>
#include <cfenv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <new>
#include <optional>
#include <stdexcept>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "cli/cli_common.hpp"
#include "cli/stop_signals.hpp"
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

// The decimal `s` read as a double rounded toward `mode` (FE_UPWARD: the least double >= s).
double ReadRounded(const std::string& s, int mode) {
  const int before = std::fegetround();
  std::fesetround(mode);
  const double v = std::strtod(s.c_str(), nullptr);
  std::fesetround(before);
  return v;
}

// x as a decimal of `digits` significant digits rounded down (up = false) or up, so that the printed
// interval contains the JSON's (docs/prove.md): s <= x exactly when the least double >= s is <= x.
std::string Outward(double x, bool up, int digits = 12) {
  if (x == 0 || !std::isfinite(x)) return fmt::format("{}", x);
  std::string s = fmt::format("{:.{}e}", x, digits - 1);
  for (int step = 0; step < 4; ++step) {
    if (up ? ReadRounded(s, FE_DOWNWARD) >= x : ReadRounded(s, FE_UPWARD) <= x) break;
    const int exponent = std::atoi(s.c_str() + s.find('e') + 1);
    const double unit = std::pow(10.0, exponent - (digits - 1));
    s = fmt::format("{:.{}e}", std::strtod(s.c_str(), nullptr) + (up ? unit : -unit), digits - 1);
  }
  return fmt::format("{:.{}g}", std::strtod(s.c_str(), nullptr), digits);
}

std::string Range(const vibro::Enclosure& e) { return fmt::format("[{}, {}]", Outward(e.lo, false), Outward(e.hi, true)); }

// A stop request ends `vibro prove` with exit 130 and no verdict; `kept` says what was kept.
int Interrupted(const std::string& kept) {
  fmt::print(stderr, "vibro: interrupted; {}\n", kept);
  return kExitInterrupted;
}

// `vibro prove SCENE --branch FILE.h5`: every stored point of a continuation branch, each from its
// stored section state at its parameter value. Exit 0 when every point is proven, 4 otherwise.
int RunProveBranch(const std::string& path, const std::vector<std::string>& sets, bool json, const ProveArgs& args) {
  const auto started = std::chrono::steady_clock::now();
  const auto seconds_left = [&] {
    return args.request.time_limit - std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  };
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
  long long done = 0;
  long long unreached = -1;  // the first point the time limit left unattempted (-1: none)
  bool interrupted = false;
  for (long long k = 0; k < first.points && !interrupted; ++k) {
    if (k > 0 && seconds_left() <= 0) {
      unreached = k;
      if (!json)
        fmt::print("points {}..{} not proven: the time limit of {:g} s (--time-limit, for the whole command) was "
                   "reached before them\n", k, first.points - 1, args.request.time_limit);
      break;
    }
    const auto pt = k == 0 ? first : vibro::ReadBranchPoint(args.branch, k);
    auto at = sets;
    at.push_back(vibro::frontend::Assignment(pt.param, pt.value));
    const auto loaded = vibro::LoadScene(path, at);
    const vibro::System sys(loaded.scene);
    if (pt.X.size() != sys.dof())
      throw vibro::InputError({fmt::format("--branch {}: point {} has {} modes, the scene has {}", args.branch, k,
                                           pt.X.size(), sys.dof())});
    vibro::ProofRequest req = args.request;
    req.start = vibro::InitialOverride{pt.section_time, pt.X, pt.V};
    req.period = pt.period;
    req.time_limit = seconds_left();  // --time-limit bounds the whole command
    vibro::ProofResult r;
    if (req.time_limit <= 0) {
      r.reason = fmt::format("the time limit of {:g} s (--time-limit, for the whole command) was reached before "
                             "this point: nothing is proven", args.request.time_limit);
      r.summary_json = fmt::format("{{\"verdict\": \"not-proven\", \"reason\": {}}}", Quoted(r.reason));
    } else {
      try {
        r = vibro::ProveOrbit(sys, loaded.scene, req);
      } catch (const std::invalid_argument& e) {
        throw vibro::InputError({path + ": " + e.what()});
      }
    }
    if (r.interrupted || vibro::cli::StopRequested()) {
      interrupted = true;
      break;
    }
    proven += r.proven ? 1 : 0;
    if (previous && previous->proven && r.proven && r.kind == "impact") {
      // Every parameter value between the two points: one box, one orbit (impacting orbits).
      const vibro::System sys_prev(previous->scene);
      auto from = previous->request;
      from.time_limit = std::max(seconds_left(), 1e-3);
      const auto pieces = vibro::ProveOrbitOverInterval(sys_prev, previous->scene, from, sys, loaded.scene, req);
      if (pieces.front().interrupted || vibro::cli::StopRequested()) {
        interrupted = true;
        break;
      }
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
                   seg_proven ? fmt::format("{} piece(s), each with exactly one orbit in its {}{}", pieces.size(),
                                            pt.param == "excitation.frequency" ? "tube along the tangent" : "box",
                                            std::all_of(pieces.begin(), pieces.end(),
                                                        [](const auto& p) { return p.stability == "stable"; })
                                                ? ", stable throughout"
                                                : "")
                              : pieces.front().reason);
    }
    previous = Point{loaded.scene, req, r.proven, pt.value};
    points += fmt::format("{}{{\"point\": {}, \"value\": {}, \"summary\": {}}}", k ? ", " : "", k, pt.value, r.summary_json);
    if (!r.certificate_json.empty()) certificates += (certificates.size() > 1 ? ", " : "") + r.certificate_json;
    ++done;
    if (!json)
      fmt::print("point {:>4}  {} = {:<12.10g} {}: {}\n", k, pt.param, pt.value, r.proven ? "proven    " : "not proven",
                 r.reason);
  }
  // What was proven is kept: interrupted, the certificates of the points done (each whole).
  if (!args.out.empty() && certificates.size() > 1) {
    const vibro::cli::FinalWrite writing;
    std::ofstream file(args.out, std::ios::trunc);
    file << "{\"branch\": " << Quoted(args.branch) << ", \"certificates\": " << certificates << "]}\n";
    if (!file) throw vibro::WriteError(args.out + ": the certificates could not be written");
  }
  if (json)
    fmt::print("{{\"branch\": {}, \"param\": {}, \"proven\": {}, \"total\": {}, \"points\": {}], "
               "\"segments_proven\": {}, \"segments\": {}]{}}}\n",
               Quoted(args.branch), Quoted(first.param), proven, first.points, points, segments_proven, segments,
               interrupted ? fmt::format(", \"interrupted_after\": {}", done)
               : unreached >= 0 ? fmt::format(", \"time_limit_reached_at\": {}", unreached)
                                : "");
  else
    fmt::print("proven       {} of {} points, {} of the segments between them\n", proven, first.points, segments_proven);
  if (interrupted)
    return Interrupted(args.out.empty() || done == 0
                           ? fmt::format("{} of {} points were done, nothing is written", done, first.points)
                           : fmt::format("{} of {} points were done, their certificates are kept in {}", done,
                                         first.points, args.out));
  return proven == first.points ? 0 : kExitDisagree;
}

// A proof's refusal of its input (std::invalid_argument) as bad input located in the scene file.
template <class F>
vibro::ProofResult Located(const std::string& path, F&& prove) {
  try {
    return prove();
  } catch (const std::invalid_argument& e) {
    throw vibro::InputError({path + ": " + e.what()});
  }
}

// The certificate to --out (if given), as one final write that a stop request waits for.
void WriteCertificate(const std::string& out, const vibro::ProofResult& result) {
  if (out.empty()) return;
  const vibro::cli::FinalWrite writing;
  std::ofstream file(out, std::ios::trunc);
  file << result.certificate_json << "\n";
  if (!file) throw vibro::WriteError(out + ": the certificate could not be written");
}

// `vibro prove SCENE --bifurcation SOURCE`: the bifurcation point's parameter enclosed (docs/prove.md
// "Bifurcation points"). SOURCE: BRANCH.h5 (with --point K) or KIND:KEY=VALUE.
int ProveBifurcationPoint(const std::string& path, const std::vector<std::string>& sets, bool json,
                          const ProveArgs& args) {
  vibro::BifurcationRequest req;
  req.time_limit = args.request.time_limit;
  long long before = -1;  // the branch's point before the bifurcation read from BRANCH.h5 (−1: unknown)
  const auto& src = args.bifurcation;
  const auto colon = src.find(':'), equals = src.find('=');
  if (colon != std::string::npos && equals != std::string::npos && colon < equals && !std::filesystem::exists(src)) {
    req.kind = src.substr(0, colon);
    req.parameter = src.substr(colon + 1, equals - colon - 1);
    const std::string number = src.substr(equals + 1);
    char* end = nullptr;
    req.value = std::strtod(number.c_str(), &end);
    if (number.empty() || end == nullptr || *end != '\0' || !std::isfinite(req.value))
      throw vibro::InputError({"--bifurcation " + src + ": '" + number + "' is not a number (KIND:KEY=VALUE)"});
  } else {
    // Neither a file nor KIND:KEY=VALUE: say both (the file's own refusal named no option).
    if (!std::filesystem::exists(src))
      throw vibro::InputError({"--bifurcation " + src + ": no such file, and not KIND:KEY=VALUE (e.g. "
                               "branch-point:excitation.amplitude=3.286)"});
    const auto list = vibro::ReadBranchBifurcations(src);
    if (args.point >= static_cast<long long>(list.size()))
      throw vibro::InputError({fmt::format("--point {}: {} has {} bifurcation(s)", args.point, src, list.size())});
    const auto& b = list[static_cast<std::size_t>(args.point)];
    req.kind = b.kind;
    req.value = b.value;
    req.bracket = b.bracket;
    before = b.point;
    req.parameter = vibro::ReadBranchPoint(src, 0).param;
  }
  if (req.kind == "grazing" || req.kind == "branch-point") {
    // The orbit that grazes (or whose symmetry breaks), from the stored point nearest the grazing but at least 1e-6 (relative)
    // from it, where the orbit clears the contact plainly: of --from BRANCH.h5, or of the branch
    // the bifurcation was read from, there the branch's point before it (Bifurcation::point: past
    // a grazing the branch may come back to the same value on other orbits).
    const bool given = colon != std::string::npos && equals != std::string::npos && colon < equals &&
                       !std::filesystem::exists(src);
    const std::string file = given ? args.from : src;
    if (!file.empty()) {
      const double apart = 1e-6 * (1 + std::abs(req.value));
      if (given) before = vibro::BifurcationPointNear(file, req.kind, req.value, apart);
      const auto near = vibro::NearestBranchPoint(file, req.value, apart, before);
      if (near.param != req.parameter)
        throw vibro::InputError({fmt::format("--from {}: a branch in {}, not {}", file, near.param, req.parameter)});
      req.start = vibro::InitialOverride{near.section_time, near.X, near.V};
      req.period = near.period;
      req.start_value = near.value;
    }
  } else if (!args.from.empty()) {
    throw vibro::InputError({"--from " + args.from + ": with --bifurcation, only for a grazing given as KIND:KEY=VALUE"});
  }
  auto at = sets;
  at.push_back(vibro::frontend::Assignment(req.parameter, req.value));
  const auto loaded = vibro::LoadScene(path, at);
  const vibro::System sys(loaded.scene);
  const vibro::ProofResult result = Located(path, [&] { return vibro::ProveBifurcation(sys, loaded.scene, req); });
  if (result.interrupted || vibro::cli::StopRequested()) return Interrupted("nothing is proven or written");
  WriteCertificate(args.out, result);
  if (json) {
    fmt::print("{}\n", result.summary_json);
  } else {
    fmt::print("verdict      {}\n", result.proven ? "proven" : "not proven");
    fmt::print("reason       {}\n", result.reason);
    if (result.proven) {
      const auto s = nlohmann::json::parse(result.summary_json);
      const auto& iv = s["interval"];
      fmt::print("bifurcation  {} at {} in [{}, {}] (width {})\n", s["bifurcation"].get<std::string>(), req.parameter,
                 iv[0].get<std::string>(), iv[1].get<std::string>(), Outward(s["width"].get<double>(), true, 3));
      const auto pair = [](const nlohmann::json& p) {
        return Range(vibro::Enclosure{p[0].get<double>(), p[1].get<double>()});
      };
      const bool fold = s["bifurcation"] == "fold", grazing = s["bifurcation"] == "grazing";
      fmt::print("transversal  d {}/d{} in {}\n", fold ? "disc" : grazing ? "(minimum gap)" : s.contains("impact_contacts") ? "mu" : "det(DH + I)",
                 s["parameter"].get<std::string>(), pair(s["slope"]));
      if (grazing)
        fmt::print("grazing      flight {} touches contact {} at t in {} (gap curvature {})\n",
                   s["grazing_flight"].get<int>(), s["grazing_contact"].get<int>(), pair(s["grazing_time"]),
                   pair(s["curvature"]));
      if (s.contains("half_map_multipliers"))
        fmt::print("multipliers  of the half-period map at the point: -1 and {} (the period map: +1 and their "
                   "squares)\n", pair(s["half_map_multipliers"][1]));
    }
    if (!args.out.empty()) fmt::print("certificate  {} (check it: vibro_check_proof.py {})\n", args.out, args.out);
  }
  return result.proven ? 0 : kExitDisagree;
}

int Prove(const std::string& path, const std::vector<std::string>& sets, bool json, const ProveArgs& args) {
  if (!args.out.empty()) {  // bad input before any work, and nothing created
    const auto dir = std::filesystem::path(args.out).parent_path();
    if (!dir.empty() && !std::filesystem::is_directory(dir))
      throw vibro::InputError({"--out " + args.out + ": no directory " + dir.string()});
    if (std::filesystem::is_directory(args.out)) throw vibro::InputError({"--out " + args.out + ": a directory"});
  }
  if (!args.branch.empty()) return RunProveBranch(path, sets, json, args);
  if (!args.bifurcation.empty()) return ProveBifurcationPoint(path, sets, json, args);
  const auto loaded = vibro::LoadScene(path, sets);
  const vibro::System sys(loaded.scene);
  vibro::ProofRequest req = args.request;
  if (!args.from.empty()) {
    req.start = vibro::ReadOrbitSection(args.from);
    if (req.start->X.size() != sys.dof())
      throw vibro::InputError({args.from + ": /orbit: an orbit of " + std::to_string(req.start->X.size()) +
                               " modes, the scene has " + std::to_string(sys.dof())});
  }
  const vibro::ProofResult result = Located(path, [&] { return vibro::ProveOrbit(sys, loaded.scene, req); });
  if (result.interrupted || vibro::cli::StopRequested()) return Interrupted("nothing is proven or written");
  WriteCertificate(args.out, result);
  if (json) {
    fmt::print("{}\n", result.summary_json);
  } else {
    // The summary of the certificate (result's fields are read from it), every interval rounded
    // outward to 12 digits: what is printed is what the checker checks.
    fmt::print("verdict      {}\n", result.proven ? "proven" : "not proven");
    fmt::print("reason       {}\n", result.reason);
    if (result.proven) {
      fmt::print("period       {} ({} orbit, box width {})\n", result.period, result.kind, Outward(result.box_width, true, 3));
      if (result.requested_period > 0)
        fmt::print("least period {} divides the requested {}: the orbit is also period-{}\n", result.period,
                   result.requested_period, result.requested_period);
      for (const auto& e : result.events)
        fmt::print("event        {:<8} contact {}  phase {}  velocity before {}\n", e.kind, e.contact, Range(e.phase),
                   Range(e.velocity_before));
      for (const auto& [re, im] : result.multipliers) fmt::print("multiplier   {} + i {}\n", Range(re), Range(im));
      if (result.multipliers.empty())
        fmt::print("multipliers  {}\n",
                   result.kind != "sticking" ? "not enclosed (the stability is undecided)"
                   : result.reason.find("held on sets of contacts") != std::string::npos
                       ? "none (superstable: the contacts held at the section hold every direction)"
                       : "none (one-DOF sticking orbit: superstable)");
      fmt::print("stability    {}\n", result.stability);
      if (result.modal_data == "enclosed")
        fmt::print("modal data   enclosed from the scene's mass and stiffness matrices (every eigenpair; the theorem "
                   "is about the scene as written)\n");
    }
    if (!args.out.empty()) fmt::print("certificate  {} (check it: vibro_check_proof.py {})\n", args.out, args.out);
  }
  return result.proven ? 0 : kExitDisagree;
}

}  // namespace

int RunProve(const std::string& path, const std::vector<std::string>& sets, bool json, const ProveArgs& args) {
  try {
    return Prove(path, sets, json, args);
  } catch (const std::bad_alloc&) {  // the prover is bounded (docs/prove.md "Bounds"); memory may still run out
    fmt::print(stderr, "vibro: prove ran out of memory: nothing is proven{}\n",
               args.out.empty() ? "" : ", " + args.out + " is not written");
    std::fflush(nullptr);
    return kExitNumerical;
  }
}
