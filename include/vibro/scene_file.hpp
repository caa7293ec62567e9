// Scene files (docs/scenes.md): TOML in, Scene out, with `--set KEY=VALUE` overrides and located
// error messages. The only file that includes toml++ is src/io/scene_file.cpp.
#pragma once

#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "vibro/scene.hpp"

namespace vibro {

// Bad input: every problem found, each formatted as
// `file:line:col: key.path = value: violated constraint ...` (or `--set K=V: ...` for overrides).
class InputError : public std::runtime_error {
 public:
  explicit InputError(std::vector<std::string> messages);
  const std::vector<std::string>& messages() const { return messages_; }

 private:
  std::vector<std::string> messages_;
};

struct LoadedScene {
  Scene scene;
  std::string source;       // file path (or the name given to ParseScene)
  std::string text_as_run;  // the scene as TOML after the overrides: what gets stored in outputs
};

// Reads, overrides, parses and validates a scene. Throws InputError listing every problem.
LoadedScene LoadScene(const std::string& path, const std::vector<std::string>& overrides = {});
// Same from text; `source` names it in messages.
LoadedScene ParseScene(std::string_view text, const std::string& source,
                       const std::vector<std::string>& overrides = {});

// The number at `key` (e.g. "excitation.amplitude", "contact[1].position") in a scene's TOML
// text, if any. contact[0].position and contact[0].restitution of a scene with a [stop] are the
// stop's. Throws InputError for contact[i].KEY when the scene has no contact i, naming the key and
// how many contacts the scene has.
std::optional<double> SceneNumber(const std::string& text, const std::string& key);

// The scene key nearest to a mistyped one ("amplitude" → "excitation.amplitude"), or "".
std::string NearestSceneKey(const std::string& key);

}  // namespace vibro
