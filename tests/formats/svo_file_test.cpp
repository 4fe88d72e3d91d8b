// The .svo reader on version-1 files (written by tests/formats/svo_v1_writer.hpp): exact round
// trips (nodes, bricks, contours, metadata, grid) for every brick option, loading the top levels
// only, and rejection of corrupt, truncated and structurally inconsistent files with a message
// naming the file. Version 2: svo_v2_test.cpp.

#include "svokit/formats/svo/svo_file.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <map>

#include "svokit/core/morton.hpp"
#include "svokit/formats/mesh_import.hpp"
#include "svokit/svo/build_options.hpp"
#include "svokit/svo/reference_build.hpp"
#include "svokit/voxelize/voxelize.hpp"
#include "tests/formats/svo_v1_writer.hpp"
#include "tests/test_util.hpp"

namespace svokit {
namespace {

using Ijk = std::array<std::uint32_t, 3>;

// Five voxels in a 4×4×3 grid (depth 2): level 1 holds nodes (0,0,0) mask 0x43, (1,0,0) mask
// 0x10, (1,1,1) mask 0x08; the root's mask is 0x83.
Svo HandSvo(std::uint32_t side = 3) {
  VoxelSet set;
  set.grid = GridTransform({-0.5, 1.25, 3.0}, 0.375, {4, 4, 3});
  set.mode = VoxelMode::kThin;
  for (const Ijk& v : {Ijk{0, 0, 0}, Ijk{1, 0, 0}, Ijk{0, 1, 1}, Ijk{2, 0, 1}, Ijk{3, 3, 2}}) {
    set.keys.push_back(MortonEncode(v[0], v[1], v[2]));
  }
  std::sort(set.keys.begin(), set.keys.end());
  for (std::size_t i = 0; i < set.keys.size(); ++i) {
    set.colors.push_back({0.1f * static_cast<float>(i), 0.5f, 0.9f, 1});
    set.normals.push_back(Vec3f{0, 1, 0});
    set.coverage.push_back(1);
  }
  BuildOptions options;
  options.brick_side = side;
  options.contours = false;
  auto svo = BuildReferenceSvo(set, nullptr, options, R"({"source":"hand","build":"--bricks 3"})");
  EXPECT_TRUE(svo.ok()) << svo.status().message();
  return svo.ok() ? std::move(*svo) : Svo{};
}

// HandSvo with two contours set by hand, consistently: voxel (0,0,0) (child 0 of level-1 node 0)
// and level-1 node 2 (child 7 of the root).
Svo HandSvoWithContours() {
  Svo svo = HandSvo();
  svo.has_contours = true;
  const std::uint32_t word = EncodeContour({3, -5, 20, 7, 40});
  svo.levels[1].contours = {word};
  svo.levels[0].nodes[0].contour_mask = 0x80;
  svo.levels[2].contours = {word ^ 0x10u};
  svo.levels[1].nodes[0].contour_mask = 0x01;
  svo.levels[1].nodes[1].first_contour = 1;
  svo.levels[1].nodes[2].first_contour = 1;
  return svo;
}

struct Torus {
  Mesh mesh;
  VoxelSet voxels;
};
const Torus& TorusAt(std::uint32_t resolution) {
  static std::map<std::uint32_t, Torus> cache;
  auto it = cache.find(resolution);
  if (it != cache.end()) return it->second;
  Torus t;
  auto mesh = ImportMesh(test::DataDir() / "uv-torus.obj");
  EXPECT_TRUE(mesh.ok()) << mesh.status().message();
  if (mesh.ok()) {
    t.mesh = std::move(*mesh);
    auto grid = GridTransform::FitResolution(t.mesh.Bounds(), resolution);
    VoxelizeOptions options;
    options.colors = options.normals = true;
    auto voxels = Voxelize(t.mesh, *grid, options);
    EXPECT_TRUE(voxels.ok()) << voxels.status().message();
    if (voxels.ok()) t.voxels = std::move(*voxels);
  }
  return cache.emplace(resolution, std::move(t)).first->second;
}

Svo BuiltTorus(std::uint32_t resolution, std::uint32_t side, bool contours) {
  const Torus& t = TorusAt(resolution);
  BuildOptions options;
  options.brick_side = side;
  options.contours = contours;
  auto svo = BuildReferenceSvo(t.voxels, &t.mesh, options,
                               R"({"source":"uv-torus.obj","voxelize":"--resolution )" +
                                   std::to_string(resolution) + R"("})");
  EXPECT_TRUE(svo.ok()) << svo.status().message();
  return svo.ok() ? std::move(*svo) : Svo{};
}

