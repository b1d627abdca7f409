#pragma once
/// Panel presets: the resolution mode, every parameter of the table and every render setting, saved and
/// loaded as JSON ({"mode": "fluidplaying", "parameters": {"<key>": value, ...}, "render": {"<key>": value,
/// ...}}), read by the scenes' strict JSON reader.

#include <string>

#include "render/render_settings.h"
#include "sim/params.h"
#include "sim/scene.h"

namespace fp::engine {

/// What a preset holds.
struct Preset {
  sim::AdaptivityMode mode = sim::AdaptivityMode::FluidPlaying;  ///< resolution mode
  sim::SimParams params;                                         ///< every parameter of the table
  render::RenderSettings render;  ///< every render setting of render::RenderSettingsTable
};

/// Writes a preset; throws sim::InputError when the file cannot be written.
void savePreset(const std::string& path, const Preset& preset);
/// Reads a preset over `base` (keys and sections left out keep base's values); throws sim::InputError naming
/// the file and JSON path for duplicate or unknown keys, wrong types, out-of-range values or broken
/// relations.
Preset loadPreset(const std::string& path, const Preset& base);

}  // namespace fp::engine
