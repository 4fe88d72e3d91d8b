#include "svokit/export/export.hpp"

#include <algorithm>
#include <array>

#include <fmt/format.h>

#include "svokit/core/file_io.hpp"
#include "svokit/core/morton.hpp"
#include "svokit/core/parallel.hpp"
#include "svokit/export/dag_files.hpp"
#include "svokit/export/level_attributes.hpp"
#include "svokit/export/voxel_writers.hpp"

namespace svokit {

const std::vector<std::string>& ExportExtensions() {
  static const std::vector<std::string> kExtensions = {
      "vdb", "nvdb", "binvox", "vox", "ply", "xyz", "obj", "glb", "svdag", "ssvdag", "dag.bin"};
  return kExtensions;
}

VoxelSet LevelVoxels(const Svo& svo, std::uint32_t level, std::vector<float>* density) {
  VoxelSet set;
  set.grid = LevelGrid(svo.grid, svo.depth, level);
  set.mode = svo.mode;
  const std::vector<std::uint64_t> keys = svo.LevelKeys(level);
  set.keys.assign(keys.begin(), keys.end());
  FillNodeAttributes(svo.levels[level], svo.brick_side, svo.has_color, svo.has_normal, set,
                     density);
  return set;
}

InteriorCubes LevelInterior(const Svo& svo, std::uint32_t level) {
  InteriorCubes interior;
  interior.depth = level;
  interior.levels.resize(level + 1);
  if (!svo.solid) return interior;
  // Full leaves of levels ≤ `level` are its cubes; deeper ones lie inside nodes of `level`.
  for (std::uint32_t l = 0; l < level; ++l) {
    const std::vector<std::uint64_t> keys = svo.LevelKeys(l);
    for (std::size_t i = 0; i < keys.size(); ++i) {
      const std::uint8_t full = svo.levels[l].nodes[i].full_mask;
      for (unsigned c = 0; c < 8; ++c) {
        if (full >> c & 1u) interior.levels[l + 1].push_back(keys[i] << 3 | c);
      }
    }
  }
  return interior;
}

namespace {

// The voxels with the interior's as voxels of their own, in the surface's mean colour (white
// without colours): for formats that list every voxel.
StatusOr<VoxelSet> WithInteriorVoxels(VoxelSet voxels, const InteriorCubes& interior,
                                      const std::filesystem::path& path) {
  constexpr std::uint64_t kMostVoxels = std::uint64_t{1} << 28;
  if (interior.voxel_count() + voxels.size() > kMostVoxels) {
    return Status::BadInput(
        "{}: {} voxels with the interior are too many to list one by one; "
        "export a coarser --level or a .vdb",
        path.string(), interior.voxel_count() + voxels.size());
  }
  std::vector<std::uint64_t> inside;
  inside.reserve(interior.voxel_count());
  for (std::uint32_t l = 0; l < interior.levels.size(); ++l) {
    const std::uint64_t count = std::uint64_t{1} << (3 * (interior.depth - l));
    for (const std::uint64_t key : interior.levels[l]) {
      for (std::uint64_t v = 0; v < count; ++v) inside.push_back(key * count + v);
    }
  }
  std::sort(inside.begin(), inside.end());
  VoxelSet all;
  all.grid = voxels.grid;
  all.mode = voxels.mode;
  all.keys.resize(voxels.size() + inside.size());
  std::merge(voxels.keys.begin(), voxels.keys.end(), inside.begin(), inside.end(),
             all.keys.begin());
  if (voxels.has_colors()) {
    Rgba mean{0, 0, 0, 0};
    for (std::size_t i = 0; i < voxels.size(); ++i) {
      const Rgba c = voxels.color(i);
      mean = {mean.r + c.r, mean.g + c.g, mean.b + c.b, mean.a + c.a};
    }
    const float n = static_cast<float>(std::max<std::size_t>(voxels.size(), 1));
    const HalfRgba interior_color(mean.r / n, mean.g / n, mean.b / n, mean.a / n);
    all.colors.resize(all.keys.size());
    std::size_t i = 0;
    for (std::size_t k = 0; k < all.keys.size(); ++k) {
      const bool surface = i < voxels.size() && voxels.keys[i] == all.keys[k];
      all.colors[k] = surface ? voxels.color(i++) : interior_color;
    }
  }
  return all;
}

}  // namespace

namespace {

// The format `path` names, if it is one, and not a directory.
StatusOr<std::string> CheckExport(const std::filesystem::path& path) {
  const std::string ext =
      IsDagPath(path) && LowerExtension(path) == "bin" ? "dag.bin" : LowerExtension(path);
  const auto& known = ExportExtensions();
  if (std::find(known.begin(), known.end(), ext) == known.end()) {
    return Status::BadInput(
        "{}: unknown export format (use .vdb, .nvdb, .binvox, .vox, .ply, .xyz, .obj, .glb, "
        ".dag.bin, .svdag or .ssvdag)",
        path.string());
  }
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    return Status::BadInput("{}: is a directory, not a file", path.string());
  }
  return ext;
}

}  // namespace

