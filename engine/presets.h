#pragma once
/// Panel presets: the resolution mode and every parameter of the table, saved and loaded as JSON
/// ({"mode": "fluidplaying", "parameters": {"<key>": value, ...}}), read by the scenes' strict JSON reader.

#include <string>

#include "sim/params.h"
#include "sim/scene.h"

namespace fp::engine {

/// What a preset holds.
struct Preset {
  sim::AdaptivityMode mode = sim::AdaptivityMode::FluidPlaying;  ///< resolution mode
  sim::SimParams params;                                         ///< every parameter of the table
};

/// Writes a preset; throws sim::InputError when the file cannot be written.
void savePreset(const std::string& path, const Preset& preset);
/// Reads a preset over `base` (keys left out keep base's values); throws sim::InputError naming the file and
/// key for unknown keys, wrong types, out-of-range values or broken relations.
Preset loadPreset(const std::string& path, const Preset& base);

}  // namespace fp::engine
