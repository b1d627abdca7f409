#pragma once
/// The command lines of the executables, declared with CLI11: one `CommandLine` per executable declares its
/// options with types, ranges and help; `--help` is generated; a bad command line ends with exit code 2 and
/// one line on stderr, the same in every executable; `--set KEY=VALUE` is shared and checked by the parameter
/// table.

#include <CLI/CLI.hpp>

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace fp::engine {

/// A finite number in [min, max] (CLI11 check; the message names the range and the text given).
CLI::Validator numberIn(double min, double max);
/// A finite number > 0.
CLI::Validator positiveNumber();
/// An integer in [min, max] (written as an integer or as a whole number, e.g. 1e3).
CLI::Validator integerIn(long long min, long long max);
/// One of the names `names` ("a, b or c"), as `parse` accepts it.
CLI::Validator choiceOf(const std::string& names, std::function<bool(const std::string&)> parse);
/// "KEY=VALUE" naming a parameter of the simulation table with a value of its type and range.
CLI::Validator tableSetting();

/// One executable's command line.
class CommandLine {
 public:
  /// `program` names the executable in messages; `description` heads the --help text.
  CommandLine(std::string program, const std::string& description);

  /// the CLI11 application: declare the options on it
  CLI::App& app() { return m_app; }

  /// Declares a number option stored in `target` through `set` (range checked, help with the range).
  CLI::Option* addNumber(const std::string& name, std::function<void(double)> set, double min, double max,
                         const std::string& help);
  /// Declares a number option > 0.
  CLI::Option* addPositive(const std::string& name, std::function<void(double)> set, const std::string& help);
  /// Declares an integer option in [min, max].
  CLI::Option* addInteger(const std::string& name, std::function<void(long long)> set, long long min,
                          long long max, const std::string& help);
  /// Declares `--seed N`, with the range of the table's `seed` entry.
  CLI::Option* addSeed(std::function<void(std::uint64_t)> set);
  /// Declares the repeatable `--set KEY=VALUE`, appending each to `sets` (checked against the table).
  CLI::Option* addSet(std::vector<std::string>& sets);

  /// Parses `args` (without the program name). Returns false when --help was asked for; throws
  /// std::invalid_argument with a one-line message for a bad command line.
  bool parse(const std::vector<std::string>& args);
  /// Parses argv: std::nullopt to go on, or the exit code to end with: 0 after printing --help, 2 after one
  /// line "PROGRAM: MESSAGE (PROGRAM --help lists the options)" on stderr.
  std::optional<int> parse(int argc, const char* const* argv);

  /// the --help text
  std::string help() const;

 private:
  std::string m_program;
  CLI::App m_app;
};

/// The one line a bad command line prints: "PROGRAM: MESSAGE (PROGRAM --help lists the options)".
std::string usageErrorLine(const std::string& program, const std::string& message);

}  // namespace fp::engine
