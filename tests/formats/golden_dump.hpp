#pragma once
// What svokit's readers make of a file, as JSON (formats/golden/README.md, "The JSON"): the
// container's frame, then everything the format's C++ readers decode, array by array, so that
// another implementation can be checked against it value by value.

#include <filesystem>

#include "svokit/core/status.hpp"
#include "tests/formats/golden_json.hpp"

namespace svokit::test {

/// The dump of a .svm, .vfrag or .svo (by its extension), read with ReadSvm, ReadVfrag (and
/// ReadVfragInterior) or ReadSvo and SvoReader.
StatusOr<Json> DumpFormatFile(const std::filesystem::path& path);

}  // namespace svokit::test
