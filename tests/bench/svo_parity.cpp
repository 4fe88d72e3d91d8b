// The paged file against the per-node reference at full scale (scripts/bench parity). The
// reference is BuildReferenceSvo, the octree a version-1 file stores node by node, by today's
// brick filter; the file of the same voxels is written, then read back through SvoReader one page
// at a time, as a renderer reads it:
// every level's keys, child masks, contour words and assembled bricks, and the voxels' own colours
// and normals, must equal the reference byte for byte. Then the time to read each file whole and
// assemble every brick (ReadSvo), medians of 3, where the version-1 file is written (--v1-limit,
// default 4 GB).
//
//   svo_parity --resolution N MESH... [--v1-limit BYTES]
// Prints one row per mesh; exits 1 when anything differs.

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include <unistd.h>

#include <fmt/format.h>

#include "bench_main.hpp"
#include "svokit/core/file_io.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/formats/svo/svo_reader.hpp"
#include "svokit/svo/build_options.hpp"
#include "svokit/svo/compact_build.hpp"
#include "svokit/svo/compact_svo.hpp"
#include "svokit/svo/reference_build.hpp"
#include "svokit/validate/checks.hpp"
#include "svokit/voxelize/voxelize.hpp"
#include "tests/formats/svo_v1_writer.hpp"

