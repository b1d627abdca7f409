#include "engine/presets.h"

#include <fstream>

#include "engine/json_reader.h"

namespace fp::engine {

void savePreset(const std::string& path, const Preset& preset) {
  nlohmann::ordered_json j;
  j["mode"] = sim::modeName(preset.mode);
  j["parameters"] = tableToJson(sim::ParamTable::sim(), preset.params);
  j["render"] = tableToJson(render::RenderSettingsTable::get(), preset.render);
  std::ofstream out(path, std::ios::trunc);
  if (!out)
    throw sim::InputError(path + ": cannot write the preset");
  out << j.dump(2) << "\n";
  if (!out)
    throw sim::InputError(path + ": write failed");
}

Preset loadPreset(const std::string& path, const Preset& base) {
  // the scenes' strict reader: duplicate and unknown keys, types and ranges, each error with its JSON path
  const JsonReader reader(path);
  const nlohmann::json j = reader.parse(readTextFile(path, "the preset"));
  reader.expectObject(j, "$", {"mode", "parameters", "render"});
  Preset p = base;
  if (j.contains("mode")) {
    const std::string name = reader.readString(j["mode"], "$.mode");
    const auto mode = sim::parseMode(name);
    if (!mode)
      reader.fail("$.mode", "expected one of " + std::string(sim::modeNames()) + ", got '" + name + "'");
    p.mode = *mode;
  }
  if (j.contains("parameters"))
    reader.readTable(j["parameters"], "$.parameters", sim::ParamTable::sim(), p.params);
  if (j.contains("render"))
    reader.readTable(j["render"], "$.render", render::RenderSettingsTable::get(), p.render);
  const std::string relation = sim::ParamTable::validate(p.params);
  if (!relation.empty())
    reader.fail(j.contains("parameters") ? "$.parameters" : "$", relation);
  return p;
}

}  // namespace fp::engine
