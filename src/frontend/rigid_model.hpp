// The entry check of the analyses built on the rigid model's saltations (docs/compliant.md): the
// one place that says which commands refuse a compliant stop and with what message, for the
// command line (src/cli/main.cpp) and the Python module (python/src/bindings.cpp) alike.
//
// A compliant stop (a stiffness on [stop] or a [[contact]]) runs in `simulate` (with
// --rigid-beside), `model`, `check` (the exact engine against CVODE), `orbit` (the compliant
// saltations of docs/compliant.md, "Periodic orbits") and `continue` (the same map along a branch);
// proofs, `check --precision quad`, `validate`, `score`, the studies, `sweep`, `partition`, `curve`
// and `diagram` do not handle its contact phase yet: they refuse such a scene before anything is
// computed, rather than answer for a rigid stop.
#pragma once

#include <string>

#include "frontend/limits.hpp"
#include "vibro/scene_file.hpp"

namespace vibro::frontend {

// Whether `command`, named as on the command line ("simulate", "orbit", "continue", ..., or a
// command with the option that matters, "check --precision quad"), runs on a scene with a
// compliant stop.
bool TakesCompliantStops(const std::string& command);

// The entry check of `command` on a scene: InputError naming `scene` (the file, or the source of a
// scene given as text) when the scene has a compliant stop and the command does not take one.
// `naming` words the message for the caller's users (on the command line "this command", in
// Python "this function"; a command with an option is named with it).
void CheckSceneModel(const std::string& command, const LoadedScene& loaded, const std::string& scene, Naming naming);

}  // namespace vibro::frontend
