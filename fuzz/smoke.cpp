// The seeded, bounded fuzz smoke test run by ctest (docs/reliability.md): a few thousand mutated
// scenes through the scene parser and a few hundred mutated vibro files through the HDF5 readers
// and resume, with the targets of fuzz_targets.hpp (no crash, every refusal located, a refused
// resume changes nothing). ctest's timeout bounds the time (no hang).
//
// usage: vibro_fuzz_smoke SCENES_DIR SCRATCH_DIR [SCENES [FILES [SEED]]]
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <vector>

#include "fuzz_targets.hpp"
#include "vibro/hdf5_store.hpp"
#include "vibro/scene_file.hpp"
#include "vibro/simulator.hpp"
#include "vibro/system.hpp"

namespace {

using Bytes = std::string;

Bytes Slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Tokens that reach the parser's and the validator's corners.
const std::vector<std::string> kTokens = {
    ".", "[", "]", "{", "}", "=", ",", "\"", "'", "'''", "\"\"\"", "#", "\n", "[[", "]]", "\\u0000",
    "1e999", "-1e999", "nan", "inf", "-inf", "-0", "0", "1e-310", "5e-324", "1.797e308", "4294967297",
    "9223372036854775807", "-9223372036854775808", "0x7fffffff", "true", "1979-05-27T07:32:00Z",
    "structure.", "stop.", "run.", "excitation.", "initial.", "a.b.c.d.e.f.g.h.i.j.k.l.m.n.o.p.q.r",
    "[structure]", "[run]", "modes = ", "contact_dof = ", "periods = ", "frequency = ", "amplitude = ",
    "displacement = [", "velocity = [", "mass = [[", "engine = \"cvode\"", "chatter = \"none\""};

const std::vector<std::string> kSetKeys = {"excitation.amplitude", "excitation.frequency", "stop.position",
                                           "structure.modes", "structure.contact_dof", "run.periods",
                                           "initial.velocity", "run.engine", "structure.frequencies"};

Bytes Mutate(Bytes s, const std::vector<Bytes>& seeds, std::mt19937_64& rng) {
  const auto pick = [&](size_t n) { return n == 0 ? size_t{0} : static_cast<size_t>(rng() % n); };
  const int rounds = 1 + static_cast<int>(rng() % 6);
  for (int r = 0; r < rounds; ++r) {
    switch (rng() % 8) {
      case 0:  // flip a bit
        if (!s.empty()) s[pick(s.size())] ^= static_cast<char>(1 << (rng() % 8));
        break;
      case 1:  // insert a token
        s.insert(pick(s.size() + 1), kTokens[pick(kTokens.size())]);
        break;
      case 2: {  // delete a range
        if (s.empty()) break;
        const size_t at = pick(s.size());
        s.erase(at, 1 + pick(std::min<size_t>(64, s.size() - at)));
        break;
      }
      case 3: {  // duplicate a range many times (long keys, deep nesting)
        if (s.empty()) break;
        const size_t at = pick(s.size()), len = 1 + pick(std::min<size_t>(8, s.size() - at));
        const Bytes piece = s.substr(at, len);
        Bytes many;
        for (size_t k = 0, n = 1 + pick(4000); k < n; ++k) many += piece;
        s.insert(at, many);
        break;
      }
      case 4: {  // splice with another seed
        const Bytes& o = seeds[pick(seeds.size())];
        s = s.substr(0, pick(s.size() + 1)) + o.substr(pick(o.size() + 1));
        break;
      }
      case 5:  // a random byte
        s.insert(pick(s.size() + 1), 1, static_cast<char>(rng() % 256));
        break;
      case 6:  // an override with a corner value
        s = "#set " + kSetKeys[pick(kSetKeys.size())] + "=" + kTokens[pick(kTokens.size())] + "\n" + s;
        break;
      default: {  // replace a number-like run by a corner token
        const size_t at = s.find_first_of("0123456789", pick(s.size() + 1));
        if (at == Bytes::npos) break;
        const size_t end = s.find_first_not_of("0123456789.e-+", at);
        s.replace(at, (end == Bytes::npos ? s.size() : end) - at, kTokens[16 + pick(14)]);
        break;
      }
    }
    if (s.size() > (2u << 20)) s.resize(2u << 20);
  }
  return s;
}

// A small interrupted run (status "running", a checkpoint) written through the library.
Bytes InterruptedRun(const std::string& scene_text, const std::string& path) {
  const vibro::LoadedScene loaded = vibro::ParseScene(scene_text, "resume.toml");
  const vibro::System sys(loaded.scene);
  vibro::StoreHeader h;
  h.scene_text = loaded.text_as_run;
  h.engine = "exact";
  h.chatter = "accumulation";
  h.method = "adams";
  h.dof = sys.dof();
  h.samples_per_period = loaded.scene.run.samples_per_period;
  h.periods = loaded.scene.run.periods;
  h.period = sys.period();
  h.max_period = loaded.scene.run.max_period;
  h.frequencies = sys.omega();
  h.forcing = sys.forcing();
  h.contact = sys.contact();
  h.contact_shape = sys.contact_shape();
  h.damping_ratios = sys.damping();
  h.constrained_frequencies = sys.constrained().frequencies;
  {
    auto store = vibro::Hdf5Store::Create(path, h, 0.0);
    vibro::SimulationOptions opt;
    opt.observers = {store.get()};
    vibro::Simulate(sys, loaded.scene, opt);
  }  // no Finish: the file stays "running", as after a kill
  return Slurp(path);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s SCENES_DIR SCRATCH_DIR [SCENES [FILES [SEED]]]\n", argv[0]);
    return 2;
  }
  const std::string scenes_dir = argv[1], scratch_dir = argv[2];
  const long scenes = argc > 3 ? std::atol(argv[3]) : 3000;
  const long files = argc > 4 ? std::atol(argv[4]) : 300;
  // The same inputs on every machine: the scenes in name order (a directory lists them in any
  // order), and the files from a generator of their own (how many draws a scene's mutation takes
  // depends on its text). A file whose test read makes HDF5 loop costs the probe's 120 s alarm.
  const std::uint64_t seed = argc > 5 ? std::strtoull(argv[5], nullptr, 10) : 15;
  std::mt19937_64 rng(seed), file_rng(seed + 1);
  std::filesystem::create_directories(scratch_dir);

