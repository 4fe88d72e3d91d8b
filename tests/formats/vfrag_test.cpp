#include "svokit/formats/vfrag/vfrag.hpp"
#include "svokit/export/voxel_writers.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <limits>
#include <random>
#include <sstream>

#include "svokit/core/file_io.hpp"
#include "svokit/core/key_gaps.hpp"
#include "svokit/formats/container/grid_section.hpp"
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
  const auto bytes = EncodeVfrag(s, {"m.obj", 0, GridFit{7}});
  EXPECT_EQ(EncodeVfrag(s, {"m.obj", 0, GridFit{7}}), bytes);
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
    s.normals.push_back(Vec3f{0, f, 1});
    s.coverage.push_back(f * 2);
  }
  // Colours and coverage are stored as binary16, normals as 16-bit octahedral codes.
  auto back = DecodeVfrag(EncodeVfrag(s, {}), "attr.vfrag");
  ASSERT_TRUE(back.ok()) << back.status().message();
  ASSERT_EQ(back->colors.size(), s.size());
  ASSERT_EQ(back->normals.size(), s.size());
  EXPECT_EQ(back->colors, s.colors);
  EXPECT_EQ(back->normals, s.normals);
  EXPECT_EQ(back->coverage, s.coverage);
  // A voxel set holds each colour component as the binary16 nearest the float it was given, and
  // a normal as the unit vector of the octahedral code nearest its direction: within 7·10⁻⁵ rad.
  for (std::size_t i = 0; i < s.size(); ++i) {
    const float f = static_cast<float>(i) / static_cast<float>(s.size());
    const Rgba c = back->colors[i];
    const Vec3f n = back->normals[i];
    EXPECT_EQ(c, (Rgba{RoundToHalf(f), RoundToHalf(1 - f), 0.5f, 1}));
    EXPECT_NEAR(c.g, 1 - f, (1 - f) / 2048);
    const Vec3d exact = Vec3d{0, f, 1} / std::sqrt(1.0 + double{f} * f);
    EXPECT_NEAR(std::sqrt(Dot(Vec3d{n.x, n.y, n.z}, Vec3d{n.x, n.y, n.z})), 1.0, 1e-6);
    EXPECT_LT(Length(Cross(Vec3d{n.x, n.y, n.z}, exact)), 7e-5) << i;
  }
  s.colors.pop_back();
  auto bad = DecodeVfrag(EncodeVfrag(s, {}), "short.vfrag");
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.status().message().find("section 'COLR'"), std::string::npos);
  s.colors.push_back({std::nanf(""), 0, 0, 1});
  bad = DecodeVfrag(EncodeVfrag(s, {}), "nan.vfrag");
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.status().message().find("non-finite"), std::string::npos);
}

// Writing a set it consumes (its pages released as they are written) gives the file of the set
// written as it is: several batches of keys (each encoded from the one before), attribute
// sections of several pieces, and a colour every voxel shares; the set is left empty.
// The same voxels with their keys packed as varint gaps.
PackedVoxelSet Packed(const VoxelSet& set) {
  PackedVoxelSet packed;
  static_cast<VoxelAttributes&>(packed) = set;
  packed.count = set.size();
  AppendKeyGaps(std::span<const std::uint64_t>(set.keys), kNoPreviousKey, packed.key_gaps);
  return packed;
}

