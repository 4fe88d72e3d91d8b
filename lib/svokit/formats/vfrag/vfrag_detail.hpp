#pragma once
// What the .vfrag reader and writer share with the cube-by-cube ones (internal to formats/vfrag).

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "svokit/core/half.hpp"
#include "svokit/core/morton.hpp"
#include "svokit/core/status.hpp"
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
inline constexpr container::Tag kInterior = MakeTag("FILL");

/// The META section of `meta`, and back (metadata that is not such JSON reads as empty).
std::vector<std::uint8_t> MetadataSection(const Provenance& meta);
Provenance ParseMetadata(std::span<const std::uint8_t> text);

/// Voxel `i`'s key checked against the grid of `dims` (a key with bit 63 set lies outside any).
inline Status CheckKeyInGrid(std::uint64_t key, std::uint64_t i,
                             const std::array<std::uint32_t, 3>& dims, const std::string& name) {
  const MortonCoord c = MortonDecode(key);
  if (key >> 63 || c.x >= dims[0] || c.y >= dims[1] || c.z >= dims[2]) {
    return Status::BadInput("{}: voxel {} lies outside the {}x{}x{} grid", name, i, dims[0],
                            dims[1], dims[2]);
  }
  return Status::Ok();
}

inline bool IsFiniteHalf(Half h) {
  return (h.bits & 0x7c00u) != 0x7c00u;
}

}  // namespace svokit::vfrag_detail
