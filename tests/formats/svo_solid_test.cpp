// Solids in .svo (`--fill solid`): the interior's cubes are full leaves (SvoNode::full_mask, chunk
// stream 14, HEAD flag 16). A solid's file reads back as exactly FillInterior's cubes, on closed
// meshes (exact crossings) and open ones (winding numbers, whose split cubes are nodes with no
// children but full leaves); surface files carry neither the flag nor the stream; a build by
// pages writes the whole build's bytes, with full leaves in the top chunk; and a file whose full
// leaves contradict its tree is refused with one line naming it.

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cstring>
#include <set>

#include "svokit/core/crc32c.hpp"
#include "svokit/core/key_gaps.hpp"
#include "svokit/core/morton.hpp"
#include "svokit/core/thread_limit.hpp"
#include "svokit/formats/container/container.hpp"
#include "svokit/formats/mesh_import.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/formats/svo/svo_reader.hpp"
#include "svokit/pipeline/svo_by_pages.hpp"
#include "svokit/pipeline/svo_parts.hpp"
#include "svokit/svo/build_options.hpp"
#include "svokit/svo/compact_build.hpp"
#include "svokit/svo/compact_svo.hpp"
#include "svokit/voxelize/solid_fill.hpp"
#include "svokit/voxelize/voxelize.hpp"
#include "tests/test_meshes.hpp"
#include "tests/test_util.hpp"

