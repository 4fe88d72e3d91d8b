#pragma once
// What the container's two writers and its reader share (internal to formats/container): where a
// section starts, and the header and table both writers put before the sections.

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "svokit/formats/container/container.hpp"

namespace svokit::container::detail {

/// The first section offset at or after `n`.
inline std::size_t AlignUp(std::size_t n) {
  return (n + kAlignment - 1) / kAlignment * kAlignment;
}

/// Header and section table of a file whose sections (`tags`) lie at `placed`.
std::vector<std::uint8_t> EncodeHeaderAndTable(const FormatId& format, std::uint32_t flags,
                                               std::span<const Tag> tags,
                                               std::span<const Writer::Placed> placed);

}  // namespace svokit::container::detail