Status ExportSvo(const Svo& svo, const std::filesystem::path& path, const ExportOptions& options) {
  const std::uint32_t level = options.level.value_or(svo.depth);
  StatusOr<std::string> ext = CheckExport(path);
  if (!ext.ok()) return ext.status();
  if (level > svo.depth) {
    return Status::BadInput("{}: level {} does not exist (the octree has levels 0 to {})",
                            path.string(), level, svo.depth);
  }
  if (level >= svo.levels.size()) {
    return Status::BadInput("{}: level {} was not loaded", path.string(), level);
  }
  if (IsDagPath(path)) {
    return Status::BadInput("{}: a DAG is written from a .svo file (ExportSvoPages, svo-export)",
                            path.string());
  }
  const bool grids = *ext == "vdb" || *ext == "nvdb";
  std::vector<float> density;
  VoxelSet voxels = LevelVoxels(svo, level, grids ? &density : nullptr);
  const InteriorCubes interior = LevelInterior(svo, level);
  const InteriorCubes* solid = svo.solid ? &interior : nullptr;
  std::vector<std::uint8_t> ao =
      grids && svo.has_ao ? svo.levels[level].ao : std::vector<std::uint8_t>{};
  if (*ext == "vdb") {
    VoxelFileHeader header = HeaderOf(voxels);
    header.density = true;
    header.ao = svo.has_ao;
    return WriteWhole(OpenVdbWriter(header, solid, path), voxels, {density, ao});
  }
  if (*ext == "nvdb") {
    if (solid != nullptr) {
      // Interior voxels are dense and, seen from outside, fully occluded.
      StatusOr<VoxelSet> all = WithInteriorVoxels(voxels, interior, path);
      if (!all.ok()) return all.status();
      std::vector<float> all_density(all->size(), 1.f);
      std::vector<std::uint8_t> all_ao(ao.empty() ? 0 : all->size(), 255);
      for (std::size_t i = 0, k = 0; i < voxels.size(); ++i, ++k) {
        while (all->keys[k] != voxels.keys[i]) ++k;
        all_density[k] = density[i];
        if (!ao.empty()) all_ao[k] = ao[i];
      }
      voxels = std::move(*all);
      density = std::move(all_density);
      ao = std::move(all_ao);
    }
    VoxelFileHeader header = HeaderOf(voxels);
    header.density = true;
    header.ao = !ao.empty();
    return WriteWhole(OpenNanoVdbWriter(header, path), voxels, {density, ao});
  }
  if (*ext == "obj" || *ext == "glb") {
    // A solid's interior voxels are meshed with the surface's, so only its outside has faces.
    if (solid != nullptr) {
      StatusOr<VoxelSet> all = WithInteriorVoxels(std::move(voxels), interior, path);
      if (!all.ok()) return all.status();
      voxels = std::move(*all);
    }
    return WriteVoxelMesh(voxels, options.merge_faces, path).status();
  }
  if (*ext == "binvox") return WriteVoxelsBinvox(voxels, solid, path);
  if (*ext == "vox") {
    if (solid == nullptr) return WriteVoxelsVox(voxels, path);
    StatusOr<VoxelSet> all = WithInteriorVoxels(std::move(voxels), interior, path);
    return all.ok() ? WriteVoxelsVox(*all, path) : all.status();
  }
  if (*ext == "ply") return WriteVoxelsPly(voxels, path);
  return WriteVoxelsXyz(voxels, path);
}

bool ExportStreams(const SvoReader& reader, const std::filesystem::path& path) {
  return IsDagPath(path) || (!reader.shape().solid && LowerExtension(path) != "vox");
}

Status CheckWholeExport(const SvoReader& reader, const std::filesystem::path& path,
                        std::uint64_t memory_limit) {
  if (memory_limit == 0 || ExportStreams(reader, path)) return Status::Ok();
  std::uint64_t bytes = 0;
  for (std::size_t i = 0; i < reader.page_count(); ++i) {
    StatusOr<std::uint64_t> page = PageDecodedBytes(reader, i);
    if (!page.ok()) return page.status();
    bytes += *page;
  }
  if (bytes <= memory_limit) return Status::Ok();
  const std::uint64_t mib = (bytes + (1 << 20) - 1) >> 20;
  return Status::BadInput(
      "{}: {} reads the octree whole: its pages alone need {} MiB, over the memory limit of {} "
      "MiB (give {}M or more)",
      path.string(), reader.shape().solid ? "a solid's export" : "a .vox export", mib,
      memory_limit >> 20, mib);
}