namespace {

using namespace svokit;

double Seconds(const std::chrono::steady_clock::time_point& t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Median of three whole-file reads.
template <class Read>
double MedianRead(const Read& read) {
  std::vector<double> t;
  for (int i = 0; i < 3; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    read();
    t.push_back(Seconds(t0));
  }
  std::sort(t.begin(), t.end());
  return t[1];
}

// Counts what differs between the reference and the file, level by level, page by page.
struct Comparison {
  std::uint64_t nodes = 0, samples = 0, contours = 0, voxel_attributes = 0;
  std::vector<std::string> differences;

  void Differ(std::string what) {
    if (differences.size() < 10) differences.push_back(std::move(what));
  }
};

// One chunk level (its nodes are reference nodes offset .. offset + n of that level) against
// the reference.
void CompareLevel(const Svo& ref, const std::vector<std::uint64_t>& ref_keys,
                  const std::vector<std::uint32_t>& ref_contours, const SvoChunkLevel& got,
                  std::uint64_t offset, Comparison& c) {
  const SvoLevel& lv = ref.levels[got.level];
  const std::size_t n = got.keys.size();
  const std::size_t samples = ref.brick_samples();
  if (offset + n > lv.node_count) {
    c.Differ(fmt::format("level {}: more nodes than the reference", got.level));
    return;
  }
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t r = offset + i;
    if (got.keys[i] != ref_keys[r]) {
      c.Differ(fmt::format("level {} node {}: key differs", got.level, r));
      return;
    }
    if (got.level < ref.depth && got.masks[i] != lv.nodes[r].child_mask) {
      c.Differ(fmt::format("level {} node {}: child mask differs", got.level, r));
    }
    if (ref.has_contours && got.contours[i] != ref_contours[r]) {
      c.Differ(fmt::format("level {} node {}: contour word differs", got.level, r));
    }
  }
  const auto same = [&](const auto& a, const auto& b) {
    return std::equal(a.begin(), a.end(), b.begin() + static_cast<std::ptrdiff_t>(offset * samples),
                      b.begin() + static_cast<std::ptrdiff_t>((offset + n) * samples));
  };
  if (samples != 0 && (!same(got.bricks.opacity, lv.opacity) ||
                       (ref.has_color && !same(got.bricks.color, lv.color)) ||
                       (ref.has_normal && !same(got.bricks.normal, lv.normal)))) {
    c.Differ(fmt::format("level {} nodes {}..{}: bricks differ", got.level, offset, offset + n));
  }
  c.nodes += n;
  c.samples += n * samples;
  for (std::size_t i = 0; i < n; ++i) c.contours += got.contours.empty() ? 0 : got.contours[i] != 0;
}

Comparison CompareThroughReader(const Svo& ref, const VoxelSet& voxels, const SvoReader& reader) {
  Comparison c;
  std::vector<std::vector<std::uint64_t>> keys(ref.depth + 1);
  for (std::uint32_t l = 0; l <= ref.depth; ++l) keys[l] = ref.LevelKeys(l);
  const std::vector<std::vector<std::uint32_t>> contours = validate::NodeContours(ref);
  std::vector<std::uint64_t> offset(ref.depth + 1, 0);
  const auto compare_chunk = [&](const SvoChunk& chunk, std::uint32_t first, std::uint32_t last) {
    for (std::uint32_t l = first; l < last; ++l) {
      const SvoChunkLevel level = AssembleChunkLevel(chunk, reader.shape(), l);
      CompareLevel(ref, keys[l], contours[l], level, offset[l], c);
      offset[l] += level.keys.size();
    }
  };
  auto top = reader.Top();
  if (!top.ok()) {
    c.Differ(top.status().message());
    return c;
  }
  compare_chunk(*top, 0, reader.page_level());
  for (std::size_t p = 0; p < reader.page_count(); ++p) {
    auto page = reader.Page(p);
    if (!page.ok()) {
      c.Differ(page.status().message());
      return c;
    }
    const std::uint64_t first_voxel = offset[ref.depth];
    compare_chunk(*page, reader.page_level(), ref.depth + 1);
    // The voxels' own attributes, which the voxel level's bricks are filtered from.
    for (std::size_t i = 0; i < page->colors.size(); ++i) {
      if (!(page->colors[i] == voxels.color(first_voxel + i))) {
        c.Differ(fmt::format("voxel {}: colour differs", first_voxel + i));
        break;
      }
    }
    for (std::size_t i = 0; i < page->normals.size(); ++i) {
      if (page->normals[i].bits != voxels.normals[first_voxel + i].bits) {
        c.Differ(fmt::format("voxel {}: normal differs", first_voxel + i));
        break;
      }
    }
    c.voxel_attributes += page->colors.size() + page->normals.size();
  }
  for (std::uint32_t l = 0; l <= ref.depth; ++l) {
    if (offset[l] != ref.levels[l].node_count) {
      c.Differ(fmt::format("level {}: {} nodes read, the reference has {}", l, offset[l],
                           ref.levels[l].node_count));
    }
  }
  return c;
}

int Run(int argc, char** argv) {
  std::uint32_t resolution = 1024;
  std::uint64_t v1_limit = std::uint64_t{4} << 30;
  std::vector<std::string> files;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--resolution" && i + 1 < argc) {
      resolution = static_cast<std::uint32_t>(std::stoul(argv[++i]));
    } else if (a == "--v1-limit" && i + 1 < argc) {
      v1_limit = std::stoull(argv[++i]);
    } else {
      files.push_back(a);
    }
  }
  const std::filesystem::path tmp = std::filesystem::temp_directory_path() /
                                    fmt::format("svo_parity.{}", static_cast<long>(getpid()));
  std::filesystem::create_directories(tmp);
  fmt::print(
      "# every level's keys, masks, contour words and bricks, and the voxels' attributes, "
      "through SvoReader page by page,\n# against BuildReferenceSvo (what version 1 stores); "
      "read_s: ReadSvo of the whole file, bricks assembled (median of 3; 1024 only)\n");
  fmt::print("{:<10} {:>5} {:>10} {:>11} {:>13} {:>9} {:>11} {:>12} {:>12} {:>9} {:>9}\n", "mesh",
             "N", "voxels", "nodes", "samples", "contours", "differences", "v2_bytes", "v1_bytes",
             "v2_read_s", "v1_read_s");
  bool all_same = true;
  for (const std::string& f : files) {
    auto scene = bench::LoadScene(f, resolution);
    if (!scene.ok()) {
      fmt::print(stderr, "svo_parity: {}\n", scene.status().message());
      return 2;
    }
    VoxelizeOptions vo;
    vo.colors = vo.normals = true;
    auto voxels = Voxelize(scene->mesh, scene->grid, vo);
    if (!voxels.ok()) {
      fmt::print(stderr, "svo_parity: {}\n", voxels.status().message());
      return 2;
    }
    const BuildOptions options;  // 3³ bricks, contours: the full product
    auto compact = BuildCompactSvo(*voxels, &scene->mesh, options);
    if (!compact.ok()) return 2;
    const std::filesystem::path v2 = tmp / "v2.svo", v1 = tmp / "v1.svo";
    if (!WriteSvo(*compact, v2).ok()) return 2;
    compact = CompactSvo{};
    auto ref = BuildReferenceSvo(*voxels, &scene->mesh, options);
    if (!ref.ok()) return 2;
    auto reader = SvoReader::Open(v2);
    if (!reader.ok()) {
      fmt::print(stderr, "svo_parity: {}\n", reader.status().message());
      return 2;
    }
    const Comparison c = CompareThroughReader(*ref, *voxels, *reader);
    for (const std::string& d : c.differences) fmt::print(stderr, "{}: {}\n", scene->name, d);
    all_same = all_same && c.differences.empty();
    std::uint64_t v1_bytes = 0;
    for (const SvoLevel& lv : ref->levels) {
      v1_bytes +=
          lv.nodes.size() * sizeof(SvoNode) + lv.opacity.size() * 7 + lv.contours.size() * 4;
    }
    // Read times where the version-1 file is written (two whole octrees in memory at once
    // otherwise exceed the machine at 4096³); the reference is freed first.
    double v1_read = 0, v2_read = 0;
    if (v1_bytes <= v1_limit) {
      {
        const std::vector<std::uint8_t> bytes = test::EncodeSvoV1(*ref);
        if (!WriteFileAtomic(v1, bytes).ok()) return 2;
        v1_bytes = bytes.size();
      }
      ref = Svo{};
      v1_read = MedianRead([&] { (void)ReadSvo(v1); });
      v2_read = MedianRead([&] { (void)ReadSvo(v2); });
    }
    const auto seconds = [](double t) {
      return t > 0 ? fmt::format("{:.2f}", t) : std::string("-");
    };
    fmt::print("{:<10} {:>5} {:>10} {:>11} {:>13} {:>9} {:>11} {:>12} {:>12} {:>9} {:>9}\n",
               scene->name, resolution, voxels->size(), c.nodes, c.samples, c.contours,
               c.differences.size(), std::filesystem::file_size(v2), v1_bytes, seconds(v2_read),
               seconds(v1_read));
    std::filesystem::remove(v1);
    std::filesystem::remove(v2);
  }
  std::filesystem::remove_all(tmp);
  return all_same ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  return Run(argc, argv);
}
