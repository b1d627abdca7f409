#include "engine/presets.h"

#include <fstream>
#include <nlohmann/json.hpp>

namespace fp::engine {

void savePreset(const std::string& path, const Preset& preset) {
  nlohmann::ordered_json params = nlohmann::ordered_json::object();
  for (const sim::ParamInfo& info : sim::ParamTable::sim().entries()) {
    switch (info.kind) {
      case sim::ParamKind::Vector3:
        params[info.key] = sim::ParamTable::getVec3(preset.params, info);
        break;
      case sim::ParamKind::Boolean:
        params[info.key] = sim::ParamTable::getScalar(preset.params, info) != 0.0;
        break;
      case sim::ParamKind::Integer:
        params[info.key] = static_cast<long long>(sim::ParamTable::getScalar(preset.params, info));
        break;
      case sim::ParamKind::Seed:
        params[info.key] = preset.params.seed;
        break;
      case sim::ParamKind::Number:
        params[info.key] = sim::ParamTable::getScalar(preset.params, info);
        break;
    }
  }
  nlohmann::ordered_json j;
  j["mode"] = sim::modeName(preset.mode);
  j["parameters"] = params;
  std::ofstream out(path, std::ios::trunc);
  if (!out)
    throw sim::InputError(path + ": cannot write the preset");
  out << j.dump(2) << "\n";
  if (!out)
    throw sim::InputError(path + ": write failed");
}

Preset loadPreset(const std::string& path, const Preset& base) {
  std::ifstream in(path);
  if (!in)
    throw sim::InputError(path + ": cannot open the preset");
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw sim::InputError(path + ": invalid JSON: " + e.what());
  }
  if (!j.is_object())
    throw sim::InputError(path + ": a preset is a JSON object");
  Preset p = base;
  for (const auto& [key, value] : j.items()) {
    if (key == "mode") {
      const auto mode = value.is_string() ? sim::parseMode(value.get<std::string>()) : std::nullopt;
      if (!mode)
        throw sim::InputError(path + ": $.mode: expected one of " + sim::modeNames());
      p.mode = *mode;
    } else if (key != "parameters") {
      throw sim::InputError(path + ": $." + key + ": unknown key (expected mode, parameters)");
    }
  }
  if (j.contains("parameters")) {
    const nlohmann::json& params = j["parameters"];
    if (!params.is_object())
      throw sim::InputError(path + ": $.parameters: expected an object");
    for (const auto& [key, value] : params.items()) {
      const std::string where = path + ": $.parameters." + key + ": ";
      const sim::ParamInfo* info = sim::ParamTable::sim().find(key);
      if (!info)
        throw sim::InputError(where + "unknown parameter");
      std::string error;
      if (info->kind == sim::ParamKind::Vector3) {
        if (!value.is_array() || value.size() != 3 || !value[0].is_number() || !value[1].is_number() ||
            !value[2].is_number())
          throw sim::InputError(where + "expected an array of 3 numbers");
        error = sim::ParamTable::setVec3(
            p.params, *info, {value[0].get<double>(), value[1].get<double>(), value[2].get<double>()});
      } else if (info->kind == sim::ParamKind::Boolean) {
        if (!value.is_boolean())
          throw sim::InputError(where + "expected true or false");
        error = sim::ParamTable::setScalar(p.params, *info, value.get<bool>() ? 1.0 : 0.0);
      } else {
        if (!value.is_number())
          throw sim::InputError(where + "expected a number");
        error = sim::ParamTable::setScalar(p.params, *info, value.get<double>());
      }
      if (!error.empty())
        throw sim::InputError(where + error);
    }
  }
  const std::string relation = sim::ParamTable::validate(p.params);
  if (!relation.empty())
    throw sim::InputError(path + ": " + relation);
  return p;
}

}  // namespace fp::engine
