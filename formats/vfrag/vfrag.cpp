#include "formats/vfrag/vfrag.hpp"

#include <algorithm>
#include <cmath>

#include <nlohmann/json.hpp>

#include "formats/container/bytes.hpp"
#include "formats/container/grid_section.hpp"
#include "svokit/core/file_io.hpp"

namespace svokit {

namespace {

using container::MakeTag;
constexpr container::Tag kGrid = MakeTag("GRID");
constexpr container::Tag kKeys = MakeTag("KEYS");
constexpr container::Tag kColors = MakeTag("COLR");
constexpr container::Tag kNormals = MakeTag("NORM");
constexpr container::Tag kCoverage = MakeTag("COVR");
constexpr container::Tag kMetadata = MakeTag("META");

template <class T>
std::span<const std::uint8_t> Bytes(const std::vector<T>& v) {
  return {reinterpret_cast<const std::uint8_t*>(v.data()), v.size() * sizeof(T)};
}

// An optional per-voxel array: absent, or exactly one T per voxel.
template <class T>
Status ReadPerVoxel(const container::Reader& file, container::Tag tag, std::size_t voxels,
                    std::vector<T>& out) {
  const auto section = file.Find(tag);
  if (!section) return Status::Ok();
  if (section->size() != voxels * sizeof(T)) {
    return Status::BadInput("{}: section '{}' holds {} bytes, expected {} for {} voxels",
                            file.name(), std::string(tag.begin(), tag.end()), section->size(),
                            voxels * sizeof(T), voxels);
  }
  ByteReader r(*section, file.name());
  return r.GetArray(out, voxels);
}

StatusOr<VoxelSet> DecodeSections(const StatusOr<container::Reader>& file, VfragMetadata* meta) {
  if (!file.ok()) return file.status();
  const std::string& name = file->name();
  auto grid = file->Require(kGrid);
  if (!grid.ok()) return grid.status();
  auto keys = file->Require(kKeys);
  if (!keys.ok()) return keys.status();

  VoxelSet set;
  SVOKIT_RETURN_IF_ERROR(DecodeGridSection(*grid, name, set.grid, set.mode));
  const auto& dims = set.grid.dims();
  if (keys->size() % sizeof(std::uint64_t) != 0) {
    return Status::BadInput("{}: KEYS section size is not a multiple of 8", name);
  }
  ByteReader k(*keys, name + ": KEYS section");
  SVOKIT_RETURN_IF_ERROR(k.GetArray(set.keys, keys->size() / sizeof(std::uint64_t)));
  for (std::size_t i = 0; i < set.keys.size(); ++i) {
    if (i > 0 && set.keys[i] <= set.keys[i - 1]) {
      return Status::BadInput("{}: voxel keys are not strictly increasing at index {}", name, i);
    }
    const MortonCoord c = MortonDecode(set.keys[i]);
    if (set.keys[i] >> 63 || c.x >= dims[0] || c.y >= dims[1] || c.z >= dims[2]) {
      return Status::BadInput("{}: voxel {} lies outside the {}x{}x{} grid", name, i, dims[0],
                              dims[1], dims[2]);
    }
  }
  SVOKIT_RETURN_IF_ERROR(ReadPerVoxel(*file, kColors, set.keys.size(), set.colors));
  SVOKIT_RETURN_IF_ERROR(ReadPerVoxel(*file, kNormals, set.keys.size(), set.normals));
  if (file->version() >= 2) {
    SVOKIT_RETURN_IF_ERROR(ReadPerVoxel(*file, kCoverage, set.keys.size(), set.coverage));
  } else {  // version 1 stored coverage as f32
    std::vector<float> coverage;
    SVOKIT_RETURN_IF_ERROR(ReadPerVoxel(*file, kCoverage, set.keys.size(), coverage));
    set.coverage.assign(coverage.begin(), coverage.end());
  }
  for (const Rgba& c : set.colors) {
    if (!std::isfinite(c.r) || !std::isfinite(c.g) || !std::isfinite(c.b) || !std::isfinite(c.a)) {
      return Status::BadInput("{}: non-finite voxel colour", name);
    }
  }
  for (const Vec3f& n : set.normals) {
    if (!IsFinite(n)) return Status::BadInput("{}: non-finite voxel normal", name);
  }
  if (meta != nullptr) {
    *meta = {};
    if (const auto text = file->Find(kMetadata)) {
      const nlohmann::json j = nlohmann::json::parse(text->begin(), text->end(), nullptr, false);
      if (j.is_object()) {
        meta->source = j.value("source", "");
        meta->options = j.value("options", "");
      }
    }
  }
  return set;
}

}  // namespace

namespace {

// The container borrows the keys (the largest array); `set` must outlive the returned writer.
container::Writer MakeWriter(const VoxelSet& set, const VfragMetadata& meta) {
  container::Writer file(kVfragFormat, 0);
  file.AddSection(kGrid, EncodeGridSection(set.grid, set.mode));
  file.AddSectionView(kKeys, Bytes(set.keys));
  if (set.has_colors()) file.AddSectionView(kColors, Bytes(set.colors));
  if (set.has_normals()) file.AddSectionView(kNormals, Bytes(set.normals));
  if (!set.coverage.empty()) file.AddSectionView(kCoverage, Bytes(set.coverage));
  const nlohmann::json j = {
      {"source", meta.source}, {"options", meta.options}, {"generator", "svokit " SVOKIT_VERSION}};
  const std::string text = j.dump();
  file.AddSection(kMetadata, std::vector<std::uint8_t>(text.begin(), text.end()));
  return file;
}

}  // namespace

std::vector<std::uint8_t> EncodeVfrag(const VoxelSet& set, const VfragMetadata& meta) {
  return MakeWriter(set, meta).Serialize();
}

Status WriteVfrag(const VoxelSet& set, const VfragMetadata& meta,
                  const std::filesystem::path& path) {
  return MakeWriter(set, meta).WriteFile(path);
}

StatusOr<VoxelSet> DecodeVfrag(std::span<const std::uint8_t> bytes, const std::string& name,
                               VfragMetadata* meta) {
  return DecodeSections(container::Reader::FromBytes(bytes, name, kVfragFormat), meta);
}

StatusOr<VoxelSet> ReadVfrag(const std::filesystem::path& path, VfragMetadata* meta) {
  return DecodeSections(container::Reader::Open(path, kVfragFormat), meta);
}

Status WriteVoxelsXyz(const VoxelSet& set, const std::filesystem::path& path) {
  const Vec3d& o = set.grid.origin();
  const auto& d = set.grid.dims();
  // {} prints the shortest representation that reads back to the same double.
  std::string text = fmt::format("# origin {} {} {}\n# voxel_size {}\n# dims {} {} {}\n", o.x, o.y,
                                 o.z, set.grid.voxel_size(), d[0], d[1], d[2]);
  text.reserve(text.size() + set.keys.size() * 16);
  for (std::uint64_t key : set.keys) {
    const MortonCoord c = MortonDecode(key);
    fmt::format_to(std::back_inserter(text), "{} {} {}\n", c.x, c.y, c.z);
  }
  return WriteFileAtomic(path, {reinterpret_cast<const std::uint8_t*>(text.data()), text.size()});
}

Status WriteVoxelsPly(const VoxelSet& set, const std::filesystem::path& path) {
  ByteWriter w;
  std::string header = fmt::format(
      "ply\nformat binary_little_endian 1.0\ncomment svokit voxel centres, voxel size {}\n"
      "element vertex {}\nproperty float x\nproperty float y\nproperty float z\n",
      set.grid.voxel_size(), set.keys.size());
  if (set.has_normals()) header += "property float nx\nproperty float ny\nproperty float nz\n";
  // PLY viewers expect 8-bit display (sRGB) colours.
  if (set.has_colors()) header += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  header += "end_header\n";
  w.PutArray<char>(std::span<const char>(header.data(), header.size()));
  auto to_byte = [](float linear) {
    return static_cast<std::uint8_t>(
        std::lround(255.f * LinearToSrgb(std::clamp(linear, 0.f, 1.f))));
  };
  for (std::size_t i = 0; i < set.keys.size(); ++i) {
    const MortonCoord c = MortonDecode(set.keys[i]);
    const Vec3d p = set.grid.VoxelCenter({c.x, c.y, c.z});
    w.Put(static_cast<float>(p.x));
    w.Put(static_cast<float>(p.y));
    w.Put(static_cast<float>(p.z));
    if (set.has_normals()) w.Put(set.normals[i]);
    if (set.has_colors()) {
      w.Put(to_byte(set.colors[i].r));
      w.Put(to_byte(set.colors[i].g));
      w.Put(to_byte(set.colors[i].b));
    }
  }
  return WriteFileAtomic(path, w.bytes());
}

}  // namespace svokit
