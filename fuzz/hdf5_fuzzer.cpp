// libFuzzer harness of the HDF5 readers (cmake -DVIBRO_FUZZ=ON with clang; docs/reliability.md):
//   build-fuzz/vibro_fuzz_hdf5 -max_total_time=600 CORPUS_DIR_OF_VIBRO_FILES
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz_targets.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string scratch = "/tmp/vibro_fuzz_hdf5_" + std::to_string(getpid()) + ".h5";
  vibro::fuzz::StoredRunTarget(data, size, scratch);
  return 0;
}
