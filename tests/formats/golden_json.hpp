#pragma once
// The JSON of the golden files (formats/golden): written with every array of numbers on one line,
// so that a file of a few thousand values stays readable and a change shows as one line of a
// diff, and compared value by value, naming the first path where two documents differ.

#include <optional>
#include <string>

#include <nlohmann/json.hpp>

namespace svokit::test {

using Json = nlohmann::ordered_json;

/// `json` as text: objects one member per line, arrays of scalars on one line, 2-space indents,
/// a final newline.
std::string FormatJson(const Json& json);

/// The first difference between `expected` and `actual`, depth first in `expected`'s order, as
/// "PATH: expected X, got Y" (PATH a JSON pointer, e.g. /levels/3/opacity/17); none if they are
/// equal. Numbers compare by value, whatever their JSON type.
std::optional<std::string> FirstDifference(const Json& expected, const Json& actual);

}  // namespace svokit::test
