// What a new store file says about itself (docs/output.md, "Provenance"): vibro's version and
// commit, the command and its options, the scene as run, the engine, and the model in the paper's
// scaling (/model); and the rule that a file which is not such a record of the same scene and
// command is never replaced silently.
#include <sys/stat.h>

#include <ctime>

#include <fmt/format.h>

#include "io/hdf5_store_impl.hpp"
#include "vibro/scene_file.hpp"

namespace vibro::store {
namespace {

std::string NowIso8601() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

std::vector<double> Values(const Eigen::VectorXd& v) { return {v.data(), v.data() + v.size()}; }

}  // namespace

void CheckReplaceable(const std::string& path, const StoreHeader& h, bool& existed) {
  // An existing path must be a regular file holding a vibro run.
  struct stat st{};
  existed = stat(path.c_str(), &st) == 0;
  if (!existed || !S_ISREG(st.st_mode)) return;
  bool ours = false;
  if (h5::IsHdf5(path)) {
    h5::Handle probe = h5::OpenFile(path, false);
    ours = probe && h5::HasAttr(probe.get(), "vibro_version");
  }
  if (!ours)
    throw InputError({fmt::format("{}: exists and is not a vibro output file; refusing to "
                                  "overwrite it (remove it or choose another --out)",
                                  path)});
  if (h.force) return;
  // A vibro file of another scene or command is someone's result.
  h5::Handle probe = h5::OpenFile(path, false);
  const std::string scene = probe ? h5::ReadString(probe.get(), "scene") : "";
  const std::string command = probe ? h5::ReadString(probe.get(), "command") : "";
  if (scene != h.scene_text || (!command.empty() && command != h.command))
    throw InputError({fmt::format(
        "{}: holds a vibro {} of {}; refusing to overwrite it (--force to replace it, or "
        "choose another --out)",
        path, command.empty() ? "run" : "'" + command + "' run",
        scene != h.scene_text ? "another scene" : "another command")});
}

void WriteExtension(h5::Id f, const StoreHeader& h) {
  for (const auto& [name, value] : h.provenance) h5::WriteString(f, name, value);
  h5::WriteString(f, "scene", h.scene_text);
  h5::WriteInt(f, "periods", h.periods);
}

void WriteHeader(h5::Id f, const StoreHeader& h) {
  h5::WriteString(f, "vibro_version", VIBRO_VERSION);
  h5::WriteString(f, "git_commit", VIBRO_GIT_COMMIT);
  h5::WriteString(f, "command", h.command);
  for (const auto& [name, value] : h.provenance) h5::WriteString(f, name, value);
  h5::WriteString(f, "scene", h.scene_text);
  h5::WriteString(f, "engine", h.engine);
  h5::WriteDouble(f, "rtol", h.rtol);
  h5::WriteDouble(f, "atol", h.atol);
  h5::WriteString(f, "chatter", h.chatter);
  h5::WriteString(f, "status", "running");
  h5::WriteString(f, "message", "");
  h5::WriteString(f, "created", NowIso8601());
  h5::WriteInt(f, "periods", h.periods);
  h5::WriteInt(f, "samples_per_period", h.samples_per_period);
  h5::WriteDouble(f, "forcing_period", h.period);
  h5::WriteDouble(f, "initial_time", h.initial_time);

  const h5::Handle mg = h5::OpenGroup(f, "/model");
  const h5::Id m = mg.get();
  h5::WriteDoubles(m, "frequencies", Values(h.frequencies));
  h5::WriteDoubles(m, "forcing", Values(h.forcing));
  h5::WriteDoubles(m, "contact", Values(h.contact));
  h5::WriteDoubles(m, "contact_shape", Values(h.contact_shape));
  h5::WriteDoubles(m, "damping_ratios", Values(h.damping_ratios));
  h5::WriteDoubles(m, "constrained_frequencies", Values(h.constrained_frequencies));
  h5::WriteDouble(m, "s_A", h.s_A);
  h5::WriteDouble(m, "s_B", h.s_B);
  h5::WriteDouble(m, "stop", h.stop);
  h5::WriteDouble(m, "restitution", h.restitution);
  h5::WriteDouble(m, "amplitude", h.amplitude);
  h5::WriteDouble(m, "frequency", h.frequency);
  if (h.harmonic_amplitudes.size() > 0) {  // a sum of harmonics; rows of harmonic_forcing (H, n)
    h5::WriteDoubles(m, "harmonic_amplitudes", Values(h.harmonic_amplitudes));
    h5::WriteDoubles(m, "harmonic_frequencies", Values(h.harmonic_frequencies));
    h5::WriteDoubles(m, "harmonic_phases", Values(h.harmonic_phases));
    std::vector<double> rows;
    for (Eigen::Index i = 0; i < h.harmonic_forcing.rows(); ++i)
      for (Eigen::Index j = 0; j < h.harmonic_forcing.cols(); ++j) rows.push_back(h.harmonic_forcing(i, j));
    h5::WriteDoubles(m, "harmonic_forcing", rows, static_cast<h5::Size>(h.harmonic_forcing.cols()));
  }
  h5::WriteString(m, "form", h.mode_shapes.size() > 0 ? "physical" : "modal");
  if (h.mode_shapes.size() > 0) {  // (N, n), row-major as HDF5 stores it
    std::vector<double> rows;
    for (Eigen::Index i = 0; i < h.mode_shapes.rows(); ++i)
      for (Eigen::Index j = 0; j < h.mode_shapes.cols(); ++j) rows.push_back(h.mode_shapes(i, j));
    h5::WriteDoubles(m, "mode_shapes", rows, static_cast<h5::Size>(h.mode_shapes.cols()));
    h5::WriteStringArray(m, "dof_labels", h.dof_labels);
  }
}

}  // namespace vibro::store
