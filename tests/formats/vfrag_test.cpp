#include "formats/vfrag/vfrag.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <sstream>

#include "formats/container/grid_section.hpp"
#include "tests/test_util.hpp"

namespace svokit {
namespace {

VoxelSet Sample() {
  VoxelSet s;
  s.grid = GridTransform({-1.5, 0.25, 1e-3}, 0.1 + 1e-17, {5, 6, 7});
  s.mode = VoxelMode::kThin;
  for (std::uint32_t z = 0; z < 7; z += 3)
    for (std::uint32_t y = 0; y < 6; y += 2)
      for (std::uint32_t x = 0; x < 5; ++x) s.keys.push_back(MortonEncode(x, y, z));
  std::sort(s.keys.begin(), s.keys.end());
  return s;
}

TEST(Vfrag, RoundTripIsExact) {
  const VoxelSet s = Sample();
  const auto bytes = EncodeVfrag(s, {"m.obj", "--resolution 7"});
  EXPECT_EQ(EncodeVfrag(s, {"m.obj", "--resolution 7"}), bytes);
  auto back = DecodeVfrag(bytes, "mem.vfrag");
  ASSERT_TRUE(back.ok()) << back.status().message();
  EXPECT_EQ(back->grid, s.grid);
  EXPECT_EQ(back->mode, s.mode);
  EXPECT_EQ(back->keys, s.keys);
}

TEST(Vfrag, AttributesRoundTripAndMustMatchTheVoxelCount) {
  VoxelSet s = Sample();
  for (std::size_t i = 0; i < s.size(); ++i) {
    const float f = static_cast<float>(i) / static_cast<float>(s.size());
    s.colors.push_back({f, 1 - f, 0.5f, 1});
    s.normals.push_back({0, f, 1});
    s.coverage.push_back(f * 2);
  }
  auto back = DecodeVfrag(EncodeVfrag(s, {}), "attr.vfrag");
  ASSERT_TRUE(back.ok()) << back.status().message();
  EXPECT_EQ(back->colors, s.colors);
  EXPECT_EQ(back->normals, s.normals);
  EXPECT_EQ(back->coverage, s.coverage);
  s.colors.pop_back();
  auto bad = DecodeVfrag(EncodeVfrag(s, {}), "short.vfrag");
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.status().message().find("section 'COLR'"), std::string::npos);
  s.colors.push_back({std::nanf(""), 0, 0, 1});
  bad = DecodeVfrag(EncodeVfrag(s, {}), "nan.vfrag");
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.status().message().find("non-finite"), std::string::npos);
}

// Version 1 stored coverage as f32 (version 2: binary16); a version 2 reader still reads it.
TEST(Vfrag, Version1CoverageIsReadAsFloat32) {
  VoxelSet s = Sample();
  std::vector<float> coverage;
  for (std::size_t i = 0; i < s.size(); ++i) coverage.push_back(0.1f * static_cast<float>(i));
  container::FormatId v1 = kVfragFormat;
  v1.version = 1;
  container::Writer w(v1, 0);
  w.AddSection(container::MakeTag("GRID"), EncodeGridSection(s.grid, s.mode));
  const auto* keys = reinterpret_cast<const std::uint8_t*>(s.keys.data());
  w.AddSection(container::MakeTag("KEYS"), {keys, keys + 8 * s.size()});
  const auto* cov = reinterpret_cast<const std::uint8_t*>(coverage.data());
  w.AddSection(container::MakeTag("COVR"), {cov, cov + 4 * s.size()});
  auto back = DecodeVfrag(w.Serialize(), "v1.vfrag");
  ASSERT_TRUE(back.ok()) << back.status().message();
  ASSERT_EQ(back->coverage.size(), s.size());
  for (std::size_t i = 0; i < s.size(); ++i) {
    EXPECT_EQ(back->coverage[i], Half(coverage[i])) << i;
  }
  // Version 2 writes two bytes a voxel.
  s.coverage.assign(coverage.begin(), coverage.end());
  const std::vector<std::uint8_t> v2_bytes = EncodeVfrag(s, {});
  auto v2 = container::Frame::FromBytes(v2_bytes, "v2.vfrag", kVfragFormat);
  ASSERT_TRUE(v2.ok()) << v2.status().message();
  EXPECT_EQ(v2->version(), 2u);
  const auto* section = v2->Find(container::MakeTag("COVR"));
  ASSERT_NE(section, nullptr);
  EXPECT_EQ(section->size, 2 * s.size());
}

