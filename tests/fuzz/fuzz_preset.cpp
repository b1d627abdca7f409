// Panel presets: any bytes, loaded over the defaults (no crash, no sanitizer report); what loads must pass
// the parameter table's relations.

#include <cstddef>
#include <cstdint>
#include <cstdlib>

#include "engine/presets.h"
#include "tests/fuzz/fuzz_file.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string& path = fp::fuzz::writeInput(data, size, ".json");
  try {
    const fp::engine::Preset preset = fp::engine::loadPreset(path, fp::engine::Preset{});
    if (!fp::sim::ParamTable::validate(preset.params).empty())
      std::abort();  // a loaded preset breaks a relation: a bug of the loader
  } catch (const fp::sim::InputError&) {
  }
  return 0;
}
