#include "engine/cli_app.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "engine/cli.h"
#include "sim/params.h"

namespace fp::engine {

namespace {
std::string formatNumber(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

std::string rangeText(double min, double max) {
  return "[" + formatNumber(min) + ", " + formatNumber(max) + "]";
}

// the message of a checked parser without its "FLAG " head: CLI11 puts "--flag: " in front
std::string withoutFlag(const std::string& message) {
  const std::size_t space = message.find(' ');
  return space == std::string::npos ? message : message.substr(space + 1);
}
}  // namespace

CLI::Validator numberIn(double min, double max) {
  return CLI::Validator(
      [min, max](std::string& text) -> std::string {
        try {
          const double v = parseNumber("-", text);
          if (v < min || v > max)
            return "expects a number in " + rangeText(min, max) + ", got '" + text + "'";
        } catch (const std::invalid_argument& e) {
          return withoutFlag(e.what());
        }
        return "";
      },
      "");
}

CLI::Validator positiveNumber() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        try {
          parsePositive("-", text);
        } catch (const std::invalid_argument& e) {
          return withoutFlag(e.what());
        }
        return "";
      },
      "");
}

CLI::Validator integerIn(long long min, long long max) {
  return CLI::Validator(
      [min, max](std::string& text) -> std::string {
        try {
          parseInteger("-", text, min, max);
        } catch (const std::invalid_argument& e) {
          return withoutFlag(e.what());
        }
        return "";
      },
      "");
}

CLI::Validator choiceOf(const std::string& names, std::function<bool(const std::string&)> parse) {
  return CLI::Validator(
      [names, parse](std::string& text) -> std::string {
        return parse(text) ? std::string() : "expects one of " + names + ", got '" + text + "'";
      },
      "");
}

CLI::Validator tableSetting() {
  return CLI::Validator([](std::string& text) -> std::string { return checkSetting(text); }, "");
}

CommandLine::CommandLine(std::string program, const std::string& description)
    : m_program(std::move(program)), m_app(description, m_program) {
  // the last of a repeated option wins, as it always did
  m_app.option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
  m_app.get_formatter()->column_width(26);
  m_app.set_help_flag("-h,--help", "print this help and exit");
}

CLI::Option* CommandLine::addNumber(const std::string& name, std::function<void(double)> set, double min,
                                    double max, const std::string& help) {
  return m_app
      .add_option_function<std::string>(
          name, [name, set](const std::string& text) { set(parseNumber(name, text)); },
          help + ", in " + rangeText(min, max))
      ->check(numberIn(min, max))
      ->type_name("S");
}

CLI::Option* CommandLine::addPositive(const std::string& name, std::function<void(double)> set,
                                      const std::string& help) {
  return m_app
      .add_option_function<std::string>(
          name, [name, set](const std::string& text) { set(parseNumber(name, text)); }, help + ", > 0")
      ->check(positiveNumber())
      ->type_name("S");
}

CLI::Option* CommandLine::addInteger(const std::string& name, std::function<void(long long)> set,
                                     long long min, long long max, const std::string& help) {
  return m_app
      .add_option_function<std::string>(
          name, [name, set, min, max](const std::string& text) { set(parseInteger(name, text, min, max)); },
          help + ", in [" + std::to_string(min) + ", " + std::to_string(max) + "]")
      ->check(integerIn(min, max))
      ->type_name("N");
}

CLI::Option* CommandLine::addSeed(std::function<void(std::uint64_t)> set) {
  const sim::ParamInfo& seed = sim::ParamTable::sim().at("seed");
  return addInteger(
      "--seed", [set](long long v) { set(std::uint64_t(v)); }, (long long)seed.min, (long long)seed.max,
      "seed of every random choice (overrides the scene's)");
}

CLI::Option* CommandLine::addSet(std::vector<std::string>& sets) {
  return m_app
      .add_option_function<std::vector<std::string>>(
          "--set",
          [&sets](const std::vector<std::string>& kv) { sets.insert(sets.end(), kv.begin(), kv.end()); },
          "set a simulation parameter over the scene's, or a render setting (repeatable), e.g. --set "
          "dt_max=0.002 --set view=particles; checked by their tables for type, range and relations")
      ->check(tableSetting())
      ->type_name("KEY=VALUE")
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll)
      ->allow_extra_args(false);
}

bool CommandLine::parse(const std::vector<std::string>& args) {
  std::vector<std::string> reversed(args.rbegin(), args.rend());  // CLI11 takes them last first
  try {
    m_app.parse(reversed);
  } catch (const CLI::CallForHelp&) {
    return false;
  } catch (const CLI::ParseError& e) {
    std::string message = e.what();
    std::replace(message.begin(), message.end(), '\n', ' ');
    throw std::invalid_argument(message);
  }
  return true;
}

std::optional<int> CommandLine::parse(int argc, const char* const* argv) {
  try {
    if (!parse(std::vector<std::string>(argv + 1, argv + argc))) {
      std::cout << help();
      return kExitOk;
    }
  } catch (const std::invalid_argument& e) {
    std::cerr << usageErrorLine(m_program, e.what()) << "\n";
    return kExitUsage;
  }
  return std::nullopt;
}

std::string CommandLine::help() const {
  return m_app.help();
}

std::string usageErrorLine(const std::string& program, const std::string& message) {
  return program + ": " + message + " (" + program + " --help lists the options)";
}

}  // namespace fp::engine
