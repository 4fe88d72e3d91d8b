#pragma once
// .vfrag — the voxel fragment list svo-voxelize writes and svo-build reads: a VoxelSet (sorted
// unique Morton keys) with its GridTransform, in the shared container. Layout: formats/vfrag.md.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "svokit/core/box.hpp"
#include "svokit/core/file_io.hpp"
#include "svokit/core/progress.hpp"
#include "svokit/core/status.hpp"
#include "svokit/formats/container/container.hpp"
#include "svokit/formats/container/mapped_writer.hpp"
#include "svokit/formats/provenance.hpp"
#include "svokit/voxelize/solid_fill.hpp"
#include "svokit/voxelize/voxel_set.hpp"

namespace svokit {

inline constexpr container::FormatId kVfragFormat{
    {'\x89', 'V', 'F', 'R', '\r', '\n', '\x1a', '\n'}, 5, "svokit voxel fragment list (.vfrag)"};

std::vector<std::uint8_t> EncodeVfrag(const VoxelSet& set, const Provenance& meta);
Status WriteVfrag(const VoxelSet& set, const Provenance& meta, const std::filesystem::path& path);
/// The same file from a set that is consumed: its arrays' memory goes back to the kernel as it is
/// written, for the file's page cache to reuse (fresh pages are slow on VMs); `set` is left empty.
Status WriteVfrag(VoxelSet&& set, const Provenance& meta, const std::filesystem::path& path);
/// The same file from voxels whose keys are packed already, as the voxelizer packs them.
std::vector<std::uint8_t> EncodeVfrag(const PackedVoxelSet& set, const Provenance& meta);
/// A .vfrag file the voxelizer writes into directly (a PackedVoxelStorage): its KEYS, COLR, NORM
/// and COVR sections are regions of a temporary beside `path`, mapped (container::MappedWriter),
/// which the voxelizer's threads fill in place; Commit() completes the file and renames it into
/// place. The same bytes as WriteVfrag() of the same voxels, without their copy into the file (a
/// 4096³ armadillo with attributes: 290 MB). Destroyed uncommitted, it leaves nothing behind.
class VfragFileWriter final : public PackedVoxelStorage {
 public:
  /// `solid`: the file will hold a solid's interior (Commit()'s `interior`).
  VfragFileWriter(std::filesystem::path path, const Provenance& meta, bool solid = false);
  StatusOr<PackedVoxelArrays> Reserve(const PackedVoxelContents& contents, std::size_t voxels,
                                      std::size_t key_bytes) override;
  /// The keys written so far, as varint gaps (`voxels`: what the packed voxelization returned).
  std::span<const std::uint8_t> KeyGaps(const PackedVoxelization& voxels) const;
  /// `voxels`: what the packed voxelization into this storage returned; `interior` for a solid
  /// writer.
  Status Commit(const PackedVoxelization& voxels, const InteriorCubes* interior = nullptr);

 private:
  // The file's sections for these contents and sizes (regions: their rooms, or used sizes).
  std::vector<container::MappedWriter::Section> Sections(const PackedVoxelContents& contents,
                                                         std::uint64_t voxels,
                                                         std::uint64_t key_bytes) const;

  std::filesystem::path path_;
  std::vector<std::uint8_t> metadata_, grid_, shared_color_;
  container::MappedWriter file_;
  bool open_ = false, solid_ = false;
  std::vector<std::uint8_t> interior_;
  PackedVoxelContents contents_;
};

/// A .vfrag written from runs of voxels in ascending key order (cubes as they are voxelized),
/// streamed through unnamed scratch files beside `path`, never held whole: WriteVfrag()'s bytes
/// for all of them, at any resolution. Destroyed uncommitted, it leaves nothing behind.
class VfragStreamWriter {
 public:
  /// `shared_color`: the colour every voxel has, stored once (runs then carry no colours).
  static StatusOr<std::unique_ptr<VfragStreamWriter>> Create(
      const std::filesystem::path& path, const GridTransform& grid, VoxelMode mode, bool colors,
      bool normals, std::optional<HalfRgba> shared_color, const Provenance& meta);
  ~VfragStreamWriter();
  VfragStreamWriter(const VfragStreamWriter&) = delete;
  VfragStreamWriter& operator=(const VfragStreamWriter&) = delete;

