#include "engine/presets.h"

#include <fstream>
#include <nlohmann/json.hpp>
#include <type_traits>
#include <utility>

namespace fp::engine {

void savePreset(const std::string& path, const Preset& preset) {
  nlohmann::ordered_json params = nlohmann::ordered_json::object();
  for (const sim::ParamInfo& info : sim::ParamTable::sim().entries()) {
    sim::visit(info, preset.params, [&](const auto& v) {
      if constexpr (std::is_same_v<std::decay_t<decltype(v)>, sim::Choice>)
        params[info.key] = v.name();
      else
        params[info.key] = v;
    });
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
      const std::string error = sim::visit(*info, std::as_const(p.params), [&](const auto& current) {
        using T = std::decay_t<decltype(current)>;
        if constexpr (std::is_same_v<T, std::array<double, 3>>) {
          if (!value.is_array() || value.size() != 3 || !value[0].is_number() || !value[1].is_number() ||
              !value[2].is_number())
            throw sim::InputError(where + "expected an array of 3 numbers");
          return sim::ParamTable::setVec3(
              p.params, *info, {value[0].get<double>(), value[1].get<double>(), value[2].get<double>()});
        } else if constexpr (std::is_same_v<T, bool>) {
          if (!value.is_boolean())
            throw sim::InputError(where + "expected true or false");
          return sim::ParamTable::setScalar(p.params, *info, value.get<bool>() ? 1.0 : 0.0);
        } else if constexpr (std::is_same_v<T, sim::Choice>) {
          if (!value.is_string())
            throw sim::InputError(where + "expected a string");
          return sim::ParamTable::setChoice(p.params, *info, value.get<std::string>());
        } else {
          if (!value.is_number())
            throw sim::InputError(where + "expected a number");
          return sim::ParamTable::setScalar(p.params, *info, value.get<double>());
        }
      });
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
