#pragma once
// The voxelizer's output: the set of filled voxels as sorted, unique 64-bit Morton keys, with the
// grid that maps them back to world space (and, when requested, per-voxel attributes).
//   VoxelSet             the voxels as 64-bit keys, in its own vectors (Voxelize())
//   PackedVoxelSet       the voxels with keys as varint gaps, in its own vectors (VoxelizePacked())
//   PackedVoxelStorage   memory a caller provides for the packed arrays instead (a .vfrag file)
//   PackedVoxelContents  which of those arrays a packed voxelization fills
//   PackedVoxelArrays    those arrays, as spans into the caller's memory
//   PackedVoxelization   what a voxelization into a PackedVoxelStorage returns besides the arrays

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "svokit/core/default_init.hpp"
#include "svokit/core/grid_transform.hpp"
#include "svokit/core/half.hpp"
#include "svokit/core/morton.hpp"
#include "svokit/core/octahedral.hpp"
#include "svokit/core/status.hpp"
#include "svokit/core/vec.hpp"

namespace svokit {

enum class VoxelMode : std::uint32_t {
  kConservative = 0,  ///< every voxel whose closed box touches the triangle (26-separating)
  kThin = 1,          ///< Schwarz & Seidel 2010's 6-separating subset
};

/// What a voxelization holds besides its keys: the grid, the mode and the per-voxel attributes
/// (VoxelSet, PackedVoxelSet).
struct VoxelAttributes {
  GridTransform grid;
  VoxelMode mode = VoxelMode::kConservative;
  /// Per voxel (parallel to the keys), when requested: the area-weighted mean colour (linear
  /// RGBA, straight alpha) and unit normal of the surface inside the voxel, and that surface's area
  /// in voxel² (its coverage). Colour and coverage in binary16, the normal as 16-bit octahedral
  /// codes (4 bytes, ≤ 7·10⁻⁵ rad), as .vfrag stores them: ~3 significant digits are all a
  /// filtered colour or a weight needs, and the bytes a voxel saves (22 over floats) are fresh
  /// memory the voxelizer would otherwise have to touch. Empty when not requested.
  /// A colour every voxel has (an untextured mesh without vertex colours, one material colour)
  /// is held once: `colors` then has one entry; read colours through color(i). Sized without
  /// zeroing: the voxelizer's threads fill (and first touch) them in parallel.
  DefaultInitVector<HalfRgba> colors;
  DefaultInitVector<OctNormal> normals;
  DefaultInitVector<Half> coverage;
  /// Non-fatal findings of the voxelization (e.g. a texture that could not be decoded, so its
  /// materials used their base colour). Not stored in files.
  std::vector<std::string> warnings;

  bool has_colors() const { return !colors.empty(); }
  /// Voxel i's colour (has_colors()), whether held per voxel or once for all.
  HalfRgba color(std::size_t i) const { return colors[colors.size() == 1 ? 0 : i]; }
  bool has_normals() const { return !normals.empty(); }
};

struct VoxelSet : VoxelAttributes {
  /// Sorted ascending, unique. (Sized without zeroing: it is filled in parallel right after.)
  DefaultInitVector<std::uint64_t> keys;

  std::size_t size() const { return keys.size(); }
};

/// A VoxelSet whose keys are packed as .vfrag stores them (varint gaps, core/key_gaps.hpp): ~1
/// byte a voxel instead of 8. What svo-voxelize writes a file from: at 4096³ the keys are most of
/// a VoxelSet's fresh memory, and fresh memory is what these machines pay for.
struct PackedVoxelSet : VoxelAttributes {
  std::uint64_t count = 0;
  DefaultInitVector<std::uint8_t> key_gaps;

  std::size_t size() const { return static_cast<std::size_t>(count); }
};

/// Which per-voxel arrays a packed voxelization fills, and whether it has a colour every voxel
/// shares instead (held once, in VoxelAttributes::colors).
struct PackedVoxelContents {
  bool colors = false, normals = false, coverage = false;
  bool shared_color = false;
};

/// A packed voxelization's arrays (PackedVoxelSet's), in memory its caller provides.
struct PackedVoxelArrays {
  std::span<std::uint8_t> key_gaps;
  std::span<HalfRgba> colors;  ///< empty unless PackedVoxelContents::colors
  std::span<OctNormal> normals;
  std::span<Half> coverage;
};

/// Memory for VoxelizePacked()'s arrays that its caller provides: svo-voxelize gives it a .vfrag
/// file's sections, mapped (VfragFileWriter), so every byte is written once, where the file
/// keeps it, instead of into fresh memory and then into the file.
class PackedVoxelStorage {
 public:
  virtual ~PackedVoxelStorage() = default;
  /// Arrays with room for `voxels` entries (each array `contents` asks for) and `key_bytes`
  /// bytes of keys, holding what the previous ones held (up to the smaller room). They may move:
  /// not called while the arrays are being written.
  virtual StatusOr<PackedVoxelArrays> Reserve(const PackedVoxelContents& contents,
                                              std::size_t voxels, std::size_t key_bytes) = 0;
};

/// What a voxelization into a PackedVoxelStorage returns besides the arrays: grid, mode,
/// warnings and a shared colour (`attributes`, whose arrays are otherwise empty), and how much
/// of each array holds voxels.
struct PackedVoxelization {
  VoxelAttributes attributes;
  PackedVoxelContents contents;
  std::uint64_t count = 0;
  std::size_t key_bytes = 0;
};

}  // namespace svokit