// Field by field, so a failure says what differs (operator== is checked as well).
void ExpectSameSvo(const Svo& got, const Svo& want) {
  EXPECT_EQ(got.grid, want.grid);
  EXPECT_EQ(got.mode, want.mode);
  EXPECT_EQ(got.depth, want.depth);
  EXPECT_EQ(got.brick_side, want.brick_side);
  EXPECT_EQ(got.has_color, want.has_color);
  EXPECT_EQ(got.has_normal, want.has_normal);
  EXPECT_EQ(got.has_contours, want.has_contours);
  EXPECT_EQ(got.metadata, want.metadata);
  ASSERT_EQ(got.levels.size(), want.levels.size());
  for (std::size_t l = 0; l < want.levels.size(); ++l) {
    EXPECT_EQ(got.levels[l].node_count, want.levels[l].node_count) << l;
    EXPECT_TRUE(got.levels[l].nodes == want.levels[l].nodes) << "nodes of level " << l;
    EXPECT_EQ(got.levels[l].opacity, want.levels[l].opacity) << "opacity of level " << l;
    EXPECT_EQ(got.levels[l].color, want.levels[l].color) << "colour of level " << l;
    EXPECT_EQ(got.levels[l].normal, want.levels[l].normal) << "normals of level " << l;
    EXPECT_EQ(got.levels[l].contours, want.levels[l].contours) << "contours of level " << l;
  }
  EXPECT_TRUE(got == want);
}

TEST(SvoFile, HandOctreeRoundTripsExactly) {
  for (std::uint32_t side : {3u, 2u, 0u}) {
    SCOPED_TRACE("brick side " + std::to_string(side));
    const Svo svo = HandSvo(side);
    const auto bytes = test::EncodeSvoV1(svo);
    EXPECT_EQ(test::EncodeSvoV1(svo), bytes) << "deterministic";
    auto back = DecodeSvo(bytes, "hand.svo");
    ASSERT_TRUE(back.ok()) << back.status().message();
    ExpectSameSvo(*back, svo);
  }
  const Svo contours = HandSvoWithContours();
  auto back = DecodeSvo(test::EncodeSvoV1(contours), "contours.svo");
  ASSERT_TRUE(back.ok()) << back.status().message();
  ExpectSameSvo(*back, contours);
  EXPECT_EQ(back->levels[1].contours.size(), 1u);
}

TEST(SvoFile, BuiltOctreeRoundTripsWithEveryBrickOption) {
  for (std::uint32_t side : {3u, 2u, 0u}) {
    for (bool contours : {false, true}) {
      SCOPED_TRACE("brick side " + std::to_string(side) + (contours ? " contours" : ""));
      const Svo svo = BuiltTorus(32, side, contours);
      ASSERT_EQ(svo.depth, 5u);
      if (contours) {
        std::size_t n = 0;
        for (const SvoLevel& lv : svo.levels) n += lv.contours.size();
        EXPECT_GT(n, 100u);
      }
      const auto bytes = test::EncodeSvoV1(svo);
      auto back = DecodeSvo(bytes, "torus.svo");
      ASSERT_TRUE(back.ok()) << back.status().message();
      ExpectSameSvo(*back, svo);
      EXPECT_EQ(test::EncodeSvoV1(*back), bytes);
    }
  }
}

TEST(SvoFile, ReadsVersionOneFiles) {
  test::TempDir dir;
  const Svo svo = BuiltTorus(32, 3, true);
  const auto path = dir.Write("torus.svo", test::EncodeSvoV1(svo));
  auto back = ReadSvo(path);
  ASSERT_TRUE(back.ok()) << back.status().message();
  ExpectSameSvo(*back, svo);

  auto missing = ReadSvo(dir / "nope.svo");
  ASSERT_FALSE(missing.ok());
  EXPECT_EQ(missing.status().code(), StatusCode::kBadInput);
  EXPECT_NE(missing.status().message().find("nope.svo"), std::string::npos);
  auto not_svo = ReadSvo(dir.Write("text.svo", std::string("hello, this is not an octree")));
  ASSERT_FALSE(not_svo.ok());
  EXPECT_NE(not_svo.status().message().find("text.svo"), std::string::npos);
}