  std::vector<std::filesystem::path> scene_paths;
  for (const auto& e : std::filesystem::directory_iterator(scenes_dir))
    if (e.path().extension() == ".toml") scene_paths.push_back(e.path());
  std::sort(scene_paths.begin(), scene_paths.end());
  std::vector<Bytes> seeds;
  for (const auto& path : scene_paths) seeds.push_back(Slurp(path.string()));
  if (seeds.empty()) {
    std::fprintf(stderr, "no scenes in %s\n", scenes_dir.c_str());
    return 2;
  }
  for (long i = 0; i < scenes; ++i) {
    const Bytes input = Mutate(seeds[static_cast<size_t>(rng() % seeds.size())], seeds, rng);
    vibro::fuzz::SceneTarget(reinterpret_cast<const std::uint8_t*>(input.data()), input.size());
  }
  std::printf("%ld mutated scenes: no crash, every refusal located\n", scenes);

  const std::string scene = Slurp(scenes_dir + "/default.toml") + "\n";
  const std::string with_run = scene.substr(0, scene.find("[run]")) +
                               "[run]\nperiods = 40\nsamples_per_period = 4\n";
  const std::string seed_path = scratch_dir + "/seed.h5", scratch = scratch_dir + "/mutated.h5";
  const Bytes run = InterruptedRun(with_run, seed_path);
  for (long i = 0; i < files; ++i) {
    Bytes b = run;
    switch (file_rng() % 4) {
      case 0:  // a few flipped bits
        for (int k = 0, n = 1 + static_cast<int>(file_rng() % 8); k < n; ++k)
          b[static_cast<size_t>(file_rng() % b.size())] ^= static_cast<char>(1 << (file_rng() % 8));
        break;
      case 1: {  // a run of 0xff bytes
        const size_t at = static_cast<size_t>(file_rng() % b.size());
        for (size_t k = at; k < std::min(b.size(), at + 1 + static_cast<size_t>(file_rng() % 16)); ++k) b[k] = '\xff';
        break;
      }
      case 2:  // truncated
        b.resize(static_cast<size_t>(file_rng() % b.size()));
        break;
      default:  // one byte set to a random value
        b[static_cast<size_t>(file_rng() % b.size())] = static_cast<char>(file_rng() % 256);
        break;
    }
    vibro::fuzz::StoredRunTarget(reinterpret_cast<const std::uint8_t*>(b.data()), b.size(), scratch, with_run);
  }
  std::printf("%ld mutated vibro files: no crash, every refusal located, refused resumes change nothing\n", files);
  std::filesystem::remove(seed_path);
  std::filesystem::remove(scratch);
  return 0;
}
