#pragma once
// What the .vfrag reader and writer share with the cube-by-cube ones (internal to formats/vfrag).

#include <cstdint>
#include <span>
#include <vector>

#include "svokit/core/half.hpp"
#include "svokit/formats/container/container.hpp"
#include "svokit/formats/vfrag/vfrag.hpp"

namespace svokit::vfrag_detail {

using container::MakeTag;
inline constexpr container::Tag kGrid = MakeTag("GRID");
inline constexpr container::Tag kKeys = MakeTag("KEYS");
inline constexpr container::Tag kColors = MakeTag("COLR");
inline constexpr container::Tag kNormals = MakeTag("NORM");
inline constexpr container::Tag kCoverage = MakeTag("COVR");
inline constexpr container::Tag kMetadata = MakeTag("META");

/// The META section of `meta`, and back (metadata that is not such JSON reads as empty).
std::vector<std::uint8_t> MetadataSection(const VfragMetadata& meta);
VfragMetadata ParseMetadata(std::span<const std::uint8_t> text);

inline bool IsFiniteHalf(Half h) {
  return (h.bits & 0x7c00u) != 0x7c00u;
}

}  // namespace svokit::vfrag_detail
