// The fuzz targets of vibro (docs/reliability.md), shared by the libFuzzer harnesses (built with
// -DVIBRO_FUZZ=ON and clang) and the seeded smoke driver run by ctest.
//
// Each target feeds one input to a reader and returns normally when the reader accepted it or
// refused it with an InputError whose every message is located (names the file, or the --set
// override); anything else (another exception, a message that says not where) aborts, which is
// what a fuzzer reports as a finding.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace vibro::fuzz {

// The scene parser: the input is a scene file's text; a first line "#set KEY=VALUE" is applied
// as a --set override.
void SceneTarget(const std::uint8_t* data, std::size_t size);

// The HDF5 readers: the input is written to `scratch` and read as a stored run (vibro info,
// plot); when `resume_scene` is a scene's text, a resume of that scene is tried too, and a
// refused resume must leave the file byte for byte as it was.
void StoredRunTarget(const std::uint8_t* data, std::size_t size, const std::string& scratch,
                     const std::string& resume_scene = {});

}  // namespace vibro::fuzz
