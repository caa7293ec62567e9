// libFuzzer harness of the scene parser (cmake -DVIBRO_FUZZ=ON with clang; docs/reliability.md):
//   build-fuzz/vibro_fuzz_scene -max_total_time=600 data/scenes
#include <cstddef>
#include <cstdint>

#include "fuzz_targets.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  vibro::fuzz::SceneTarget(data, size);
  return 0;
}
