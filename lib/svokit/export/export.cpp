#include "svokit/export/export.hpp"

#include <algorithm>
#include <array>

#include "svokit/core/file_io.hpp"
#include "svokit/core/parallel.hpp"
#include "svokit/export/voxel_writers.hpp"

namespace svokit {

namespace {

// The brick samples that stand for a node as a whole: the centre of an odd brick, the 8 corners
// of an even one (their opacity-weighted mean is then the node's value).
std::vector<std::uint32_t> NodeSamples(std::uint32_t side) {
  if (side == 0) return {};
  if (side % 2 == 1) return {side / 2 * (1 + side + side * side)};
  std::vector<std::uint32_t> corners;
  for (std::uint32_t c = 0; c < 8; ++c) {
    const std::uint32_t x = c & 1 ? side - 1 : 0, y = c & 2 ? side - 1 : 0,
                        z = c & 4 ? side - 1 : 0;
    corners.push_back(x + side * (y + side * z));
  }
  return corners;
}

}  // namespace

const std::vector<std::string>& ExportExtensions() {
  static const std::vector<std::string> kExtensions = {"vdb", "binvox", "vox", "ply", "xyz"};
  return kExtensions;
}

VoxelSet LevelVoxels(const Svo& svo, std::uint32_t level) {
  VoxelSet set;
  const std::uint32_t shift = svo.depth - level;
  std::array<std::uint32_t, 3> dims = svo.grid.dims();
  for (std::uint32_t& d : dims) d = ((d - 1) >> shift) + 1;
  set.grid = GridTransform(svo.grid.origin(), svo.NodeSize(level), dims);
  set.mode = svo.mode;
  const std::vector<std::uint64_t> keys = svo.LevelKeys(level);
  set.keys.assign(keys.begin(), keys.end());
  const std::vector<std::uint32_t> samples = NodeSamples(svo.brick_side);
  if (samples.empty()) return set;
  if (svo.has_color) set.colors.resize(set.keys.size());
  if (svo.has_normal) set.normals.resize(set.keys.size());
  ParallelChunks(set.keys.size(), 4096, [&](std::size_t begin, std::size_t end) {
    std::vector<BrickSample> s(samples.size());
    for (std::size_t i = begin; i < end; ++i) {
      float total = 0;
      for (std::size_t k = 0; k < samples.size(); ++k) {
        s[k] = svo.Sample(level, i, samples[k]);
        total += s[k].opacity;
      }
      Rgba color{0, 0, 0, 0};
      Vec3f normal{0, 0, 0};
      for (const BrickSample& b : s) {
        // An all-empty set of samples (possible only at coarse corners) falls back to a plain mean.
        const float w = total > 0 ? b.opacity / total : 1.f / static_cast<float>(s.size());
        color = {color.r + w * b.color.r, color.g + w * b.color.g, color.b + w * b.color.b,
                 color.a + w * b.color.a};
        normal = normal + b.normal * w;
      }
      if (svo.has_color) set.colors[i] = color;
      if (svo.has_normal) {
        const float len = Length(normal);
        set.normals[i] = len > 0 ? normal / len : normal;
      }
    }
  });
  return set;
}

Status ExportSvo(const Svo& svo, const std::filesystem::path& path, const ExportOptions& options) {
  const std::string ext = LowerExtension(path);
  const auto& known = ExportExtensions();
  if (std::find(known.begin(), known.end(), ext) == known.end()) {
    return Status::BadInput("{}: unknown export format (use .vdb, .binvox, .vox, .ply or .xyz)",
                            path.string());
  }
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    return Status::BadInput("{}: is a directory, not a file", path.string());
  }
  const std::uint32_t level = options.level.value_or(svo.depth);
  if (level > svo.depth) {
    return Status::BadInput("{}: level {} does not exist (the octree has levels 0 to {})",
                            path.string(), level, svo.depth);
  }
  if (level >= svo.levels.size()) {
    return Status::BadInput("{}: level {} was not loaded", path.string(), level);
  }
  const VoxelSet voxels = LevelVoxels(svo, level);
  if (ext == "vdb") return WriteVoxelsVdb(voxels, path);
  if (ext == "binvox") return WriteVoxelsBinvox(voxels, path);
  if (ext == "vox") return WriteVoxelsVox(voxels, path);
  if (ext == "ply") return WriteVoxelsPly(voxels, path);
  return WriteVoxelsXyz(voxels, path);
}

}  // namespace svokit
