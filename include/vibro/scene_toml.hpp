// A scene written back as TOML with every key resolved (defaults included), numbers in their
// shortest form that reads back to the same double: what an output stores as provenance
// (attribute scene_resolved), so that the run can be repeated without knowing vibro's defaults.
#pragma once

#include <string>

#include "vibro/scene.hpp"

namespace vibro {

// Every key of CONTRACT §1 that applies to the scene's structure form. An initial state left to
// its default (empty) is written as a comment, as the default depends on the model.
std::string ResolvedSceneToml(const Scene& scene);

}  // namespace vibro