TEST(Vfrag, AConsumedSetWritesTheSameFile) {
  const test::TempDir dir;
  VoxelSet s;
  s.grid = GridTransform({0, 0, 0}, 1, {1 << 12, 1 << 12, 1 << 12});
  std::mt19937_64 rng(7);
  std::uint64_t key = 0;
  for (std::size_t i = 0; i < 1'500'000; ++i) {  // 12 MB of keys, 9 MB of normals
    key += 1 + rng() % 300;
    s.keys.push_back(key);
    const float f = static_cast<float>(rng() % 1000) / 1000;
    s.normals.push_back(Vec3f{f, 1 - f, 0.5f});
    s.coverage.push_back(f);
  }
  s.colors.assign(1, Rgba{0.25f, 0.5f, 0.75f, 1});
  for (const bool shared_normal : {false, true}) {
    if (shared_normal) s.normals.assign(s.size(), Vec3f{0, 0, 1});
    const std::vector<std::uint8_t> expected = EncodeVfrag(s, {"m.obj", 0, GridFit{4096}});
    VoxelSet consumed = s;
    ASSERT_TRUE(WriteVfrag(std::move(consumed), {"m.obj", 0, GridFit{4096}}, dir / "c.vfrag").ok());
    EXPECT_EQ(consumed.size(), 0u);
    EXPECT_TRUE(consumed.normals.empty());
    const auto written = ReadFileBytes(dir / "c.vfrag");
    ASSERT_TRUE(written.ok());
    EXPECT_TRUE(*written == expected) << "shared normal " << shared_normal;
    auto back = DecodeVfrag(*written, "c.vfrag");
    ASSERT_TRUE(back.ok()) << back.status().message();
    EXPECT_EQ(back->keys, s.keys);
    EXPECT_EQ(back->normals, s.normals);
    // Packed keys give the same bytes; gaps of up to 300 take one or two bytes.
    const PackedVoxelSet packed = Packed(s);
    EXPECT_GT(packed.key_gaps.size(), s.size());
    EXPECT_LT(packed.key_gaps.size(), 2 * s.size());
    EXPECT_TRUE(EncodeVfrag(packed, {"m.obj", 0, GridFit{4096}}) == expected);
  }
  // Keys whose gaps are all the same byte are still stored one per voxel (only attributes every
  // voxel shares are stored once).
  VoxelSet run;
  run.grid = s.grid;
  for (std::uint64_t k = 100; k < 200; ++k) run.keys.push_back(k);
  const std::vector<std::uint8_t> run_bytes = EncodeVfrag(run, {});
  EXPECT_TRUE(EncodeVfrag(Packed(run), {}) == run_bytes);
  auto run_back = DecodeVfrag(run_bytes, "run.vfrag");
  ASSERT_TRUE(run_back.ok()) << run_back.status().message();
  EXPECT_EQ(run_back->keys, run.keys);
}

template <class T, class A>
std::vector<std::uint8_t> RawBytes(const std::vector<T, A>& v) {
  const auto* p = reinterpret_cast<const std::uint8_t*>(v.data());
  return {p, p + v.size() * sizeof(T)};
}

// A file of an earlier version, as its writer laid it out: raw u64 keys, f32 colours and normals,
// coverage as `Coverage` (f32 in version 1, binary16 in version 2).
template <class Coverage>
std::vector<std::uint8_t> LegacyFile(std::uint32_t version, const VoxelSet& s,
                                     const std::vector<Rgba>& colors,
                                     const std::vector<Vec3f>& normals,
                                     const std::vector<Coverage>& coverage) {
  container::FormatId format = kVfragFormat;
  format.version = version;
  container::Writer w(format, 0);
  w.AddSection(container::MakeTag("GRID"), EncodeGridSection(s.grid, s.mode));
  w.AddSection(container::MakeTag("KEYS"), RawBytes(s.keys));
  if (!colors.empty()) w.AddSection(container::MakeTag("COLR"), RawBytes(colors));
  if (!normals.empty()) w.AddSection(container::MakeTag("NORM"), RawBytes(normals));
  w.AddSection(container::MakeTag("COVR"), RawBytes(coverage));
  return w.Serialize();
}

// Version 1 stored coverage as f32 (since version 2: binary16); the reader still reads it.
TEST(Vfrag, Version1CoverageIsReadAsFloat32) {
  VoxelSet s = Sample();
  std::vector<float> coverage;
  for (std::size_t i = 0; i < s.size(); ++i) coverage.push_back(0.1f * static_cast<float>(i));
  auto back = DecodeVfrag(LegacyFile(1, s, {}, {}, coverage), "v1.vfrag");
  ASSERT_TRUE(back.ok()) << back.status().message();
  EXPECT_EQ(back->keys, s.keys);
  ASSERT_EQ(back->coverage.size(), s.size());
  for (std::size_t i = 0; i < s.size(); ++i) {
    EXPECT_EQ(back->coverage[i], Half(coverage[i])) << i;
  }
}

// Version 2 stored raw u64 keys and f32 colours and normals; the reader still reads them.
TEST(Vfrag, Version2RawKeysAndFloatAttributesAreRead) {
  VoxelSet s = Sample();
  std::vector<Rgba> colors;
  std::vector<Vec3f> normals;
  std::vector<Half> coverage;
  for (std::size_t i = 0; i < s.size(); ++i) {
    const float f = 0.1f + static_cast<float>(i) / 7.f;  // not binary16-representable
    colors.push_back({f, f / 3, 0.25f, 1});
    normals.push_back({f, 0, 1});
    coverage.push_back(f);
  }
  auto back = DecodeVfrag(LegacyFile(2, s, colors, normals, coverage), "v2.vfrag");
  ASSERT_TRUE(back.ok()) << back.status().message();
  EXPECT_EQ(back->keys, s.keys);
  ASSERT_EQ(back->colors.size(), s.size());
  ASSERT_EQ(back->normals.size(), s.size());
  // Held like every voxel set: each colour float comes back as its nearest binary16, each normal
  // as the octahedral code nearest its direction.
  for (std::size_t i = 0; i < s.size(); ++i) {
    const float f = 0.1f + static_cast<float>(i) / 7.f;
    EXPECT_EQ(Rgba(back->colors[i]), (Rgba{RoundToHalf(f), RoundToHalf(f / 3), 0.25f, 1})) << i;
    EXPECT_EQ(back->normals[i], OctNormal(Vec3f{f, 0, 1})) << i;
  }
  EXPECT_EQ(std::vector<Half>(back->coverage.begin(), back->coverage.end()), coverage);
}

