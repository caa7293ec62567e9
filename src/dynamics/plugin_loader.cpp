// vibro::detail::LoadPlugin (plugin_loader.hpp).
#include "dynamics/plugin_loader.hpp"

#include <dlfcn.h>

#include <new>
#include <stdexcept>

namespace vibro::detail {
namespace {

// dlerror()'s text, or std::bad_alloc when it says the map failed for lack of memory.
std::string RefuseOutOfMemory(const char* error) {
  std::string e = error != nullptr ? error : "no error reported";
  if (e.find("failed to map segment") != std::string::npos || e.find("cannot map zero-fill") != std::string::npos ||
      e.find("Cannot allocate memory") != std::string::npos || e.find("out of memory") != std::string::npos)
    throw std::bad_alloc();
  return e;
}

}  // namespace

LoadedPlugin LoadPlugin(const PluginRequest& request) {
  Dl_info self{};
  std::string dir;
  if (dladdr(reinterpret_cast<void*>(&LoadPlugin), &self) != 0 && self.dli_fname != nullptr) {
    const std::string object = self.dli_fname;
    const auto slash = object.rfind('/');
    if (slash != std::string::npos) dir = object.substr(0, slash + 1);
  }
  const int flags = RTLD_NOW | (request.global ? RTLD_GLOBAL : RTLD_LOCAL) | RTLD_NODELETE;
  std::string path = dir + request.file, tried = path;
  void* plugin = dlopen(path.c_str(), flags);
  std::string error = plugin == nullptr ? RefuseOutOfMemory(dlerror()) : std::string();
  if (plugin == nullptr && !dir.empty()) {
    path = dir + "../" VIBRO_LIBDIR "/" + request.file;
    tried += " or " + path;
    plugin = dlopen(path.c_str(), flags);
    if (plugin == nullptr) error = RefuseOutOfMemory(dlerror());
  }
  if (plugin == nullptr) {
    throw std::runtime_error(request.prefix + "cannot load " + request.what + tried + request.need + ": " + error);
  }
  void* entry = dlsym(plugin, request.entry);
  if (entry == nullptr) throw std::runtime_error(request.prefix + path + " lacks " + request.entry);
  return {entry, path};
}

}  // namespace vibro::detail
