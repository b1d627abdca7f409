#pragma once
/// Scene files: JSON in assets/scenes/ -> sim::SceneDesc. Unknown keys, wrong types, out-of-range values and
/// missing assets are rejected with one line naming the file and the JSON path.

#include <string>

#include "sim/scene.h"

namespace fp::engine {

/// Loads a scene file. Throws sim::InputError("FILE: $.json.path: what is wrong").
sim::SceneDesc loadScene(const std::string& path);

/// Parses scene JSON text. `fileName` is used in messages; relative asset paths are resolved against
/// `baseDir`.
sim::SceneDesc parseScene(const std::string& jsonText, const std::string& fileName,
                          const std::string& baseDir);

}  // namespace fp::engine