  /// Appends voxels whose keys follow every key appended before; returns the key bytes added.
  StatusOr<std::uint64_t> Append(const VoxelSet& run);
  std::uint64_t voxel_count() const { return count_; }
  /// Writes the file; none without voxels (an error naming the file).
  Status Commit();

 private:
  struct Arrays;
  VfragStreamWriter();

  std::filesystem::path path_;
  GridTransform grid_;
  VoxelMode mode_ = VoxelMode::kConservative;
  bool colors_ = false, normals_ = false;
  std::optional<HalfRgba> shared_color_;
  Provenance meta_;
  std::unique_ptr<ScratchFile> keys_;
  std::unique_ptr<Arrays> arrays_;
  std::uint64_t count_ = 0, previous_ = 0;
};

/// The voxel count a .vfrag states, without reading its voxels: for choosing how to read it.
StatusOr<std::uint64_t> VfragVoxelCount(const std::filesystem::path& path);

/// A .vfrag read a box of voxels at a time, never whole (svo-build --memory-limit): Open() makes
/// one pass over the file, checking its keys and every section's checksum, and keeps where each
/// cube of 2^cube_bits voxels that holds voxels begins; Read() then reads any box's voxels from
/// the cubes it meets. Version 5 files (what svo-voxelize writes). Reads may run in parallel.
class VfragCubes {
 public:
  static StatusOr<std::unique_ptr<VfragCubes>> Open(const std::filesystem::path& path,
                                                    int cube_bits, Provenance* meta = nullptr);
  ~VfragCubes();
  VfragCubes(const VfragCubes&) = delete;
  VfragCubes& operator=(const VfragCubes&) = delete;

  const GridTransform& grid() const { return grid_; }
  VoxelMode mode() const { return mode_; }
  bool has_colors() const { return colors_.present; }
  bool has_normals() const { return normals_.present; }
  /// The colour every voxel has, when the file stores one for all.
  std::optional<HalfRgba> shared_color() const;
  std::uint64_t voxel_count() const { return count_; }
  /// The cubes that hold voxels, by Morton key at the cube size, ascending.
  const std::vector<std::uint64_t>& cubes() const { return cube_keys_; }
  /// Bytes held: the cubes' index.
  std::size_t bytes() const { return cube_keys_.size() * (8 + sizeof(CubeStart)); }
  /// The voxels inside `box`, keys ascending, with their attributes as ReadVfrag() gives them.
  StatusOr<VoxelSet> Read(const IBox3& box) const;

 private:
  struct CubeStart {
    std::uint64_t voxel = 0;     ///< index of its first voxel
    std::uint64_t offset = 0;    ///< of its first key's varint, in the file
    std::uint64_t previous = 0;  ///< the key before its first
  };
  struct Array {
    bool present = false, shared = false;
    std::uint64_t offset = 0;  ///< in the file
  };
  template <class T>
  Status ReadRun(const Array& array, std::uint64_t first, std::uint64_t n,
                 std::vector<T>& out) const;
  VfragCubes() = default;

  std::string name_;
  int fd_ = -1;
  int bits_ = 0;
  GridTransform grid_;
  VoxelMode mode_ = VoxelMode::kConservative;
  std::uint64_t count_ = 0, keys_end_ = 0;
  std::vector<std::uint64_t> cube_keys_;
  std::vector<CubeStart> cube_starts_;
  Array colors_, normals_, coverage_;
  HalfRgba shared_color_value_{};
};

/// A solid's interior as the FILL section stores it (formats/vfrag.md), and back: every level's
/// keys ascending and below 8^level, the depth the grid's, every cube's first voxel inside it.
std::vector<std::uint8_t> EncodeInteriorSection(const InteriorCubes& interior);
StatusOr<InteriorCubes> DecodeInteriorSection(std::span<const std::uint8_t> bytes,
                                              const GridTransform& grid, const std::string& name);
/// The interior of a solid's .vfrag (`--fill solid`); none for a surface's.
StatusOr<std::optional<InteriorCubes>> ReadVfragInterior(const std::filesystem::path& path);

/// Verifies and decodes; fills `meta` (when given) from the META section.
StatusOr<VoxelSet> DecodeVfrag(std::span<const std::uint8_t> bytes, const std::string& name,
                               Provenance* meta = nullptr);
StatusOr<VoxelSet> ReadVfrag(const std::filesystem::path& path, Provenance* meta = nullptr);

}  // namespace svokit
