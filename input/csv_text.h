#pragma once
/// The text side of the recorded-motion CSV files (input/pose_track, input/joint_track): exact,
/// locale-independent numbers and comma-separated fields.

#include <string>
#include <string_view>
#include <vector>

namespace fp::input::csv {

/// the shortest decimal text that parses back to exactly `value`, independent of the C locale (unlike
/// printf, whose decimal separator follows LC_NUMERIC)
std::string formatExact(double value);
/// `s` without leading and trailing blanks (space, tab, carriage return)
std::string_view trim(std::string_view s);
/// parses the whole of `field` (trimmed, a leading '+' allowed) as a double, exactly and independent of the
/// locale; false when it is not a number
bool parseDouble(std::string_view field, double& value);
/// the fields of `line` between commas, each trimmed
std::vector<std::string_view> splitCommas(std::string_view line);
/// the first line of the file at `path`, trimmed ("" when it cannot be read)
std::string firstLine(const std::string& path);

}  // namespace fp::input::csv