TEST(SvoFile, TopLevelsOnly) {
  const Svo full = BuiltTorus(32, 3, true);
  const auto bytes = test::EncodeSvoV1(full);
  for (std::uint32_t k = 0; k <= full.depth + 2; ++k) {
    SCOPED_TRACE("max_level " + std::to_string(k));
    auto top = DecodeSvo(bytes, "torus.svo", k);
    ASSERT_TRUE(top.ok()) << top.status().message();
    const std::uint32_t last = std::min(k, full.depth);
    ASSERT_EQ(top->levels.size(), last + 1);
    EXPECT_EQ(top->depth, full.depth) << "the depth stays the file's";
    EXPECT_EQ(top->grid, full.grid);
    EXPECT_EQ(top->brick_side, full.brick_side);
    EXPECT_EQ(top->has_color, full.has_color);
    EXPECT_EQ(top->has_normal, full.has_normal);
    EXPECT_EQ(top->has_contours, full.has_contours);
    EXPECT_EQ(top->metadata, full.metadata);
    for (std::uint32_t l = 0; l <= last; ++l) {
      EXPECT_TRUE(top->levels[l] == full.levels[l]) << "level " << l;
      EXPECT_EQ(top->LevelKeys(l), full.LevelKeys(l)) << "level " << l;
    }
    if (k >= full.depth) ExpectSameSvo(*top, full);
  }
}

TEST(SvoFile, TopLevelsOnlyStillCheckTheLastLevelAgainstTheNextLevelsCounts) {
  // The HEAD section holds every level's node count, so a reader that stops at level k can (and,
  // verifying on open, must) check level k's child masks and first-child indices against level
  // k + 1's count: a streaming client loads level k + 1 later and indexes it with them.
  Svo svo = HandSvo();
  svo.levels[1].nodes[2].child_mask = 0xc0;  // 6 children named, level 2 holds 5
  svo.levels[1].nodes[2].leaf_mask = 0xc0;
  const auto bytes = test::EncodeSvoV1(svo);
  ASSERT_FALSE(DecodeSvo(bytes, "bad.svo").ok());
  auto top = DecodeSvo(bytes, "bad.svo", 1);
  EXPECT_FALSE(top.ok()) << "level 1 names 6 children, the file's level 2 holds 5";
  svo = HandSvo();
  svo.levels[1].nodes[1].first_child += 1;
  top = DecodeSvo(test::EncodeSvoV1(svo), "bad.svo", 1);
  EXPECT_FALSE(top.ok()) << "first child index out of sequence at the last loaded level";
  // The consistent file loads at every max_level.
  for (std::uint32_t k = 0; k <= 2; ++k)
    EXPECT_TRUE(DecodeSvo(test::EncodeSvoV1(HandSvo()), "ok.svo", k).ok());
}

// Decodes `bytes` and expects a one-line bad-input error naming the file.
void ExpectDetected(const std::vector<std::uint8_t>& bytes, const std::string& what) {
  auto r = DecodeSvo(bytes, "flip.svo");
  ASSERT_FALSE(r.ok()) << what << " not detected";
  EXPECT_EQ(r.status().code(), StatusCode::kBadInput) << what;
  EXPECT_EQ(r.status().message().rfind("flip.svo: ", 0), 0u)
      << what << ": " << r.status().message();
  EXPECT_EQ(r.status().message().find('\n'), std::string::npos) << what;
}

TEST(SvoFile, EveryFlippedByteOfASmallFileIsDetected) {
  const auto clean = test::EncodeSvoV1(HandSvoWithContours());
  for (std::size_t i = 0; i < clean.size(); ++i) {
    for (std::uint8_t mask : {std::uint8_t{0x01}, std::uint8_t{0x80}}) {
      auto bytes = clean;
      bytes[i] ^= mask;
      ExpectDetected(bytes, "byte " + std::to_string(i));
    }
  }
}

