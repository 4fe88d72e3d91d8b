#include "svokit/core/byte_size.hpp"

#include <charconv>

#include <fmt/format.h>

namespace svokit {

StatusOr<std::uint64_t> ParseByteSize(const std::string& what, const std::string& text) {
  std::uint64_t value = 0;
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, value);
  int shift = 0;
  if (ptr != end && ptr + 1 == end) {
    switch (*ptr) {
      case 'K':
      case 'k':
        shift = 10;
        break;
      case 'M':
      case 'm':
        shift = 20;
        break;
      case 'G':
      case 'g':
        shift = 30;
        break;
      case 'T':
      case 't':
        shift = 40;
        break;
      default:
        shift = -1;
    }
  }
  if (ec != std::errc() || ptr == text.data() || shift < 0 || (ptr != end && shift == 0) ||
      value == 0 || value > (~std::uint64_t{0} >> shift)) {
    return Status::BadInput("{} '{}': expected a size such as 4G, 512M or a byte count", what,
                            text);
  }
  return value << shift;
}

std::string ByteSizeText(double bytes) {
  return bytes >= 1073741824.0 ? fmt::format("{:.1f} GiB", bytes / 1073741824.0)
                               : fmt::format("{:.0f} MiB", bytes / 1048576.0);
}

}  // namespace svokit
