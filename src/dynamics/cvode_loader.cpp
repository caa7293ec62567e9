// MakeCvodeEngine (cvode_api.hpp) and MakeCvodeCompliant (cvode_engine.hpp) in libvibro: they load
// the CVODE plugin libvibro_cvode.so on their first call and forward to it, so that no process maps
// SUNDIALS before it integrates with CVODE (docs/performance.md, "Start-up"), as the prover
// (src/proof/prove_loader.cpp) and HDF5 (src/io/h5_file.cpp) are loaded.
#include <mutex>
#include <stdexcept>

#include "dynamics/plugin_loader.hpp"

#include "dynamics/cvode_api.hpp"
#include "dynamics/cvode_engine.hpp"

namespace vibro::detail {
namespace {

const VibroCvodeApi* LoadCvode() {
  const LoadedPlugin plugin =
      LoadPlugin({VIBRO_CVODE_PLUGIN, "vibro_cvode_api", false, "run.engine = \"cvode\": ", "the CVODE engine ", ""});
  const VibroCvodeApi* api = reinterpret_cast<const VibroCvodeApi* (*)()>(plugin.entry)();
  if (api->run_size != sizeof(RunSpec) || api->model_size != sizeof(ModelT<double>))
    throw std::runtime_error("run.engine = \"cvode\": " + plugin.path + " was built from other headers than this libvibro");
  return api;
}

const VibroCvodeApi& Cvode() {
  static std::once_flag once;
  static const VibroCvodeApi* api = nullptr;
  std::call_once(once, [] { api = LoadCvode(); });  // a failed load throws and is tried again
  return *api;
}

}  // namespace

std::unique_ptr<Propagator> MakeCvodeEngine(const System& system, const RunSpec& run) {
  return Cvode().make_engine(system, run);
}

std::unique_ptr<CompliantPhase> MakeCvodeCompliant(const RunSpec& run, const std::vector<const ModelT<double>*>& models,
                                                   int contact) {
  return Cvode().make_compliant(run, models, contact);
}

}  // namespace vibro::detail