// Version 5: per voxel 8 B colour, 4 B normal, 2 B coverage, and keys as varint gaps (spelled out
// byte by byte here).
TEST(Vfrag, Version5StoresKeyGapsAsVarintsAttributesAsBinary16AndOctahedralNormals) {
  VoxelSet s;
  s.grid = GridTransform({0, 0, 0}, 1, {(1u << 21) - 1, 1u << 20, 1u << 20});
  s.keys = {5, 6, 6 + 1 + 200, (std::uint64_t{1} << 60) + 3};
  for (int i = 0; i < 4; ++i) {
    const float f = 0.25f * static_cast<float>(i);
    s.colors.push_back({f, 0.25f, 1, 1});
    s.normals.push_back(Vec3f{0, f, 1});
    s.coverage.push_back(f);
  }
  const std::vector<std::uint8_t> bytes = EncodeVfrag(s, {});
  auto frame = container::Frame::FromBytes(bytes, "v5.vfrag", kVfragFormat);
  ASSERT_TRUE(frame.ok()) << frame.status().message();
  EXPECT_EQ(frame->version(), 5u);
  const auto* keys = frame->Find(container::MakeTag("KEYS"));
  ASSERT_NE(keys, nullptr);
  // count 4; gaps 5, 0, 200 = 0xC8 0x01, 2^60 + 3 − 207 − 1 = 2^60 − 205.
  std::vector<std::uint8_t> expected = {4, 0, 0, 0, 0, 0, 0, 0, 5, 0, 0xC8, 0x01};
  for (std::uint64_t gap = (std::uint64_t{1} << 60) - 205; gap >= 0x80; gap >>= 7) {
    expected.push_back(static_cast<std::uint8_t>(gap | 0x80));
  }
  expected.push_back(static_cast<std::uint8_t>(((std::uint64_t{1} << 60) - 205) >> 56));
  EXPECT_EQ(std::vector<std::uint8_t>(keys->bytes.begin(), keys->bytes.end()), expected);
  EXPECT_EQ(frame->Find(container::MakeTag("COLR"))->size, 8 * s.size());
  EXPECT_EQ(frame->Find(container::MakeTag("NORM"))->size, 4 * s.size());
  EXPECT_EQ(frame->Find(container::MakeTag("COVR"))->size, 2 * s.size());
  // COLR holds binary16 r, g, b, a per voxel: voxel 1 is (0.25, 0.25, 1, 1).
  const std::uint8_t* colr = frame->Find(container::MakeTag("COLR"))->bytes.data();
  const std::vector<std::uint8_t> voxel1(colr + 8, colr + 16);
  EXPECT_EQ(voxel1, (std::vector<std::uint8_t>{0x00, 0x34, 0x00, 0x34, 0x00, 0x3c, 0x00, 0x3c}));
  // NORM holds two u16 octahedral codes, x first: +z is the octahedron's centre, code 2^15 each;
  // voxel 2's (0, 0.5, 1) is (0, 1/3) on it, 2^15 + round(32767 / 3) = 0xAAAA for y.
  const std::uint8_t* norm = frame->Find(container::MakeTag("NORM"))->bytes.data();
  EXPECT_EQ(std::vector<std::uint8_t>(norm, norm + 4),
            (std::vector<std::uint8_t>{0x00, 0x80, 0x00, 0x80}));
  EXPECT_EQ(std::vector<std::uint8_t>(norm + 8, norm + 12),
            (std::vector<std::uint8_t>{0x00, 0x80, 0xAA, 0xAA}));
  auto back = DecodeVfrag(bytes, "v5.vfrag");
  ASSERT_TRUE(back.ok()) << back.status().message();
  EXPECT_EQ(back->keys, s.keys);
  EXPECT_EQ(back->colors, s.colors);
  EXPECT_EQ(back->normals, s.normals);
  EXPECT_EQ(back->coverage, s.coverage);
}