TEST(SvoFile, FlippedBytesAcrossABuiltFileAreDetected) {
  const auto clean = test::EncodeSvoV1(BuiltTorus(32, 3, true));
  ASSERT_GT(clean.size(), 10000u);
  // The header and section table byte by byte, then positions spread over the payloads.
  for (std::size_t i = 0; i < clean.size(); i += (i < 1024 ? 1 : 997)) {
    auto bytes = clean;
    bytes[i] ^= 0x04;
    ExpectDetected(bytes, "byte " + std::to_string(i));
  }
  auto last = clean;
  last.back() ^= 0xff;
  ExpectDetected(last, "last byte");
}

TEST(SvoFile, EveryTruncationAndExtensionIsDetected) {
  const Svo svo = HandSvoWithContours();
  const auto clean = test::EncodeSvoV1(svo);
  for (std::size_t n = 0; n < clean.size(); ++n) {
    const std::vector<std::uint8_t> cut(clean.begin(),
                                        clean.begin() + static_cast<std::ptrdiff_t>(n));
    auto r = DecodeSvo(cut, "cut.svo");
    ASSERT_FALSE(r.ok()) << "truncated to " << n << " bytes";
    EXPECT_EQ(r.status().code(), StatusCode::kBadInput);
    EXPECT_EQ(r.status().message().rfind("cut.svo: ", 0), 0u) << r.status().message();
  }
  const auto big = test::EncodeSvoV1(BuiltTorus(32, 2, false));
  for (std::size_t n = 0; n < big.size(); n += 101) {
    const std::vector<std::uint8_t> cut(big.begin(), big.begin() + static_cast<std::ptrdiff_t>(n));
    ASSERT_FALSE(DecodeSvo(cut, "cut.svo").ok()) << "truncated to " << n << " bytes";
  }
  auto longer = clean;
  longer.push_back(0);
  auto r = DecodeSvo(longer, "long.svo");
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().message().rfind("long.svo: ", 0), 0u) << r.status().message();
  // A truncated file on disk, through ReadSvo.
  test::TempDir dir;
  const auto path =
      dir.Write("trunc.svo", std::vector<std::uint8_t>(clean.begin(), clean.end() - 10));
  auto file = ReadSvo(path);
  ASSERT_FALSE(file.ok());
  EXPECT_NE(file.status().message().find("trunc.svo"), std::string::npos);
}

// EncodeSvo recomputes every checksum, so these reach the reader's structural checks.
void ExpectRejected(const Svo& svo, const std::string& expect) {
  auto r = DecodeSvo(test::EncodeSvoV1(svo), "bad.svo");
  ASSERT_FALSE(r.ok()) << "accepted; expected: " << expect;
  EXPECT_EQ(r.status().code(), StatusCode::kBadInput);
  EXPECT_EQ(r.status().message().rfind("bad.svo: ", 0), 0u) << r.status().message();
  EXPECT_NE(r.status().message().find(expect), std::string::npos) << r.status().message();
}

TEST(SvoFile, RejectsChildCountsThatDoNotMatchTheNextLevel) {
  Svo svo = HandSvo();
  svo.levels[0].nodes[0].child_mask = 0x03;  // two children named, level 1 holds three
  ExpectRejected(svo, "level 0 masks name 2 children");
  svo = HandSvo();
  svo.levels[1].nodes[2].child_mask = 0xc0;  // one voxel more than level 2 holds
  svo.levels[1].nodes[2].leaf_mask = 0xc0;
  ExpectRejected(svo, "level 1 masks name 6 children");
  svo = HandSvo();
  svo.levels[1].nodes[1].child_mask = 0;
  svo.levels[1].nodes[1].leaf_mask = 0;
  ExpectRejected(svo, "without children");
}

