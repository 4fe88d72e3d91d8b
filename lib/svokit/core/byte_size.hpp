#pragma once
// Sizes in bytes as people write them: "4G", "512M", "64K" or a byte count, and back.

#include <cstdint>
#include <string>

#include "svokit/core/status.hpp"

namespace svokit {

/// The bytes `text` names ("4G", "512M", "64K", "1T" or a count; a suffix is a power of 1024); an
/// error names `what` (e.g. the option that gave it).
StatusOr<std::uint64_t> ParseByteSize(const std::string& what, const std::string& text);

/// "4.0 GiB" or "120 MiB".
std::string ByteSizeText(double bytes);

}  // namespace svokit