namespace svokit {
namespace {

constexpr std::uint32_t kSolidFlag = 16;    // HEAD flag of a solid (formats/svo/svo_detail.hpp)
constexpr std::uint8_t kFullMaskKind = 14;  // chunk stream of the full-leaf masks

std::filesystem::path Spider() {
  return test::AssimpModels() / "OBJ" / "spider.obj";
}

// A surface's voxels, the interior FillInterior finds around them, and the solid's octree.
struct Solid {
  Mesh mesh;
  VoxelSet voxels;  ///< the surface's (kept: the octree is built from a copy)
  InteriorCubes interior;
  CompactSvo svo;
};

Solid MakeSolid(Mesh mesh, std::uint32_t resolution, std::uint32_t side = 3, bool contours = false,
                bool attributes = true) {
  Solid s;
  s.mesh = std::move(mesh);
  auto grid = GridTransform::FitResolution(s.mesh.Bounds(), resolution);
  EXPECT_TRUE(grid.ok());
  VoxelizeOptions vo;
  vo.colors = vo.normals = attributes;
  auto voxels = Voxelize(s.mesh, *grid, vo);
  EXPECT_TRUE(voxels.ok()) << voxels.status().message();
  s.voxels = std::move(*voxels);
  auto interior = FillInterior(s.mesh, *grid, s.voxels.keys);
  EXPECT_TRUE(interior.ok()) << interior.status().message();
  s.interior = std::move(*interior);
  BuildOptions bo;
  bo.brick_side = side;
  bo.contours = contours;
  bo.interior = &s.interior;
  auto svo = BuildCompactSvo(s.voxels, &s.mesh, bo, R"({"source":"solid test"})");
  EXPECT_TRUE(svo.ok()) << svo.status().message();
  if (svo.ok()) s.svo = std::move(*svo);
  return s;
}

Mesh Imported(const std::filesystem::path& path) {
  auto mesh = ImportMesh(path);
  EXPECT_TRUE(mesh.ok()) << mesh.status().message();
  return mesh.ok() ? std::move(*mesh) : Mesh{};
}

// The icosphere with the triangles around a few vertices removed: open, so its interior is
// decided by winding numbers.
Mesh HoledIcosphere() {
  Mesh m = test::Icosphere(4, false);
  std::vector<Triangle> kept;
  for (const Triangle& t : m.triangles) {
    if (t[0] % 97 == 5 || t[1] % 97 == 5 || t[2] % 97 == 5) continue;
    kept.push_back(t);
  }
  m.triangles = std::move(kept);
  m.material_ids.clear();
  EnsureDefaultMaterial(m);
  return m;
}

// The full leaves of a decoded octree as cubes: per level L, the keys of the cubes of that level
// (children of level L − 1's nodes), in the order the walk of LevelKeys gives (ascending).
std::vector<std::vector<std::uint64_t>> FullLeaves(const Svo& svo) {
  std::vector<std::vector<std::uint64_t>> cubes(svo.depth + 1);
  for (std::uint32_t l = 0; l < svo.depth; ++l) {
    const std::vector<std::uint64_t> keys = svo.LevelKeys(l);
    EXPECT_EQ(keys.size(), svo.levels[l].nodes.size()) << l;
    for (std::size_t i = 0; i < keys.size() && i < svo.levels[l].nodes.size(); ++i) {
      const std::uint8_t full = svo.levels[l].nodes[i].full_mask;
      for (unsigned c = 0; c < 8; ++c) {
        if (full >> c & 1u) cubes[l + 1].push_back(keys[i] << 3 | c);
      }
    }
  }
  return cubes;
}

// HEAD's flags of a version-2 file.
std::uint32_t HeadFlags(const std::vector<std::uint8_t>& bytes) {
  auto file = container::Reader::FromBytes(bytes, "t.svo", kSvoFormat);
  EXPECT_TRUE(file.ok()) << file.status().message();
  if (!file.ok()) return 0;
  const auto head = file->Find(container::MakeTag("HEAD"));
  EXPECT_TRUE(head && head->size() >= 12);
  std::uint32_t flags = 0;
  std::memcpy(&flags, head->data() + 8, 4);
  return flags;
}

// The stream kinds of each chunk of a version-2 file, read from the stream directories: the top
// chunk (if any) first, then the pages in page-table order.
std::vector<std::set<std::uint8_t>> ChunkStreamKinds(const std::vector<std::uint8_t>& bytes) {
  std::vector<std::set<std::uint8_t>> kinds;
  auto file = container::Reader::FromBytes(bytes, "t.svo", kSvoFormat);
  EXPECT_TRUE(file.ok()) << file.status().message();
  if (!file.ok()) return kinds;
  const auto directory = [&](std::span<const std::uint8_t> chunk) {
    std::set<std::uint8_t> k;
    const std::uint8_t* p = chunk.data();
    const std::uint8_t* end = p + chunk.size();
    EXPECT_FALSE(chunk.empty());
    if (chunk.empty()) return k;
    const std::uint8_t count = *p++;
    for (std::uint8_t i = 0; i < count; ++i) {
      EXPECT_LE(p + 2, end);
      k.insert(p[0]);
      p += 2;  // kind, codec
      std::uint64_t decoded = 0, stored = 0;
      EXPECT_TRUE(GetVarint(p, end, decoded) && GetVarint(p, end, stored));
    }
    return k;
  };
  if (const auto top = file->Find(container::MakeTag("TOPL"))) kinds.push_back(directory(*top));
  const auto pages = file->Find(container::MakeTag("PAGE"));
  const auto table = file->Find(container::MakeTag("PTAB"));
  EXPECT_TRUE(pages && table);
  if (!pages || !table) return kinds;
  for (std::size_t e = 0; e + 32 <= table->size(); e += 32) {
    std::uint64_t offset = 0;
    std::uint32_t size = 0;
    std::memcpy(&offset, table->data() + e + 8, 8);
    std::memcpy(&size, table->data() + e + 16, 4);
    kinds.push_back(directory(pages->subspan(offset, size)));
  }
  return kinds;
}

// `bytes` with HEAD's flags replaced and every checksum made right again (HEAD's and the
// header's): what another writer's bug would produce, which only the structure checks can catch.
std::vector<std::uint8_t> WithHeadFlags(std::vector<std::uint8_t> bytes, std::uint32_t flags) {
  auto frame = container::Frame::FromBytes(bytes, "t.svo", kSvoFormat);
  EXPECT_TRUE(frame.ok());
  if (!frame.ok()) return bytes;
  for (std::size_t e = 0; e < frame->sections().size(); ++e) {
    const container::Frame::Section& s = frame->sections()[e];
    if (s.tag != container::MakeTag("HEAD")) continue;
    std::memcpy(bytes.data() + s.offset + 8, &flags, 4);
    const std::uint32_t crc = Crc32c(bytes.data() + s.offset, s.size);
    std::memcpy(bytes.data() + container::kHeaderSize + e * container::kSectionEntrySize + 24, &crc,
                4);
  }
  std::uint32_t head = Crc32c(bytes.data(), 28);
  head = Crc32c(bytes.data() + container::kHeaderSize,
                frame->sections().size() * container::kSectionEntrySize, head);
  std::memcpy(bytes.data() + 28, &head, 4);
  return bytes;
}

// Every invariant of a solid's decoded octree against the interior it was built from.
void ExpectSolidOctree(const Svo& svo, const Solid& s) {
  ASSERT_TRUE(svo.solid);
  ASSERT_EQ(svo.levels.size(), svo.depth + 1);
  // Exactly FillInterior's cubes, level by level, and nothing at level 0 (the root is a node).
  const std::vector<std::vector<std::uint64_t>> cubes = FullLeaves(svo);
  ASSERT_EQ(s.interior.levels.size(), cubes.size());
  for (std::size_t l = 0; l < cubes.size(); ++l) {
    EXPECT_EQ(cubes[l], s.interior.levels[l]) << "full leaves of level " << l;
  }
  EXPECT_EQ(svo.InteriorVoxelCount(), s.interior.voxel_count());
  EXPECT_GT(svo.InteriorVoxelCount(), 0u);
  // The surface's voxels are the voxel level, unchanged.
  EXPECT_EQ(svo.LevelKeys(svo.depth),
            std::vector<std::uint64_t>(s.voxels.keys.begin(), s.voxels.keys.end()));
  // Masks: full leaves are never children, every node above the voxels has one or the other, and
  // a node without children holds full leaves only (a cube the winding numbers split).
  for (std::uint32_t l = 0; l < svo.depth; ++l) {
    for (std::size_t i = 0; i < svo.levels[l].nodes.size(); ++i) {
      const SvoNode& n = svo.levels[l].nodes[i];
      EXPECT_EQ(n.child_mask & n.full_mask, 0) << "level " << l << " node " << i;
      EXPECT_NE(n.child_mask | n.full_mask, 0) << "level " << l << " node " << i;
    }
  }
}

// The solid's voxels (surface ∪ cubes) in a dense grid: 1 surface, 2 interior; a voxel in both
// fails the test.
std::vector<std::uint8_t> DenseSolid(const Svo& svo) {
  const auto& d = svo.grid.dims();
  std::vector<std::uint8_t> cells(std::size_t{d[0]} * d[1] * d[2], 0);
  const auto at = [&](std::uint64_t x, std::uint64_t y, std::uint64_t z) -> std::uint8_t* {
    if (x >= d[0] || y >= d[1] || z >= d[2]) return nullptr;
    return &cells[(z * d[1] + y) * d[0] + x];
  };
  for (const std::uint64_t key : svo.LevelKeys(svo.depth)) {
    const MortonCoord c = MortonDecode(key);
    std::uint8_t* cell = at(c.x, c.y, c.z);
    EXPECT_NE(cell, nullptr);
    if (cell) *cell = 1;
  }
  const std::vector<std::vector<std::uint64_t>> cubes = FullLeaves(svo);
  std::uint64_t overlaps = 0, outside = 0;
  for (std::uint32_t l = 0; l < cubes.size(); ++l) {
    const std::uint64_t side = std::uint64_t{1} << (svo.depth - l);
    for (const std::uint64_t key : cubes[l]) {
      const MortonCoord c = MortonDecode(key);
      for (std::uint64_t z = c.z * side; z < (c.z + 1) * side; ++z) {
        for (std::uint64_t y = c.y * side; y < (c.y + 1) * side; ++y) {
          for (std::uint64_t x = c.x * side; x < (c.x + 1) * side; ++x) {
            std::uint8_t* cell = at(x, y, z);
            if (cell == nullptr) {
              ++outside;
            } else {
              overlaps += *cell != 0;
              *cell = 2;
            }
          }
        }
      }
    }
  }
  EXPECT_EQ(overlaps, 0u) << "interior voxels that are surface voxels or in two cubes";
  EXPECT_EQ(outside, 0u) << "interior voxels outside the grid";
  return cells;
}

// The unit icosphere's solid, read back from its file, is the ball: every interior voxel's
// centre inside the unit sphere (the polyhedron is inscribed in it), every voxel centre well
// inside the polyhedron (its faces are within 1.2e-3 of the sphere at 4 subdivisions) solid.
void ExpectBall(const Svo& svo) {
  const std::vector<std::uint8_t> cells = DenseSolid(svo);
  const std::int64_t nx = svo.grid.dims()[0], ny = svo.grid.dims()[1], nz = svo.grid.dims()[2];
  std::uint64_t inside_missing = 0, interior_outside = 0;
  for (std::int64_t z = 0; z < nz; ++z) {
    for (std::int64_t y = 0; y < ny; ++y) {
      for (std::int64_t x = 0; x < nx; ++x) {
        const std::uint8_t cell = cells[static_cast<std::size_t>((z * ny + y) * nx + x)];
        const Vec3d p = svo.grid.VoxelCenter({x, y, z});
        const double r = Length(p);
        if (r < 0.995 && cell == 0) ++inside_missing;
        if (r > 1.0 && cell == 2) ++interior_outside;
      }
    }
  }
  EXPECT_EQ(inside_missing, 0u) << "voxel centres inside the ball that are not solid";
  EXPECT_EQ(interior_outside, 0u) << "interior voxels whose centre is outside the ball";
}

// ---------------------------------------------------------------------------------------------

TEST(SvoSolid, FullLeavesReadBackAsTheInteriorCubes) {
  struct Case {
    std::uint32_t resolution, side;
    bool contours;
  };
  for (const Case& c : {Case{64, 3, true}, Case{128, 2, false}, Case{96, 0, false}}) {
    SCOPED_TRACE("icosphere at " + std::to_string(c.resolution) + ", bricks " +
                 std::to_string(c.side));
    const Solid s = MakeSolid(test::Icosphere(4), c.resolution, c.side, c.contours);
    ASSERT_EQ(s.interior.method, FillMethod::kColumns);
    ASSERT_TRUE(s.svo.frame.shape.solid);
    for (const SvoCompression& compression : {SvoCompression{}, SvoCompression{false, 0}}) {
      SvoFileStats stats;
      const std::vector<std::uint8_t> bytes = EncodeSvo(s.svo, compression, &stats);
      EXPECT_EQ(EncodeSvo(s.svo, compression), bytes) << "deterministic";
      auto back = DecodeSvo(bytes, "solid.svo");
      ASSERT_TRUE(back.ok()) << back.status().message();
      ExpectSolidOctree(*back, s);
      EXPECT_TRUE(*back == AssembleSvo(s.svo));
      // Closed: no node was split, the tree is the surface's.
      const auto surface =
          LevelKeysFromVoxels(std::span<const std::uint64_t>(s.voxels.keys), s.svo.depth());
      for (std::uint32_t l = 0; l <= s.svo.depth(); ++l) {
        EXPECT_EQ(back->LevelKeys(l), surface[l]) << l;
      }
      EXPECT_EQ(HeadFlags(bytes) & kSolidFlag, kSolidFlag);
      for (const std::set<std::uint8_t>& kinds : ChunkStreamKinds(bytes)) {
        EXPECT_TRUE(kinds.count(kFullMaskKind)) << "a chunk without full-leaf masks";
      }
      // The stats name the stream: one mask byte per node above the voxels.
      std::uint64_t raw = 0;
      for (const SvoSectionBytes& sec : stats.sections) {
        if (sec.name == "full leaves") raw = sec.raw;
      }
      std::uint64_t nodes = 0;
      for (std::uint32_t l = 0; l < s.svo.depth(); ++l) nodes += s.svo.NodeCount(l);
      EXPECT_EQ(raw, nodes);
      auto lenient = DecodeSvoLenient(bytes, "solid.svo");
      ASSERT_TRUE(lenient.ok());
      EXPECT_TRUE(lenient->complete && lenient->issues.empty());
      EXPECT_TRUE(lenient->svo == *back);
    }
    // Through a file too, and down to any level: the full leaves of the levels read.
    test::TempDir dir;
    ASSERT_TRUE(WriteSvo(s.svo, dir / "s.svo").ok());
    auto read = ReadSvo(dir / "s.svo");
    ASSERT_TRUE(read.ok()) << read.status().message();
    ExpectSolidOctree(*read, s);
    for (std::uint32_t k = 0; k < s.svo.depth(); ++k) {
      auto top = ReadSvo(dir / "s.svo", k);
      ASSERT_TRUE(top.ok()) << k << ": " << top.status().message();
      EXPECT_TRUE(top->solid);
      for (std::uint32_t l = 0; l <= k; ++l) {
        EXPECT_TRUE(top->levels[l] == read->levels[l]) << "level " << l << " of " << k;
      }
    }
    if (c.resolution == 64 || c.resolution == 128) ExpectBall(*read);
  }
}

TEST(SvoSolid, SurfaceFilesCarryNoFullLeaves) {
  Mesh sphere = test::Icosphere(4);
  auto grid = GridTransform::FitResolution(sphere.Bounds(), 64);
  ASSERT_TRUE(grid.ok());
  auto voxels = Voxelize(sphere, *grid, {});
  ASSERT_TRUE(voxels.ok());
  BuildOptions bo;
  bo.contours = false;
  auto svo = BuildCompactSvo(*voxels, &sphere, bo);
  ASSERT_TRUE(svo.ok());
  EXPECT_FALSE(svo->frame.shape.solid);
  EXPECT_TRUE(svo->whole.tree.full.empty());
  SvoFileStats stats;
  const std::vector<std::uint8_t> bytes = EncodeSvo(*svo, {}, &stats);
  EXPECT_EQ(HeadFlags(bytes) & kSolidFlag, 0u);
  for (const std::set<std::uint8_t>& kinds : ChunkStreamKinds(bytes)) {
    EXPECT_FALSE(kinds.count(kFullMaskKind)) << "a surface's chunk with full-leaf masks";
  }
  for (const SvoSectionBytes& sec : stats.sections) EXPECT_NE(sec.name, "full leaves");
  auto back = DecodeSvo(bytes, "surface.svo");
  ASSERT_TRUE(back.ok()) << back.status().message();
  EXPECT_FALSE(back->solid);
  EXPECT_EQ(back->InteriorVoxelCount(), 0u);
  for (const SvoLevel& level : back->levels) {
    for (const SvoNode& n : level.nodes) EXPECT_EQ(n.full_mask, 0);
  }
  // Without bricks (whose opacities a solid's interior changes), the solid of the same voxels
  // differs from the surface only by the flag, the masks and their counts.
  bo.brick_side = 0;
  auto plain = BuildCompactSvo(*voxels, &sphere, bo);
  ASSERT_TRUE(plain.ok());
  const Solid s = MakeSolid(test::Icosphere(4), 64, 0, false, false);
  EXPECT_GT(EncodeSvo(s.svo).size(), EncodeSvo(*plain).size());
}

// Open surfaces: winding numbers split the cubes they cannot decide whole; the split cube is a
// node without children whose full leaves are its inside parts.
void ExpectOpenSolid(const Mesh& mesh, std::uint32_t resolution, bool expect_split) {
  const Solid s = MakeSolid(mesh, resolution, 3, false);
  ASSERT_EQ(s.interior.method, FillMethod::kWindingNumber);
  EXPECT_GT(s.interior.open_edges, 0u);
  const std::vector<std::uint8_t> bytes = EncodeSvo(s.svo);
  auto back = DecodeSvo(bytes, "open.svo");
  ASSERT_TRUE(back.ok()) << back.status().message();
  ExpectSolidOctree(*back, s);
  EXPECT_TRUE(*back == AssembleSvo(s.svo));
  // Split nodes: not nodes of the surface, each holding full leaves only; every other node is one
  // of the surface's.
  const auto surface =
      LevelKeysFromVoxels(std::span<const std::uint64_t>(s.voxels.keys), s.svo.depth());
  std::uint64_t split = 0;
  for (std::uint32_t l = 0; l < back->depth; ++l) {
    const std::vector<std::uint64_t> keys = back->LevelKeys(l);
    for (std::size_t i = 0; i < keys.size(); ++i) {
      const SvoNode& n = back->levels[l].nodes[i];
      const bool of_surface = std::binary_search(surface[l].begin(), surface[l].end(), keys[i]);
      if (n.child_mask == 0) {
        ++split;
        EXPECT_NE(n.full_mask, 0) << "level " << l << " node " << i;
        EXPECT_FALSE(of_surface) << "level " << l << " node " << i;
      }
      if (!of_surface) {
        // A split node, or an ancestor of one: it holds no surface voxel.
        EXPECT_NE(n.child_mask | n.full_mask, 0);
      }
    }
  }
  if (expect_split) {
    EXPECT_GT(split, 0u) << "no split cube: the test does not test them";
  }
  EXPECT_EQ(HeadFlags(bytes) & kSolidFlag, kSolidFlag);
  ::testing::Test::RecordProperty("split_nodes", static_cast<int>(split));
}

TEST(SvoSolid, OpenSurfacesKeepTheirSplitCubesAsNodes) {
  {
    SCOPED_TRACE("holed icosphere");
    ExpectOpenSolid(HoledIcosphere(), 64, true);
  }
  SVOKIT_REQUIRE_FILE(Spider());
  SCOPED_TRACE("spider.obj");
  ExpectOpenSolid(Imported(Spider()), 128, true);
}

// A solid over several pages: the interior's largest cubes (a whole page) are full leaves of the
// top chunk; the build by pages, whatever its limit, thread count and bricks, writes the whole
// build's bytes.
TEST(SvoSolid, PagedSolidsHaveFullLeavesInTheTopChunkAndBuildByPagesAlike) {
  const Mesh sphere = test::Icosphere(4, false);
  const std::uint32_t resolution = 400;  // depth 9, pages below level 2; one page cube is inside
  const Solid s = MakeSolid(sphere, resolution, 0, false, false);
  ASSERT_EQ(s.svo.depth(), 9u);
  const std::vector<std::uint8_t> bytes = EncodeSvo(s.svo);
  auto reader = SvoReader::FromBytes(bytes, "ball.svo");
  ASSERT_TRUE(reader.ok()) << reader.status().message();
  ASSERT_EQ(reader->page_level(), 2u);
  ASSERT_GT(reader->page_count(), 1u);
  EXPECT_TRUE(reader->shape().solid);
  auto top = reader->Top();
  ASSERT_TRUE(top.ok()) << top.status().message();
  ASSERT_EQ(top->tree.full.size(), 2u);
  EXPECT_FALSE(s.interior.levels[2].empty()) << "no page-sized cube";
  std::uint64_t top_cubes = 0;
  for (const auto& level : top->tree.full) {
    for (const std::uint8_t m : level) top_cubes += static_cast<std::uint64_t>(std::popcount(m));
  }
  EXPECT_EQ(top_cubes, s.interior.levels[1].size() + s.interior.levels[2].size());
  for (std::size_t i = 0; i < reader->page_count(); ++i) {
    auto page = reader->Page(i);
    ASSERT_TRUE(page.ok()) << page.status().message();
    EXPECT_EQ(page->tree.full.size(), page->tree.masks.size()) << "page " << i;
  }
  auto back = DecodeSvo(bytes, "ball.svo");
  ASSERT_TRUE(back.ok()) << back.status().message();
  ExpectSolidOctree(*back, s);

  test::TempDir dir;
  auto finder = InteriorFinder::Create(s.mesh, s.voxels.grid);
  ASSERT_TRUE(finder.ok()) << finder.status().message();
  auto regions = RegionVoxelizer::Create(s.mesh, s.voxels.grid, VoxelizeOptions{});
  ASSERT_TRUE(regions.ok()) << regions.status().message();
  BuildOptions bo;
  bo.contours = false;
  bo.interior_finder = finder->get();
  // With bricks the pages' faces read the interior across them, and the top levels the whole
  // pages inside.
  for (const std::uint32_t side : {0u, 3u, 2u}) {
    const Solid whole = side == 0 ? Solid{} : MakeSolid(sphere, resolution, side, false, false);
    ASSERT_TRUE(WriteSvo(side == 0 ? s.svo : whole.svo, dir / "whole.svo").ok());
    const std::string want = test::ReadText(dir / "whole.svo");
    bo.brick_side = side;
    for (const std::uint64_t limit : {std::uint64_t{0}, std::uint64_t{16} << 20}) {
      for (const std::size_t threads : {1, 2}) {
        if (side == 2 && (limit == 0 || threads == 1)) continue;  // side 3's paths, other weights
        ThreadLimit limit_threads(threads);
        auto stats = BuildSvoByPages(**regions, bo, R"({"source":"solid test"})", dir / "paged.svo",
                                     {}, limit);
        ASSERT_TRUE(stats.ok()) << stats.status().message();
        EXPECT_TRUE(test::ReadText(dir / "paged.svo") == want)
            << "bricks " << side << ", limit " << limit << ", threads " << threads;
      }
    }
  }
  // Parts cannot fill: the top levels' full leaves depend on every part's pages.
  auto part = BuildSvoPart(**regions, bo, "{}", {0, 2, 1}, dir / "p.svopart", {}, 0);
  ASSERT_FALSE(part.ok());
  EXPECT_NE(part.status().message().find("--pages"), std::string::npos) << part.status().message();
  EXPECT_FALSE(std::filesystem::exists(dir / "p.svopart"));
}

TEST(SvoSolid, OpenSurfacesAreNotBuiltByPages) {
  const Mesh holed = HoledIcosphere();
  auto grid = GridTransform::FitResolution(holed.Bounds(), 200);
  ASSERT_TRUE(grid.ok());
  auto finder = InteriorFinder::Create(holed, *grid);
  ASSERT_TRUE(finder.ok());
  ASSERT_EQ((*finder)->method(), FillMethod::kWindingNumber);
  auto regions = RegionVoxelizer::Create(holed, *grid, VoxelizeOptions{});
  ASSERT_TRUE(regions.ok());
  BuildOptions bo;
  bo.brick_side = 0;
  bo.contours = false;
  bo.interior_finder = finder->get();
  test::TempDir dir;
  auto paged = BuildSvoByPages(**regions, bo, "{}", dir / "o.svo", {}, 0);
  ASSERT_FALSE(paged.ok());
  EXPECT_NE(paged.status().message().find("open edges"), std::string::npos)
      << paged.status().message();
  EXPECT_EQ(paged.status().message().find('\n'), std::string::npos);
  EXPECT_TRUE(dir.Files().empty());
}

// ---------------------------------------------------------------------------------------------
// Damage: full leaves that contradict the tree are refused, with one line naming the file.

// `whole_file`: a check of the whole file (as voxels inside the grid), which a streaming reader
// loading one chunk at a time does not make.
void ExpectRefused(const CompactSvo& svo, const std::string& expect, bool whole_file = false) {
  const std::vector<std::uint8_t> bytes = EncodeSvo(svo);
  auto r = DecodeSvo(bytes, "bad.svo");
  ASSERT_FALSE(r.ok()) << "accepted: " << expect;
  EXPECT_EQ(r.status().message().rfind("bad.svo: ", 0), 0u) << r.status().message();
  EXPECT_EQ(r.status().message().find('\n'), std::string::npos) << r.status().message();
  EXPECT_NE(r.status().message().find(expect), std::string::npos) << r.status().message();
  auto lenient = DecodeSvoLenient(bytes, "bad.svo");
  ASSERT_TRUE(lenient.ok());
  EXPECT_FALSE(lenient->complete && lenient->issues.empty()) << expect;
  auto reader = SvoReader::FromBytes(bytes, "bad.svo");
  if (reader.ok() && !whole_file) {
    bool refused = !reader->Top().ok();
    for (std::size_t i = 0; i < reader->page_count(); ++i) refused |= !reader->Page(i).ok();
    EXPECT_TRUE(refused) << "the streaming reader loads every chunk: " << expect;
  }
}

TEST(SvoSolid, AFullLeafThatIsAlsoAChildIsRefused) {
  const Solid s = MakeSolid(test::Icosphere(4), 64, 3, false);
  // At the root, at the page level's parent and just above the voxels.
  for (const std::uint32_t level : {0u, 3u, s.svo.depth() - 1}) {
    CompactSvo bad = s.svo;
    std::vector<std::uint8_t>& masks = bad.whole.tree.masks[level];
    const std::size_t node = masks.size() / 2;
    bad.whole.tree.full[level][node] |= static_cast<std::uint8_t>(masks[node] & -masks[node]);
    ExpectRefused(bad, "both full and not");
  }
}

TEST(SvoSolid, ANodeWithNeitherChildrenNorFullLeavesIsRefused) {
  const Solid s = MakeSolid(HoledIcosphere(), 64, 3, false);
  // A split cube's node with its full leaves cleared: an empty node.
  CompactSvo bad = s.svo;
  bool found = false;
  for (std::uint32_t l = 0; l < bad.depth() && !found; ++l) {
    for (std::size_t i = 0; i < bad.whole.tree.masks[l].size() && !found; ++i) {
      if (bad.whole.tree.masks[l][i] == 0) {
        ASSERT_NE(bad.whole.tree.full[l][i], 0);
        bad.whole.tree.full[l][i] = 0;
        found = true;
      }
    }
  }
  ASSERT_TRUE(found) << "the holed icosphere at 64 has no split cube";
  ExpectRefused(bad, "has no children");
}

// The flag and the stream go together: a solid's file without the flag has a stream too many, a
// surface's with it one too few (checksums made right, so only the structure tells).
TEST(SvoSolid, HeadFlagAndFullLeafStreamMustAgree) {
  const Solid s = MakeSolid(test::Icosphere(4), 64, 3, false);
  const std::vector<std::uint8_t> solid = EncodeSvo(s.svo);
  const std::uint32_t flags = HeadFlags(solid);
  ASSERT_TRUE(DecodeSvo(WithHeadFlags(solid, flags), "same.svo").ok());
  auto unflagged = DecodeSvo(WithHeadFlags(solid, flags & ~kSolidFlag), "bad.svo");
  ASSERT_FALSE(unflagged.ok()) << "a solid's masks read as a surface";
  EXPECT_EQ(unflagged.status().message().rfind("bad.svo: ", 0), 0u);
  EXPECT_NE(unflagged.status().message().find("full"), std::string::npos)
      << unflagged.status().message();

  CompactSvo surface = s.svo;
  surface.frame.shape.solid = false;
  surface.whole.tree.full.clear();
  const std::vector<std::uint8_t> plain = EncodeSvo(surface);
  ASSERT_TRUE(DecodeSvo(plain, "plain.svo").ok());
  auto flagged = DecodeSvo(WithHeadFlags(plain, HeadFlags(plain) | kSolidFlag), "bad.svo");
  ASSERT_FALSE(flagged.ok()) << "a solid without full-leaf masks";
  EXPECT_EQ(flagged.status().message().rfind("bad.svo: ", 0), 0u);
  // Unknown flags beside it are refused as before.
  auto unknown = DecodeSvo(WithHeadFlags(solid, flags | 64), "bad.svo");
  ASSERT_FALSE(unknown.ok());
  EXPECT_NE(unknown.status().message().find("flags"), std::string::npos)
      << unknown.status().message();
}

// A full leaf outside the grid stands for voxels the grid does not have: the readers check every
// voxel against the grid, and must check the interior's cubes likewise (exports would otherwise
// write voxels past the grid's dimensions).
TEST(SvoSolid, AFullLeafOutsideTheGridIsRefused) {
  // The torus' grid is 64 × 17 × 64: the root's children with y = 1 (y ≥ 32) lie outside it.
  const Solid s = MakeSolid(Imported(test::DataDir() / "uv-torus.obj"), 64, 3, false);
  ASSERT_EQ(s.svo.frame.grid.dims()[1], 17u);
  ASSERT_EQ(s.svo.whole.tree.masks[0][0] & 0xcc, 0) << "no root child above y = 32 expected";
  CompactSvo bad = s.svo;
  bad.whole.tree.full[0][0] |= 0x04;  // child (0, 1, 0): voxels (0..31, 32..63, 0..31)
  ExpectRefused(bad, "outside the grid", /*whole_file=*/true);
}

}  // namespace
}  // namespace svokit
