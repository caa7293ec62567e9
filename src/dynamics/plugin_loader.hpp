// vibro::detail::LoadPlugin: the one place where libvibro maps a plugin of its own (the CVODE
// engine, the thread pool, the prover, MPI) on first use, so that no process maps SUNDIALS, oneTBB,
// Arb/FLINT or OpenMPI before it needs them (docs/performance.md, "Start-up").
#pragma once

#include <string>

namespace vibro::detail {

// What to load and how to name a failure: "<prefix>cannot load <what><tried><need>: <dlerror>".
struct PluginRequest {
  const char* file;   // e.g. "libvibro_cvode.so"
  const char* entry;  // the plugin's exported entry point, e.g. "vibro_cvode_api"
  bool global;        // RTLD_GLOBAL (OpenMPI's own components resolve against its libraries)
  std::string prefix; // e.g. "run.engine = \"cvode\": "
  std::string what;   // e.g. "the CVODE engine "
  std::string need;   // e.g. ", which a run under mpirun needs"
};

struct LoadedPlugin {
  void* entry;       // the entry point (cast by the caller to its table's getter)
  std::string path;  // the file it was loaded from (for the caller's own checks' messages)
};

// Loads the plugin beside the object this code is in (libvibro.so: build/ in the build tree, lib/
// once installed), or from ../<libdir> of it (a program linked with a static libvibro, installed in
// bin/), once for the life of the process (RTLD_NODELETE). A plugin that could not be mapped because
// the address space or memory ran out (ulimit -v) is memory exhausted like any refused allocation:
// std::bad_alloc (exit 3 from the command line, MemoryError in Python). Any other failure, or a
// plugin without its entry point: std::runtime_error with the message above.
LoadedPlugin LoadPlugin(const PluginRequest& request);

}  // namespace vibro::detail