// An attribute every voxel shares (an untextured mesh's colour) is stored once (since version 4);
// earlier versions must hold one per voxel, and a section of any other size is refused. A shared
// colour is read back as VoxelSet holds one (once); normals and coverage are given to every voxel.
// Version 4's binary16 normals are read as the octahedral codes nearest them; non-finite ones are
// refused.
TEST(Vfrag, AnAttributeEveryVoxelSharesIsStoredOnce) {
  VoxelSet s = Sample();
  ASSERT_GT(s.size(), 2u);
  s.colors.assign(s.size(), Rgba{0.5f, 0.25f, 1, 1});
  for (std::size_t i = 0; i < s.size(); ++i) {
    s.normals.push_back(Vec3f{0, static_cast<float>(i), 1});
  }
  s.coverage.assign(s.size(), Half(1.f));
  const std::vector<std::uint8_t> bytes = EncodeVfrag(s, {});
  auto frame = container::Frame::FromBytes(bytes, "uniform.vfrag", kVfragFormat);
  ASSERT_TRUE(frame.ok()) << frame.status().message();
  EXPECT_EQ(frame->Find(container::MakeTag("COLR"))->size, 8u);
  EXPECT_EQ(frame->Find(container::MakeTag("NORM"))->size, 4 * s.size());
  EXPECT_EQ(frame->Find(container::MakeTag("COVR"))->size, 2u);
  auto back = DecodeVfrag(bytes, "uniform.vfrag");
  ASSERT_TRUE(back.ok()) << back.status().message();
  ASSERT_EQ(back->colors.size(), 1u);
  for (std::size_t i = 0; i < s.size(); ++i) EXPECT_EQ(back->color(i), s.colors[i]);
  EXPECT_EQ(back->normals, s.normals);
  EXPECT_EQ(back->coverage, s.coverage);
  // A set holding its colour once writes the same file.
  VoxelSet once = s;
  once.colors.resize(1);
  EXPECT_EQ(EncodeVfrag(once, {}), bytes);
  // The same sections in a version 3 file are refused.
  auto with_version = [&](std::uint32_t version, std::size_t colors,
                          std::vector<HalfVec3> normals = {}) {
    container::FormatId format = kVfragFormat;
    format.version = version;
    container::Writer w(format, 0);
    w.AddSection(container::MakeTag("GRID"), EncodeGridSection(s.grid, s.mode));
    const auto keys = frame->Find(container::MakeTag("KEYS"))->bytes;
    w.AddSection(container::MakeTag("KEYS"), std::vector<std::uint8_t>(keys.begin(), keys.end()));
    std::vector<HalfRgba> c(colors, HalfRgba(Rgba{0.5f, 0.25f, 1, 1}));
    w.AddSection(container::MakeTag("COLR"), RawBytes(c));
    if (!normals.empty()) w.AddSection(container::MakeTag("NORM"), RawBytes(normals));
    return DecodeVfrag(w.Serialize(), "versioned.vfrag");
  };
  EXPECT_TRUE(with_version(4, 1).ok());
  std::vector<HalfVec3> halves;
  for (std::size_t i = 0; i < s.size(); ++i) halves.push_back(Vec3f{0.5f, -1, float(i) / 3});
  auto v4 = with_version(4, 1, halves);
  ASSERT_TRUE(v4.ok()) << v4.status().message();
  ASSERT_EQ(v4->normals.size(), s.size());
  for (std::size_t i = 0; i < s.size(); ++i) {
    EXPECT_EQ(v4->normals[i], OctNormal(Vec3f(halves[i]))) << i;
  }
  halves[1].y = Half(std::numeric_limits<float>::infinity());
  auto inf = with_version(4, 1, halves);
  ASSERT_FALSE(inf.ok());
  EXPECT_NE(inf.status().message().find("non-finite voxel normal"), std::string::npos);
  auto v3 = with_version(3, 1);
  ASSERT_FALSE(v3.ok());
  EXPECT_NE(v3.status().message().find("section 'COLR' holds 8 bytes"), std::string::npos);
  auto two = with_version(4, 2);
  ASSERT_FALSE(two.ok());
  EXPECT_NE(two.status().message().find("holds 16 bytes, expected"), std::string::npos);
}

