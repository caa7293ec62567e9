#include "fuzz_targets.hpp"

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string_view>

#include "vibro/hdf5_store.hpp"
#include "vibro/scene_file.hpp"
#include "vibro/system.hpp"

namespace vibro::fuzz {
namespace {

[[noreturn]] void Finding(const std::string& what) {
  std::fprintf(stderr, "fuzz finding: %s\n", what.c_str());
  std::fflush(stderr);
  std::abort();
}

// Every message of a refusal names where: the source ("fuzz.toml", the scratch file) or a --set.
void RequireLocated(const InputError& e, const std::string& source) {
  if (e.messages().empty()) Finding("an InputError without a message");
  for (const auto& m : e.messages())
    if (m.rfind(source, 0) != 0 && m.rfind("--set", 0) != 0)
      Finding("a message that does not say where: " + m.substr(0, 300));
}

std::string Slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

}  // namespace

void SceneTarget(const std::uint8_t* data, std::size_t size) {
  std::string_view text(reinterpret_cast<const char*>(data), size);
  std::vector<std::string> sets;
  if (text.rfind("#set ", 0) == 0) {
    const auto eol = text.find('\n');
    sets.emplace_back(text.substr(5, eol == std::string_view::npos ? std::string_view::npos : eol - 5));
  }
  try {
    const LoadedScene loaded = ParseScene(text, "fuzz.toml", sets);
    const System sys(loaded.scene);  // a valid scene must give a model
    (void)sys;
  } catch (const InputError& e) {
    RequireLocated(e, "fuzz.toml");
  } catch (const std::exception& e) {
    Finding(std::string("not an InputError: ") + e.what());
  }
}

void StoredRunTarget(const std::uint8_t* data, std::size_t size, const std::string& scratch,
                     const std::string& resume_scene) {
  {
    std::ofstream out(scratch, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  try {
    ReadStoredRun(scratch, 66);
  } catch (const InputError& e) {
    RequireLocated(e, scratch);
  } catch (const std::exception& e) {
    Finding(std::string("ReadStoredRun: not an InputError: ") + e.what());
  }
  if (resume_scene.empty()) return;
  const std::string before = Slurp(scratch);
  try {
    const LoadedScene loaded = ParseScene(resume_scene, "resume.toml");
    const System sys(loaded.scene);
    StoreHeader h;
    h.scene_text = loaded.text_as_run;
    h.dof = sys.dof();
    h.max_period = loaded.scene.run.max_period;
    h.engine = "exact";
    StoredRun stored;
    auto store = Hdf5Store::Resume(scratch, h, stored);
    // An accepted resume must be able to write what the run writes: rows, checkpoints, the end.
    try {
      const Checkpoint& c = *stored.checkpoint;
      const Event e{EventKind::kImpact, c.clock, 0.0, 0.0, -1.0, 0.5};
      const Sample s{c.clock, 0.0, c.X, c.V, 0.0, c.mode, c.mode == Mode::kSticking ? 1 : 0};
      for (int i = 0; i < 5000; ++i) {
        store->OnEvent(e);
        store->OnSample(s);
        store->OnSection(s);
      }
      store->OnCheckpoint(c);
      RunResult r;
      r.status = RunStatus::kInterrupted;
      Attractor a;
      a.kind = "impact-periodic";
      a.period = 1;
      a.impact_phases = {0.5};
      a.impact_velocities = {1.0};
      store->Finish(r, a);
    } catch (const std::exception& e) {
      Finding(std::string("an accepted resume could not write: ") + e.what());
    }
  } catch (const InputError& e) {
    RequireLocated(e, scratch);
    if (Slurp(scratch) != before) Finding("a refused resume changed the file: " + e.messages().front());
  } catch (const std::exception& e) {
    Finding(std::string("Resume: not an InputError: ") + e.what());
  }
}

}  // namespace vibro::fuzz
