// The CVODE engine as a plugin (docs/performance.md, "Start-up"). SUNDIALS CVODE (and with it
// its vector, matrix and linear-solver libraries) is bound at load, not lazily: every process that
// linked it paid for mapping and binding it, although only run.engine = "cvode" integrates with it.
// So src/dynamics/cvode_engine.cpp, the one file that includes SUNDIALS, is built into the plugin
// libvibro_cvode.so beside libvibro, and libvibro reaches it through this table, loaded
// (src/dynamics/cvode_loader.cpp) on the first CVODE engine or CVODE compliant phase of a process.
#pragma once

#include <memory>
#include <vector>

#include "dynamics/compliant_contact.hpp"
#include "dynamics/model_t.hpp"
#include "dynamics/propagator.hpp"
#include "vibro/scene.hpp"
#include "vibro/system.hpp"

namespace vibro::detail {

// The CVODE engine of a scene (run.engine = "cvode"): the plugin's CvodeEngine (cvode_engine.hpp).
std::unique_ptr<Propagator> MakeCvodeEngine(const System& system, const RunSpec& run);

// The definitions behind MakeCvodeEngine and MakeCvodeCompliant (cvode_engine.hpp), in the plugin
// (cvode_engine.cpp).
std::unique_ptr<Propagator> CreateCvodeEngine(const System& system, const RunSpec& run);
std::unique_ptr<CompliantPhase> CreateCvodeCompliant(const RunSpec& run, const std::vector<const ModelT<double>*>& models,
                                                     int contact);

}  // namespace vibro::detail

extern "C" {

struct VibroCvodeApi {
  // sizeof(vibro::RunSpec) and sizeof(vibro::detail::ModelT<double>) as the plugin was built: the
  // loader refuses a plugin of another build of the headers.
  unsigned long run_size, model_size;
  std::unique_ptr<vibro::detail::Propagator> (*make_engine)(const vibro::System&, const vibro::RunSpec&);
  std::unique_ptr<vibro::detail::CompliantPhase> (*make_compliant)(
      const vibro::RunSpec&, const std::vector<const vibro::detail::ModelT<double>*>&, int);
};

// The plugin's one exported symbol.
const VibroCvodeApi* vibro_cvode_api();
}

// The plugin's file name; cvode_loader.cpp looks for it beside the object libvibro is in.
#define VIBRO_CVODE_PLUGIN "libvibro_cvode.so"