TEST(Vfrag, MalformedKeyVarintsAreRefused) {
  const VoxelSet s = Sample();
  auto with_keys = [&](std::vector<std::uint8_t> keys) {
    container::Writer w(kVfragFormat, 0);
    w.AddSection(container::MakeTag("GRID"), EncodeGridSection(s.grid, s.mode));
    w.AddSection(container::MakeTag("KEYS"), std::move(keys));
    return DecodeVfrag(w.Serialize(), "keys.vfrag");
  };
  auto message = [](const StatusOr<VoxelSet>& r) {
    return r.ok() ? std::string("ok") : r.status().message();
  };
  // count 2: keys 1, 3.
  EXPECT_TRUE(with_keys({2, 0, 0, 0, 0, 0, 0, 0, 1, 1}).ok());
  EXPECT_NE(message(with_keys({2, 0, 0, 0, 0, 0, 0, 0, 0x81, 0x81})).find("ends inside"),
            std::string::npos);
  EXPECT_NE(message(with_keys({2, 0, 0, 0, 0, 0, 0, 0, 1, 0x81})).find("ends inside"),
            std::string::npos);
  EXPECT_NE(message(with_keys({2, 0, 0, 0, 0, 0, 0, 0, 1, 1, 0})).find("1 trailing bytes"),
            std::string::npos);
  EXPECT_NE(message(with_keys({0xff, 0, 0, 0, 0, 0, 0, 0, 1, 1})).find("claims 255 keys"),
            std::string::npos);
  EXPECT_NE(message(with_keys({1, 0, 0})).find("KEYS section"), std::string::npos);
  // An 11-byte varint, and a 10th byte with more than bit 63.
  std::vector<std::uint8_t> long_varint = {1, 0, 0, 0, 0, 0, 0, 0};
  long_varint.insert(long_varint.end(), 10, 0x80);
  long_varint.push_back(0);
  EXPECT_NE(message(with_keys(long_varint)).find("malformed key 0"), std::string::npos);
  std::vector<std::uint8_t> wide = {1, 0, 0, 0, 0, 0, 0, 0};
  wide.insert(wide.end(), 9, 0x80);
  wide.push_back(2);
  EXPECT_NE(message(with_keys(wide)).find("malformed key 0"), std::string::npos);
  // Gap 2^63 (a decreasing key, wrapped): not increasing; gap 2^62: beyond the grid.
  std::vector<std::uint8_t> wrapped = {1, 0, 0, 0, 0, 0, 0, 0};
  wrapped.insert(wrapped.end(), 9, 0x80);
  wrapped.push_back(1);
  EXPECT_NE(message(with_keys(wrapped)).find("not strictly increasing"), std::string::npos);
  std::vector<std::uint8_t> far = {1, 0, 0, 0, 0, 0, 0, 0};
  far.insert(far.end(), 8, 0x80);
  far.push_back(0x40);
  EXPECT_NE(message(with_keys(far)).find("outside the 5x6x7 grid"), std::string::npos);
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
  bytes.resize(bytes.size() - 3);
  EXPECT_FALSE(DecodeVfrag(bytes, "cut.vfrag").ok());
}

TEST(Vfrag, EveryFlippedByteIsDetected) {
  VoxelSet s = Sample();
  for (std::size_t i = 0; i < s.size(); ++i) {
    s.colors.push_back({0.5f, 0.25f, 1, 1});
    s.normals.push_back(Vec3f{0, 0, 1});
    s.coverage.push_back(static_cast<float>(i));
  }
  const auto clean = EncodeVfrag(s, {"m.obj", 0, GridFit{7}});
  for (std::size_t i = 0; i < clean.size(); ++i) {
    auto bytes = clean;
    bytes[i] ^= 0x08;
    auto r = DecodeVfrag(bytes, "flip.vfrag");
    ASSERT_FALSE(r.ok()) << "flipped byte " << i << " not detected";
    EXPECT_EQ(r.status().message().rfind("flip.vfrag: ", 0), 0u) << r.status().message();
  }
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
  EXPECT_EQ(keys, std::vector<std::uint64_t>(s.keys.begin(), s.keys.end()));  // Morton order
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

// The source name goes into the META JSON: one that is not UTF-8 is escaped, not thrown on.
TEST(Vfrag, NonUtf8SourceNameIsEscaped) {
  std::vector<std::uint8_t> bytes;
  ASSERT_NO_THROW(bytes = EncodeVfrag(Sample(), {"\xFF.svm", 0, GridFit{7}}));
  Provenance meta;
  ASSERT_TRUE(DecodeVfrag(bytes, "mem.vfrag", &meta).ok());
  EXPECT_EQ(meta.source, "\\xFF.svm");
}

}  // namespace
}  // namespace svokit