namespace {

// What an export holding `needs` bytes says when they pass `memory_limit` (0: none), before
// reading.
Status CheckHeld(const std::filesystem::path& path, const std::string& what, std::uint64_t needs,
                 std::uint64_t memory_limit) {
  if (memory_limit == 0 || needs <= memory_limit) return Status::Ok();
  const std::uint64_t mib = (needs + (1 << 20) - 1) >> 20;
  return Status::BadInput(
      "{}: {} need {} MiB, over the memory limit of {} MiB (give {}M or more, or export a coarser "
      "--level)",
      path.string(), what, mib, memory_limit >> 20, mib);
}

// A .nvdb's grids are built whole (OpenNanoVdbWriter): what they need, from HEAD alone, against
// the limit before a page is read.
Status CheckNanoVdbFits(const SvoReader& reader, const VoxelFileHeader& header,
                        const std::filesystem::path& path, std::uint32_t level,
                        std::uint64_t memory_limit) {
  auto nodes_above = [&](std::uint32_t up) {
    return level < up ? 1 : reader.NodeCount(level - up);
  };
  const std::uint64_t needs =
      NanoVdbBytes({nodes_above(3), nodes_above(7), nodes_above(12)}, header.colors, header.ao) +
      (header.ao ? reader.NodeCount(level) : 0);
  return CheckHeld(path, fmt::format("a .nvdb is built whole: level {}'s grids", level), needs,
                   memory_limit);
}

// Per page (in key order), the index of its first node of `level` in the level (the last entry:
// the level's count): from the page table at the voxel level, else from the pages' masks.
StatusOr<std::vector<std::uint64_t>> PageFirstNodes(const SvoReader& reader, std::uint32_t level) {
  std::vector<std::uint64_t> first(reader.page_count() + 1, 0);
  for (std::size_t i = 0; i < reader.page_count(); ++i) {
    std::uint64_t nodes = reader.page(i).voxels;
    if (level < reader.depth()) {
      StatusOr<SvoChunk> page = reader.Page(i, ChunkParts::kCounts);
      if (!page.ok()) return page.status();
      nodes = page->tree.NodeCount(level);
    }
    first[i + 1] = first[i] + nodes;
  }
  return first;
}

// A voxel mesh of a file read page by page: the level's nodes (key and colour, 16 bytes each) are
// gathered, since a face needs its neighbours across pages, and checked against the limit first.
Status ExportVoxelMeshPages(const SvoReader& reader, const VoxelFileHeader& header,
                            const std::filesystem::path& path, std::uint32_t level, bool merge,
                            std::uint64_t memory_limit, Progress::Stage* stage) {
  const std::uint64_t nodes = reader.NodeCount(level);
  const std::uint64_t needs = nodes * (sizeof(std::uint64_t) + sizeof(HalfRgba));
  SVOKIT_RETURN_IF_ERROR(CheckHeld(
      path, fmt::format("a voxel mesh's {} nodes of level {}", nodes, level), needs, memory_limit));
  VoxelSet all;
  all.grid = header.grid;
  all.mode = reader.mode();
  all.keys.reserve(nodes);
  if (header.colors) all.colors.reserve(nodes);
  const std::uint32_t side = reader.shape().brick_side;
  SVOKIT_RETURN_IF_ERROR(ForEachLevelPage(
      reader, level, header.colors, SvoStreamOptions{.memory_limit = memory_limit},
      [&](std::size_t, SvoChunkLevel& page) {
        VoxelSet part;
        part.grid = header.grid;
        part.keys.assign(page.keys.begin(), page.keys.end());
        FillNodeAttributes(page.bricks, side, header.colors, false, part);
        all.keys.insert(all.keys.end(), part.keys.begin(), part.keys.end());
        all.colors.insert(all.colors.end(), part.colors.begin(), part.colors.end());
        return Status::Ok();
      },
      stage));
  return WriteVoxelMesh(all, merge, path).status();
}

}  // namespace