TEST(SvoFile, RejectsMasksNamingMissingChildren) {
  Svo svo = HandSvoWithContours();
  svo.levels[1].nodes[0].contour_mask |= 0x04;  // child 2 does not exist (mask 0x43)
  ExpectRejected(svo, "contour mask names a missing child");
  svo = HandSvoWithContours();
  svo.levels[0].nodes[0].contour_mask = 0x04;  // the root has no child 2 (mask 0x83)
  ExpectRejected(svo, "contour mask names a missing child");
  svo = HandSvo();
  svo.levels[1].nodes[0].leaf_mask = 0x47;  // leaf bit without the child bit
  ExpectRejected(svo, "names a missing child");
  svo = HandSvo();
  svo.levels[0].nodes[0].leaf_mask = 0x01;  // a leaf above the voxel level
  ExpectRejected(svo, "leaf above the voxel level");
  svo = HandSvo();
  svo.levels[1].nodes[0].leaf_mask = 0x03;  // a voxel that is not a leaf
  ExpectRejected(svo, "voxel children not leaves");
  // More contours marked than stored.
  svo = HandSvoWithContours();
  svo.levels[1].nodes[0].contour_mask = 0x03;
  svo.levels[1].nodes[1].first_contour = 2;
  svo.levels[1].nodes[2].first_contour = 2;
  ExpectRejected(svo, "2 contours");
}

TEST(SvoFile, RejectsIndicesOutOfSequence) {
  Svo svo = HandSvo();
  svo.levels[1].nodes[1].first_child += 1;
  ExpectRejected(svo, "first child index out of sequence");
  svo = HandSvo();
  svo.levels[1].nodes[0].first_child = 1;
  ExpectRejected(svo, "level 1 node 0: first child index out of sequence");
  svo = HandSvoWithContours();
  svo.levels[1].nodes[2].first_contour = 0;
  ExpectRejected(svo, "first contour index out of sequence");
  svo = HandSvo();
  svo.levels[1].nodes[1].full_mask = 1;
  ExpectRejected(svo, "reserved");
}

TEST(SvoFile, RejectsADepthThatDoesNotFitTheGrid) {
  Svo svo = HandSvo();
  svo.depth = 1;  // 2 < 4 voxels
  ExpectRejected(svo, "depth 1 is not the 4-voxel grid's octree depth 2");
  svo = HandSvo();
  svo.depth = 3;  // deeper than the enclosing power of two
  ExpectRejected(svo, "depth 3 is not the 4-voxel grid's octree depth 2");
  svo = HandSvo();
  svo.depth = 0;
  ExpectRejected(svo, "depth 0");
  // The grid grows beyond the tree.
  svo = HandSvo();
  svo.grid = GridTransform(svo.grid.origin(), svo.grid.voxel_size(), {5, 4, 3});
  ExpectRejected(svo, "depth 2 is not the 5-voxel grid's octree depth 3");
}

TEST(SvoFile, RejectsNodesOutsideTheGridAndImpossibleCounts) {
  // Voxel (3,3,2) lies in the 4×4×3 grid; in a 4×4×2 grid it does not.
  Svo svo = HandSvo();
  svo.grid = GridTransform(svo.grid.origin(), svo.grid.voxel_size(), {4, 4, 2});
  ExpectRejected(svo, "outside the grid");
  // Two roots.
  svo = HandSvo();
  svo.levels[0].node_count = 2;
  svo.levels[0].nodes.push_back(svo.levels[0].nodes[0]);
  svo.levels[0].opacity.resize(2 * 27, 0);
  svo.levels[0].color.resize(2 * 27, 0);
  svo.levels[0].normal.resize(2 * 27, 0);
  ExpectRejected(svo, "level 0 counts (2 nodes");
  // A brick plane one sample short, or missing.
  svo = HandSvo();
  svo.levels[2].opacity.pop_back();
  ExpectRejected(svo, "section 'OP02' holds 134 bytes, expected 135");
  svo = HandSvo();
  svo.levels[1].color.clear();
  ExpectRejected(svo, "section 'CL01' holds 0 bytes");
  // Colour without bricks.
  svo = HandSvo(0);
  svo.has_color = true;
  ExpectRejected(svo, "invalid flags");
  svo = HandSvo();
  svo.brick_side = 4;
  ExpectRejected(svo, "brick side 4");
  // Contours in a file that says it has none; a contour word with a zero normal.
  svo = HandSvoWithContours();
  svo.has_contours = false;
  ExpectRejected(svo, "impossible");
  svo = HandSvoWithContours();
  svo.levels[2].contours[0] &= ~0x3ffffu;
  ExpectRejected(svo, "contour without a normal");
}

}  // namespace
}  // namespace svokit