TEST(Vfrag, RejectsUnsortedOrOutOfGridKeysAndCorruption) {
  VoxelSet s = Sample();
  std::swap(s.keys[0], s.keys[1]);
  auto r = DecodeVfrag(EncodeVfrag(s, {}), "unsorted.vfrag");
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("not strictly increasing"), std::string::npos);
  s = Sample();
  s.keys.push_back(MortonEncode(4, 5, 7));  // beyond every key, but z = 7 is outside the grid
  r = DecodeVfrag(EncodeVfrag(s, {}), "outside.vfrag");
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("outside the 5x6x7 grid"), std::string::npos);
  auto bytes = EncodeVfrag(Sample(), {});
  bytes[bytes.size() / 2] ^= 1;
  EXPECT_FALSE(DecodeVfrag(bytes, "flip.vfrag").ok());
  bytes.resize(bytes.size() - 3);
  EXPECT_FALSE(DecodeVfrag(bytes, "cut.vfrag").ok());
}

TEST(Vfrag, XyzHeaderRoundTripsTheTransformExactly) {
  test::TempDir dir;
  const VoxelSet s = Sample();
  ASSERT_TRUE(WriteVoxelsXyz(s, dir / "v.xyz").ok());
  std::istringstream in(test::ReadText(dir / "v.xyz"));
  std::string hash, key;
  std::string ox, oy, oz, h;
  std::uint32_t nx, ny, nz;
  in >> hash >> key >> ox >> oy >> oz;
  EXPECT_EQ(key, "origin");
  EXPECT_EQ(std::strtod(ox.c_str(), nullptr), s.grid.origin().x);
  EXPECT_EQ(std::strtod(oz.c_str(), nullptr), s.grid.origin().z);
  in >> hash >> key >> h;
  EXPECT_EQ(key, "voxel_size");
  EXPECT_EQ(std::strtod(h.c_str(), nullptr), s.grid.voxel_size());
  in >> hash >> key >> nx >> ny >> nz;
  EXPECT_EQ(key, "dims");
  EXPECT_EQ(nx, 5u);
  EXPECT_EQ(nz, 7u);
  std::vector<std::uint64_t> keys;
  std::uint32_t x, y, z;
  while (in >> x >> y >> z) keys.push_back(MortonEncode(x, y, z));
  EXPECT_EQ(keys, s.keys);  // Morton order
}

TEST(Vfrag, PlyPointsAreVoxelCentres) {
  test::TempDir dir;
  const VoxelSet s = Sample();
  ASSERT_TRUE(WriteVoxelsPly(s, dir / "v.ply").ok());
  const std::string text = test::ReadText(dir / "v.ply");
  const std::size_t end = text.find("end_header\n");
  ASSERT_NE(end, std::string::npos);
  EXPECT_NE(text.find(fmt::format("element vertex {}", s.keys.size())), std::string::npos);
  const std::size_t body = end + 11;
  ASSERT_EQ(text.size() - body, s.keys.size() * 12);
  float p[3];
  std::memcpy(p, text.data() + body, 12);
  const MortonCoord c = MortonDecode(s.keys[0]);
  const Vec3d want = s.grid.VoxelCenter({c.x, c.y, c.z});
  EXPECT_FLOAT_EQ(p[0], static_cast<float>(want.x));
  EXPECT_FLOAT_EQ(p[2], static_cast<float>(want.z));
}

}  // namespace
}  // namespace svokit