Status ExportSvoPages(const SvoReader& reader, const std::filesystem::path& path,
                      const ExportOptions& options, std::uint64_t memory_limit,
                      Progress::Stage* stage) {
  const SvoShape& shape = reader.shape();
  const std::uint32_t level = options.level.value_or(reader.depth());
  if (level > reader.depth()) {  // worded as the readers word it
    return Status::BadInput("{}: level {} exceeds the octree's depth {}", reader.name(), level,
                            reader.depth());
  }
  StatusOr<std::string> ext = CheckExport(path);
  if (!ext.ok()) return ext.status();
  if (IsDagPath(path)) return ExportDag(reader, path, {level, memory_limit}).status();
  if (!ExportStreams(reader, path)) {
    return Status::BadInput("{}: a .vox or a solid's export takes the octree whole", path.string());
  }
  const bool colors = shape.brick_side != 0 && shape.has_color;
  const bool normals = shape.brick_side != 0 && shape.has_normal;
  VoxelFileHeader header{LevelGrid(reader.grid(), reader.depth(), level), colors, normals,
                         reader.NodeCount(level)};
  header.density = *ext == "vdb" || *ext == "nvdb";
  header.ao = header.density && reader.has_ao();
  if (*ext == "nvdb") {
    SVOKIT_RETURN_IF_ERROR(CheckNanoVdbFits(reader, header, path, level, memory_limit));
  }
  if (*ext == "obj" || *ext == "glb") {
    return ExportVoxelMeshPages(reader, header, path, level, options.merge_faces, memory_limit,
                                stage);
  }
  // AO by node index in the level, each page's nodes from its first on (pages may come in any
  // order, a .vdb's).
  std::vector<std::uint8_t> level_ao;
  std::vector<std::uint64_t> first_node;
  if (header.ao) {
    StatusOr<std::vector<std::uint8_t>> ao = reader.LevelAo(level);
    if (!ao.ok()) return ao.status();
    level_ao = std::move(*ao);
    if (level >= reader.page_level()) {
      StatusOr<std::vector<std::uint64_t>> first = PageFirstNodes(reader, level);
      if (!first.ok()) return first.status();
      first_node = std::move(*first);
    }
  }
  StatusOr<std::unique_ptr<VoxelFileWriter>> writer =
      *ext == "vdb"      ? OpenVdbWriter(header, nullptr, path)
      : *ext == "nvdb"   ? OpenNanoVdbWriter(header, path)
      : *ext == "binvox" ? OpenBinvoxWriter(header, nullptr, path)
      : *ext == "ply"    ? OpenPlyWriter(header, path)
                         : OpenXyzWriter(header, path);
  if (!writer.ok()) return writer.status();
  // binvox runs along x: pages go by slabs of page cubes along x, each slab written out once in.
  SvoStreamOptions stream{.memory_limit = memory_limit};
  const bool by_slabs = *ext == "binvox";
  if (by_slabs) stream.order = SvoPageOrder::kSlabsAlongX;
  // A .vdb stores its nodes 4096³ cube by cube, 128³ cube by cube: pages come in that order.
  if (*ext == "vdb")
    stream = {.memory_limit = memory_limit, .order = SvoPageOrder::kVdbTree, .level = level};
  const std::uint64_t page_side =
      level < reader.page_level() ? 0 : std::uint64_t{1} << (level - reader.page_level());
  std::vector<std::uint64_t> x_done(reader.page_count(), 0);
  if (by_slabs) {
    const std::vector<std::size_t> order = PageOrder(reader, SvoPageOrder::kSlabsAlongX);
    for (std::size_t k = 0; k < order.size(); ++k) {
      const std::uint64_t x = MortonDecode(reader.page(order[k]).key).x;
      const bool last = k + 1 == order.size() || MortonDecode(reader.page(order[k + 1]).key).x != x;
      x_done[order[k]] = last ? (x + 1) * page_side : x * page_side;
    }
  }
  SVOKIT_RETURN_IF_ERROR(ForEachLevelPage(
      reader, level, shape.brick_side != 0 && (colors || normals || header.density), stream,
      [&](std::size_t page, SvoChunkLevel& nodes) {
        VoxelSet part;
        part.grid = header.grid;
        part.mode = reader.mode();
        part.keys.assign(nodes.keys.begin(), nodes.keys.end());
        std::vector<float> density;
        FillNodeAttributes(nodes.bricks, shape.brick_side, colors, normals, part,
                           header.density ? &density : nullptr);
        VoxelValues values{density, {}};
        if (header.ao) {
          const std::uint64_t first = page < first_node.size() ? first_node[page] : 0;
          values.ao = std::span<const std::uint8_t>(level_ao).subspan(first, part.size());
        }
        return (*writer)->Add(part, values,
                              page < x_done.size() ? x_done[page] : ~std::uint64_t{0});
      },
      stage));
  return (*writer)->Finish();
}

}  // namespace svokit
