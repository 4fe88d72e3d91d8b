// Version 2 of .svo: the file of an octree reads back as that octree (bricks assembled equal to
// what version 1 stored) for every brick option, attribute and compression, whatever the thread
// count; pages load alone and by box; and every damaged byte, truncation or damaged stream is an
// error naming the file (and the page), never a crash or a wrong octree.

#include "svokit/formats/svo/svo_file.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <set>

#include "svokit/core/crc32c.hpp"
#include "svokit/core/key_gaps.hpp"
#include "svokit/core/morton.hpp"
#include "svokit/core/thread_limit.hpp"
#include "svokit/formats/mesh_import.hpp"
#include "svokit/formats/svo/svo_chunk.hpp"
#include "svokit/formats/svo/svo_reader.hpp"
#include "svokit/svo/build_options.hpp"
#include "svokit/svo/compact_build.hpp"
#include "svokit/svo/compact_svo.hpp"
#include "svokit/voxelize/voxelize.hpp"
#include "tests/formats/svo_v1_writer.hpp"
#include "tests/test_util.hpp"

namespace svokit {
namespace {

struct Built {
  Mesh mesh;
  VoxelSet voxels;
  CompactSvo svo;
};

Built Build(const std::filesystem::path& mesh_path, std::uint32_t resolution,
            std::uint32_t side = 3, bool attributes = true, bool contours = true) {
  Built b;
  auto mesh = ImportMesh(mesh_path);
  EXPECT_TRUE(mesh.ok()) << mesh.status().message();
  b.mesh = std::move(*mesh);
  auto grid = GridTransform::FitResolution(b.mesh.Bounds(), resolution);
  VoxelizeOptions vo;
  vo.colors = vo.normals = attributes;
  auto voxels = Voxelize(b.mesh, *grid, vo);
  EXPECT_TRUE(voxels.ok());
  b.voxels = std::move(*voxels);
  BuildOptions bo;
  bo.brick_side = side;
  bo.contours = contours;
  auto svo = BuildCompactSvo(b.voxels, &b.mesh, bo, R"({"source":"test"})");
  EXPECT_TRUE(svo.ok());
  b.svo = std::move(*svo);
  return b;
}

const Built& Torus() {
  static const Built b = Build(test::DataDir() / "uv-torus.obj", 64);
  return b;
}

// The torus over several pages (pages are 128³ voxels).
const Built& PagedTorus() {
  static const Built b = Build(test::DataDir() / "uv-torus.obj", 256);
  return b;
}

TEST(SvoFileV2, ReadsBackAsTheOctreeForEveryOption) {
  struct Case {
    std::filesystem::path mesh;
    std::uint32_t resolution, side;
    bool attributes, contours;
  };
  const std::vector<Case> cases = {
      {test::DataDir() / "uv-torus.obj", 64, 3, true, true},  // textured: colours per voxel
      {test::DataDir() / "uv-torus.obj", 64, 2, true, false},
      {test::DataDir() / "uv-torus.obj", 40, 0, false, true},
      {test::DataDir() / "box-room.obj", 48, 3, true, true},  // materials, shared colours
      {test::DataDir() / "tetra.off", 1, 3, true, true},      // one voxel
      {test::DataDir() / "tetra.off", 200, 3, false, false},  // many pages, no attributes
  };
  for (const Case& c : cases) {
    const Built b = Build(c.mesh, c.resolution, c.side, c.attributes, c.contours);
    const Svo expected = AssembleSvo(b.svo);
    for (const SvoCompression& compression :
         {SvoCompression{}, SvoCompression{true, 19}, SvoCompression{false, 0}}) {
      SvoFileStats stats;
      const auto bytes = EncodeSvo(b.svo, compression, &stats);
      EXPECT_EQ(stats.file_bytes, bytes.size());
      auto back = DecodeSvo(bytes, "t.svo");
      ASSERT_TRUE(back.ok()) << back.status().message();
      EXPECT_TRUE(*back == expected) << c.mesh << " side " << c.side;
      auto lenient = DecodeSvoLenient(bytes, "t.svo");
      ASSERT_TRUE(lenient.ok());
      EXPECT_TRUE(lenient->complete && lenient->issues.empty());
    }
  }
}

TEST(SvoFileV2, BytesDoNotDependOnTheThreadCount) {
  const Built& b = Torus();
  std::vector<std::uint8_t> one;
  {
    ThreadLimit limit(1);
    auto svo = BuildCompactSvo(b.voxels, &b.mesh, {});
    one = EncodeSvo(*svo);
  }
  ThreadLimit limit(2);
  auto svo = BuildCompactSvo(b.voxels, &b.mesh, {});
  EXPECT_TRUE(EncodeSvo(*svo) == one);
}

// The top levels alone, or down to any level: the same levels as the whole file's.
TEST(SvoFileV2, LevelsDownToAnyLevel) {
  const Built& b = Torus();
  const auto bytes = EncodeSvo(b.svo);
  auto whole = DecodeSvo(bytes, "t.svo");
  ASSERT_TRUE(whole.ok());
  for (std::uint32_t k = 0; k <= b.svo.depth(); ++k) {
    auto top = DecodeSvo(bytes, "t.svo", k);
    ASSERT_TRUE(top.ok()) << k << ": " << top.status().message();
    ASSERT_EQ(top->levels.size(), k + 1);
    for (std::uint32_t l = 0; l <= k; ++l) {
      EXPECT_TRUE(top->levels[l] == whole->levels[l]) << "level " << l << " of " << k;
    }
  }
}

// Loading every page gives the whole tree: each level is the pages' parts in page order.
TEST(SvoReader, EveryPageTogetherIsTheWholeTree) {
  const Built& b = PagedTorus();
  const auto bytes = EncodeSvo(b.svo);
  auto reader = SvoReader::FromBytes(bytes, "t.svo");
  ASSERT_TRUE(reader.ok()) << reader.status().message();
  ASSERT_GT(reader->page_count(), 1u);
  const Svo whole = AssembleSvo(b.svo);
  const std::uint32_t p = reader->page_level();
  for (std::uint32_t level = p; level <= whole.depth; ++level) {
    SvoLevel joined;
    std::vector<std::uint32_t> contours;
    for (std::size_t i = 0; i < reader->page_count(); ++i) {
      auto page = reader->Page(i);
      ASSERT_TRUE(page.ok()) << page.status().message();
      const SvoChunkLevel part = AssembleChunkLevel(*page, reader->shape(), level);
      joined.opacity.insert(joined.opacity.end(), part.bricks.opacity.begin(),
                            part.bricks.opacity.end());
      joined.color.insert(joined.color.end(), part.bricks.color.begin(), part.bricks.color.end());
      joined.normal.insert(joined.normal.end(), part.bricks.normal.begin(),
                           part.bricks.normal.end());
      for (const std::uint32_t w : part.contours) {
        if (w != 0) contours.push_back(w);
      }
    }
    const SvoLevel& want = whole.levels[level];
    EXPECT_EQ(joined.opacity, want.opacity) << level;
    EXPECT_EQ(joined.color, want.color) << level;
    EXPECT_EQ(joined.normal, want.normal) << level;
    EXPECT_EQ(contours, want.contours) << level;
  }
  auto top = reader->Top();
  ASSERT_TRUE(top.ok());
  for (std::uint32_t level = 0; level < p; ++level) {
    const SvoChunkLevel part = AssembleChunkLevel(*top, reader->shape(), level);
    EXPECT_EQ(part.bricks.opacity, whole.levels[level].opacity) << level;
    EXPECT_EQ(part.keys, whole.LevelKeys(level)) << level;
  }
}

// Without bricks the voxels' own colours and normals are still the file's, page by page, and
// no page carries a halo (it exists for the voxel bricks).
TEST(SvoReader, BricksNoneKeepsTheVoxelsAttributes) {
  const Built b = Build(test::DataDir() / "uv-torus.obj", 96, 0, true, false);
  ASSERT_TRUE(b.voxels.has_colors() && b.voxels.colors.size() > 1 && b.voxels.has_normals());
  const auto bytes = EncodeSvo(b.svo);
  auto reader = SvoReader::FromBytes(bytes, "t.svo");
  ASSERT_TRUE(reader.ok()) << reader.status().message();
  EXPECT_TRUE(reader->shape().has_color && reader->shape().has_normal);
  EXPECT_EQ(reader->shape().brick_side, 0u);
  std::size_t voxel = 0;
  for (std::size_t i = 0; i < reader->page_count(); ++i) {
    auto page = reader->Page(i);
    ASSERT_TRUE(page.ok()) << page.status().message();
    EXPECT_TRUE(page->halo_keys.empty());
    ASSERT_EQ(page->colors.size(), page->normals.size());
    for (std::size_t v = 0; v < page->colors.size(); ++v, ++voxel) {
      ASSERT_LT(voxel, b.voxels.size());
      EXPECT_TRUE(page->colors[v] == b.voxels.color(voxel)) << voxel;
      EXPECT_EQ(page->normals[v].bits, b.voxels.normals[voxel].bits) << voxel;
    }
  }
  EXPECT_EQ(voxel, b.voxels.size());
}

// The pages a box selects hold exactly the tree's voxels inside the box (and others of their
// pages): random boxes, against a filter of all the voxels.
TEST(SvoReader, PagesInABoxHoldTheVoxelsInsideIt) {
  const Built b = Build(test::DataDir() / "uv-torus.obj", 128);
  const auto bytes = EncodeSvo(b.svo);
  auto reader = SvoReader::FromBytes(bytes, "t.svo");
  ASSERT_TRUE(reader.ok());
  const GridTransform& g = b.voxels.grid;
  const double h = g.voxel_size();
  std::mt19937 rng(3);
  const Box3d bounds = b.mesh.Bounds();
  std::uniform_real_distribution<double> ux(bounds.lo.x, bounds.hi.x), uy(bounds.lo.y, bounds.hi.y),
      uz(bounds.lo.z, bounds.hi.z);
  for (int trial = 0; trial < 20; ++trial) {
    Box3d box;
    box.Expand(Vec3d{ux(rng), uy(rng), uz(rng)});
    box.Expand(Vec3d{ux(rng), uy(rng), uz(rng)});
    std::set<std::uint64_t> inside, loaded;
    for (const std::uint64_t key : b.voxels.keys) {
      const MortonCoord c = MortonDecode(key);
      const Vec3d lo = g.origin() + Vec3d{c.x * h, c.y * h, c.z * h};
      if (lo.x + h >= box.lo.x && lo.x <= box.hi.x && lo.y + h >= box.lo.y && lo.y <= box.hi.y &&
          lo.z + h >= box.lo.z && lo.z <= box.hi.z) {
        inside.insert(key);
      }
    }
    for (const std::size_t i : reader->PagesIn(box)) {
      auto page = reader->Page(i);
      ASSERT_TRUE(page.ok());
      for (const std::uint64_t key : ChunkVoxelKeys(*page)) loaded.insert(key);
    }
    EXPECT_TRUE(std::includes(loaded.begin(), loaded.end(), inside.begin(), inside.end()))
        << "trial " << trial;
    // No page is loaded that has no voxel near the box: each selected page's cube meets it.
    for (const std::size_t i : reader->PagesIn(box)) {
      const Box3d p = reader->PageBox(i);
      EXPECT_TRUE(p.lo.x <= box.hi.x && box.lo.x <= p.hi.x);
    }
  }
}

// Every flipped byte of a file is detected: the strict reader refuses it with one line naming the
// file, and the lenient one lists an issue.
TEST(SvoFileV2, EveryFlippedByteIsDetected) {
  const Built b = Build(test::DataDir() / "tetra.off", 24);
  const auto clean = EncodeSvo(b.svo);
  ASSERT_LT(clean.size(), 20000u);
  for (std::size_t i = 0; i < clean.size(); ++i) {
    auto bytes = clean;
    bytes[i] ^= static_cast<std::uint8_t>(1u << (i % 8));
    auto r = DecodeSvo(bytes, "flip.svo");
    ASSERT_FALSE(r.ok()) << "flipped byte " << i << " not detected";
    EXPECT_EQ(r.status().message().rfind("flip.svo: ", 0), 0u) << r.status().message();
    EXPECT_EQ(r.status().message().find('\n'), std::string::npos);
    auto lenient = DecodeSvoLenient(bytes, "flip.svo");
    if (lenient.ok()) {
      EXPECT_FALSE(lenient->issues.empty()) << "byte " << i;
    }
  }
}

TEST(SvoFileV2, EveryTruncationIsDetected) {
  const Built b = Build(test::DataDir() / "tetra.off", 24);
  const auto clean = EncodeSvo(b.svo);
  for (std::size_t n = 0; n < clean.size(); ++n) {
    const std::vector<std::uint8_t> cut(clean.begin(),
                                        clean.begin() + static_cast<std::ptrdiff_t>(n));
    auto r = DecodeSvo(cut, "cut.svo");
    ASSERT_FALSE(r.ok()) << "truncated to " << n;
    EXPECT_EQ(r.status().message().rfind("cut.svo: ", 0), 0u) << r.status().message();
  }
}

// A page whose compressed stream is damaged is an error naming the page: by its checksum; and with
// every checksum made right again (another writer's bug, not a flipped bit), by the stream checks,
// or else it decodes to some consistent octree: never a crash.
TEST(SvoFileV2, ADamagedStreamIsAnErrorNamingThePage) {
  const Built& b = Torus();
  const auto clean = EncodeSvo(b.svo);
  auto reader = SvoReader::FromBytes(clean, "t.svo");
  ASSERT_TRUE(reader.ok());
  auto frame = container::Frame::FromBytes(clean, "t.svo", kSvoFormat);
  ASSERT_TRUE(frame.ok());
  const container::Frame::Section* pages = frame->Find(container::MakeTag("PAGE"));
  const container::Frame::Section* table = frame->Find(container::MakeTag("PTAB"));
  ASSERT_TRUE(pages && table);
  int refused = 0;
  std::mt19937 rng(5);
  for (int trial = 0; trial < 200; ++trial) {
    auto bytes = clean;
    const std::size_t page = rng() % reader->page_count();
    std::uint64_t offset;
    std::uint32_t size;
    std::memcpy(&offset, bytes.data() + table->offset + 32 * page + 8, 8);
    std::memcpy(&size, bytes.data() + table->offset + 32 * page + 16, 4);
    const std::size_t at = pages->offset + offset + rng() % size;
    bytes[at] ^= static_cast<std::uint8_t>(1 + rng() % 255);
    const std::string page_name = "t.svo: page " + std::to_string(page);
    // The page's checksum finds it (the container's does too, for the lenient reader).
    auto r = DecodeSvo(bytes, "t.svo");
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.status().message(), page_name + ": checksum mismatch (file is corrupt)");
    auto direct = SvoReader::FromBytes(bytes, "t.svo");
    ASSERT_TRUE(direct.ok());
    EXPECT_FALSE(direct->Page(page).ok());
    // Every checksum right again: the page's, PAGE's, PTAB's and the header's.
    const std::uint32_t crc = Crc32c(bytes.data() + pages->offset + offset, size);
    std::memcpy(bytes.data() + table->offset + 32 * page + 20, &crc, 4);
    for (std::size_t e = 0; e < frame->sections().size(); ++e) {
      const container::Frame::Section& s = frame->sections()[e];
      if (s.tag != pages->tag && s.tag != table->tag) continue;
      const std::uint32_t c = Crc32c(bytes.data() + s.offset, s.size);
      std::memcpy(bytes.data() + container::kHeaderSize + e * container::kSectionEntrySize + 24, &c,
                  4);
    }
    std::uint32_t head = Crc32c(bytes.data(), 28);
    head = Crc32c(bytes.data() + container::kHeaderSize,
                  frame->sections().size() * container::kSectionEntrySize, head);
    std::memcpy(bytes.data() + 28, &head, 4);
    r = DecodeSvo(bytes, "t.svo");
    if (r.ok()) continue;  // another octree, consistent: the data changed, the checks hold
    ++refused;
    EXPECT_EQ(r.status().message().rfind(page_name + ": ", 0), 0u) << r.status().message();
  }
  EXPECT_GT(refused, 0);  // the stream checks do find some (40 of 200 here)
}

// Stated sizes are refused before anything is allocated for them: one stream over 1 GiB, or a
// chunk whose streams add up to more than 4 GiB (five frames of 1 GiB, ~30 KB of zstd each,
// would otherwise be a decompression bomb).
TEST(SvoFileV2, StatedSizesBeyondTheLimitsAreRefusedFirst) {
  const auto chunk = [](std::vector<std::uint64_t> raw) {
    std::vector<std::uint8_t> bytes = {static_cast<std::uint8_t>(raw.size())};
    for (std::size_t i = 0; i < raw.size(); ++i) {
      std::uint8_t varint[10];
      bytes.push_back(static_cast<std::uint8_t>(i + 1));  // kinds 1, 2, …
      bytes.push_back(1);                                 // zstd
      bytes.insert(bytes.end(), varint, varint + PutVarint(raw[i], varint));
      bytes.insert(bytes.end(), varint, varint + PutVarint(4, varint));
    }
    bytes.resize(bytes.size() + 4 * raw.size(), 0);
    return bytes;
  };
  SvoShape shape;
  shape.depth = 4;
  const ChunkFrame frame{0, 0, 4, false};
  const std::uint64_t gib = std::uint64_t{1} << 30;
  auto one = DecodeChunk(chunk({gib + 1}), shape, frame, "t.svo: top chunk");
  ASSERT_FALSE(one.ok());
  EXPECT_NE(one.status().message().find("a stream may hold"), std::string::npos)
      << one.status().message();
  auto five = DecodeChunk(chunk({gib, gib, gib, gib, gib}), shape, frame, "t.svo: top chunk");
  ASSERT_FALSE(five.ok());
  EXPECT_NE(five.status().message().find("a chunk may hold"), std::string::npos)
      << five.status().message();
  // Within the limits, the same garbage is refused as a stream that does not decompress.
  auto small = DecodeChunk(chunk({64}), shape, frame, "t.svo: top chunk");
  ASSERT_FALSE(small.ok());
  EXPECT_NE(small.status().message().find("does not decompress"), std::string::npos)
      << small.status().message();
}

TEST(SvoFileV2, VersionOneFilesStillRead) {
  const Built& b = Torus();
  const Svo svo = AssembleSvo(b.svo);
  auto back = DecodeSvo(test::EncodeSvoV1(svo), "old.svo");
  ASSERT_TRUE(back.ok()) << back.status().message();
  EXPECT_TRUE(*back == svo);
  auto reader = SvoReader::FromBytes(test::EncodeSvoV1(svo), "old.svo");
  ASSERT_FALSE(reader.ok());
  EXPECT_NE(reader.status().message().find("no pages"), std::string::npos);
}

// By level, each kind of array's bytes add up to its file-wide figures exactly, and the decoded
// bytes land where the octree puts them: one mask byte per node above the voxels, one opacity
// byte per distinct sample, the voxels' own normals on the voxel level only.
TEST(SvoReader, FileStatsByLevelSplitEachKindOfArrayExactly) {
  for (const bool zstd : {true, false}) {
    const Built& b = PagedTorus();
    SvoCompression compression;
    compression.zstd = zstd;
    const auto bytes = EncodeSvo(b.svo, compression);
    auto reader = SvoReader::FromBytes(bytes, "t.svo");
    ASSERT_TRUE(reader.ok()) << reader.status().message();
    ASSERT_GT(reader->page_count(), 1u);
    const auto whole = reader->FileStats();
    const auto split = reader->FileStats(true);
    ASSERT_TRUE(whole.ok() && split.ok());
    EXPECT_TRUE(whole->levels.empty());
    const std::uint32_t depth = b.svo.depth();
    ASSERT_EQ(split->levels.size(), depth + 1);
    ASSERT_EQ(split->sections.size(), whole->sections.size());
    const auto at = [&](std::uint32_t level, const std::string& name) {
      for (const SvoSectionBytes& s : split->levels[level]) {
        if (s.name == name) return s;
      }
      return SvoSectionBytes{name, 0, 0};
    };
    for (std::size_t k = 0; k < whole->sections.size(); ++k) {
      const SvoSectionBytes& sec = whole->sections[k];
      EXPECT_EQ(split->sections[k].name, sec.name);
      EXPECT_EQ(split->sections[k].stored, sec.stored);
      if (sec.name == "frame") continue;
      std::uint64_t stored = 0, raw = 0;
      for (std::uint32_t l = 0; l <= depth; ++l) {
        stored += at(l, sec.name).stored;
        raw += at(l, sec.name).raw;
        EXPECT_LE(at(l, sec.name).stored, sec.stored);
      }
      EXPECT_EQ(stored, sec.stored) << sec.name;
      EXPECT_EQ(raw, sec.raw) << sec.name;
      if (!zstd) {
        EXPECT_EQ(stored, raw) << sec.name;
      }
    }
    // Samples stored per level: the top chunk's, then each page's (a page also stores the samples
    // on its border that a neighbouring page holds too).
    std::vector<std::uint64_t> samples(depth + 1, 0);
    for (std::size_t c = 0; c <= reader->page_count(); ++c) {
      auto chunk = c == 0 ? reader->Top() : reader->Page(c - 1);
      ASSERT_TRUE(chunk.ok());
      for (std::size_t k = 0; k < chunk->samples.size(); ++k) {
        samples[chunk->root_level + k] += chunk->samples[k].opacity.size();
      }
    }
    for (std::uint32_t l = 0; l < depth; ++l) {
      EXPECT_EQ(at(l, "masks").raw, b.svo.NodeCount(l)) << l;
      EXPECT_EQ(at(l, "opacity").raw, samples[l]) << l;
      EXPECT_GE(samples[l], b.svo.whole.layouts[l].size()) << l;
      EXPECT_EQ(at(l, "voxel normals").raw, 0u) << l;
      EXPECT_GT(at(l, "contours").raw, 0u) << l;
    }
    EXPECT_EQ(at(depth, "masks").raw, 0u);
    EXPECT_EQ(at(depth, "opacity").raw, 0u);
    EXPECT_EQ(at(depth, "voxel normals").raw, 4 * b.svo.voxel_count());
    EXPECT_GT(at(depth, "halo").raw, 0u);
  }
}

TEST(SvoFileV2, WriteReplacesAndReportsTheFile) {
  test::TempDir dir;
  const Built& b = Torus();
  auto stats = WriteSvo(b.svo, dir / "t.svo");
  ASSERT_TRUE(stats.ok()) << stats.status().message();
  EXPECT_EQ(stats->file_bytes, std::filesystem::file_size(dir / "t.svo"));
  EXPECT_TRUE(test::ReadBytes(dir / "t.svo") == EncodeSvo(b.svo));
  std::uint64_t sum = 0;
  for (const SvoSectionBytes& s : stats->sections) sum += s.stored;
  EXPECT_EQ(sum, stats->file_bytes);
  EXPECT_FALSE(WriteSvo(b.svo, dir / "missing" / "t.svo").ok());
  EXPECT_EQ(dir.Files(), std::vector<std::string>{"t.svo"});
}

}  // namespace
}  // namespace svokit
