// .svopart (formats/svopart.md): parts written by real builds read back with their heads, their
// pages in key order with the page table's counts (those of the whole build by pages), shells
// exactly with bricks and the top contours in part 0 only; WriteSvoPart writes a read part's
// bytes again; and parts damaged by hand, their checksums made right again, are refused with one
// line naming the file.

#include "svokit/formats/svo/svo_part.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "svokit/formats/container/container.hpp"
#include "svokit/formats/mesh_import.hpp"
#include "svokit/formats/svo/svo_reader.hpp"
#include "svokit/pipeline/svo_by_pages.hpp"
#include "svokit/pipeline/svo_parts.hpp"
#include "svokit/svo/build_options.hpp"
#include "svokit/voxelize/voxelize.hpp"
#include "tests/test_meshes.hpp"
#include "tests/test_util.hpp"

namespace svokit {
namespace {

namespace fs = std::filesystem;

// A mesh ready to be built by pages at `resolution`.
struct Source {
  Mesh mesh;
  std::unique_ptr<RegionVoxelizer> regions;
};

std::unique_ptr<Source> MakeSource(Mesh mesh, std::uint32_t resolution, bool attributes) {
  auto source = std::make_unique<Source>();
  source->mesh = std::move(mesh);
  const StatusOr<GridTransform> grid =
      GridTransform::FitResolution(source->mesh.Bounds(), resolution);
  EXPECT_TRUE(grid.ok());
  VoxelizeOptions options;
  options.colors = options.normals = attributes;
  StatusOr<std::unique_ptr<RegionVoxelizer>> regions =
      RegionVoxelizer::Create(source->mesh, *grid, options);
  EXPECT_TRUE(regions.ok()) << regions.status().message();
  if (regions.ok()) source->regions = std::move(*regions);
  return source;
}

// The textured torus at 300 (depth 9, page level 2): 27 cells, no shared colour.
const Source& Torus(bool attributes) {
  static const auto make = [](bool with) {
    StatusOr<Mesh> mesh = ImportMesh(test::DataDir() / "uv-torus.obj");
    EXPECT_TRUE(mesh.ok()) << mesh.status().message();
    return MakeSource(mesh.ok() ? std::move(*mesh) : Mesh{}, 300, with);
  };
  static const std::unique_ptr<Source> with = make(true), without = make(false);
  return attributes ? *with : *without;
}

// A ball of one material: every voxel shares its colour.
const Source& Ball() {
  static const std::unique_ptr<Source> ball = MakeSource(test::Icosphere(3), 256, true);
  return *ball;
}

struct Case {
  std::string name;
  const Source* source;
  std::uint32_t bricks;
  bool contours;
  SvoCompression compression;
  std::uint32_t parts;
};

BuildOptions OptionsOf(const Case& c) {
  BuildOptions options;
  options.brick_side = c.bricks;
  options.contours = c.contours;
  return options;
}

constexpr std::uint64_t kIdentity = 0x1234'5678'9abc'def0;
const std::string kMeta = R"({"source":"part-test"})";

std::vector<fs::path> WriteParts(const Case& c, const test::TempDir& dir) {
  std::vector<fs::path> paths;
  for (std::uint32_t k = 0; k < c.parts; ++k) {
    paths.push_back(dir / (c.name + std::to_string(k) + ".svopart"));
    const StatusOr<SvoPartStats> made =
        BuildSvoPart(*c.source->regions, OptionsOf(c), kMeta, {k, c.parts, kIdentity}, paths.back(),
                     c.compression, 0);
    EXPECT_TRUE(made.ok()) << made.status().message();
  }
  return paths;
}

// The head every part of `c` has besides its share.
void ExpectHead(const SvoPartHead& head, const Case& c) {
  const RegionVoxelizer& regions = *c.source->regions;
  EXPECT_EQ(head.of.parts, c.parts);
  EXPECT_EQ(head.of.identity, kIdentity);
  EXPECT_LE(head.first, head.end);
  EXPECT_LE(head.end, head.cells);
  EXPECT_EQ(head.frame.grid, regions.grid());
  EXPECT_EQ(head.frame.mode, regions.options().mode);
  const SvoShape& shape = head.frame.shape;
  EXPECT_EQ(shape.depth, OctreeDepth(regions.grid()));
  EXPECT_EQ(shape.brick_side, c.bricks);
  EXPECT_EQ(shape.has_color, regions.options().colors);
  EXPECT_EQ(shape.has_normal, regions.options().normals);
  EXPECT_EQ(shape.has_contours, c.contours);
  EXPECT_FALSE(shape.solid);
  const std::optional<Rgba> shared = regions.shared_color();
  ASSERT_EQ(shape.shared_color.size(), shared ? 1u : 0u);
  if (shared) {
    EXPECT_EQ(shape.shared_color[0], HalfRgba(*shared));
  }
  EXPECT_EQ(head.frame.metadata, kMeta);
  EXPECT_EQ(head.compression, c.compression);
}

// Every part of `c` against the whole build by pages: the heads, the pages with their table's
// counts and sizes, the shells and the top contours.
void ExpectPartsOfTheBuild(const Case& c) {
  SCOPED_TRACE(c.name);
  test::TempDir dir;
  const std::vector<fs::path> paths = WriteParts(c, dir);
  const StatusOr<SvoFileStats> whole =
      BuildSvoByPages(*c.source->regions, OptionsOf(c), kMeta, dir / "whole.svo", c.compression, 0);
  ASSERT_TRUE(whole.ok()) << whole.status().message();
  const StatusOr<SvoReader> reader = SvoReader::Open(dir / "whole.svo");
  ASSERT_TRUE(reader.ok()) << reader.status().message();
  const std::uint32_t depth = reader->depth(), page_level = reader->page_level();
  ASSERT_GE(reader->page_count(), 4u);

  std::vector<std::uint64_t> keys;
  std::vector<std::array<std::uint64_t, 2>> level_counts(depth - page_level + 1, {0, 0});
  std::uint64_t previous_end = 0;
  for (std::uint32_t k = 0; k < c.parts; ++k) {
    SCOPED_TRACE("part " + std::to_string(k));
    const StatusOr<SvoPart> part = ReadSvoPart(paths[k]);
    ASSERT_TRUE(part.ok()) << part.status().message();
    EXPECT_EQ(part->name, paths[k].string());
    ExpectHead(part->head, c);
    EXPECT_EQ(part->head.of.part, k);
    EXPECT_EQ(part->head.first, previous_end);
    previous_end = part->head.end;
    if (k + 1 == c.parts) {
      EXPECT_EQ(part->head.end, part->head.cells);
    }

    std::uint64_t page_bytes = 0, shell_bytes = 0;
    for (const SvoPartPage& page : part->pages) {
      const std::size_t i = keys.size();
      ASSERT_LT(i, reader->page_count());
      EXPECT_TRUE(keys.empty() || page.key > keys.back()) << "keys not ascending";
      keys.push_back(page.key);
      EXPECT_EQ(page.key, reader->page(i).key);
      ASSERT_EQ(page.levels.size(), depth - page_level + 1);
      EXPECT_EQ(page.levels.back()[0], reader->page(i).voxels);
      for (std::size_t l = 0; l < page.levels.size(); ++l) {
        level_counts[l][0] += page.levels[l][0];
        level_counts[l][1] += page.levels[l][1];
        // Samples: above the voxels with bricks only.
        EXPECT_EQ(page.levels[l][2] > 0, c.bricks != 0 && l + 1 < page.levels.size()) << l;
      }
      EXPECT_EQ(page.offset, page_bytes);
      EXPECT_GT(page.size, 0u);
      StatusOr<std::vector<std::uint8_t>> bytes = part->PageBytes(page);
      ASSERT_TRUE(bytes.ok()) << bytes.status().message();
      EXPECT_EQ(bytes->size(), page.size);
      page_bytes += page.size;
      // Without bricks a page is stored as the .svo stores it.
      if (c.bricks == 0) {
        EXPECT_EQ(page.size, reader->page(i).stored_bytes);
      }
      EXPECT_EQ(page.shell_offset, shell_bytes);
      EXPECT_EQ(page.shell_size > 0, c.bricks != 0);
      shell_bytes += page.shell_size;
    }
    EXPECT_EQ(page_bytes, part->page_bytes.size);
    EXPECT_EQ(shell_bytes, part->shell_bytes.size);

    // The top levels' contour words: part 0's, with contours; every node of the whole tree's top
    // levels among them, with its word.
    if (k > 0 || !c.contours) {
      EXPECT_TRUE(part->top.empty());
      continue;
    }
    ASSERT_EQ(part->top.size(), page_level);
    const StatusOr<SvoChunk> top = reader->Top();
    ASSERT_TRUE(top.ok()) << top.status().message();
    for (std::uint32_t l = 0; l < page_level; ++l) {
      const SvoChunkLevel level = AssembleChunkLevel(*top, reader->shape(), l);
      ASSERT_FALSE(level.keys.empty());
      EXPECT_GE(part->top[l].size(), level.keys.size());
      for (std::size_t n = 0; n < level.keys.size(); ++n) {
        const auto it = part->top[l].find(level.keys[n]);
        ASSERT_NE(it, part->top[l].end()) << "level " << l << " key " << level.keys[n];
        EXPECT_EQ(it->second, level.contours[n]);
      }
    }
  }
  EXPECT_EQ(keys.size(), reader->page_count());
  for (std::uint32_t l = page_level; l <= depth; ++l) {
    EXPECT_EQ(level_counts[l - page_level][0], reader->NodeCount(l)) << "nodes of level " << l;
    EXPECT_EQ(level_counts[l - page_level][1], reader->ContourCount(l)) << "contours of " << l;
  }
}

TEST(SvoPart, PartsOfABuildReadBackWithTheirHeadsPagesShellsAndTopContours) {
  ExpectPartsOfTheBuild({"bricks", &Torus(true), 3, true, {true, 7}, 3});
  ExpectPartsOfTheBuild({"plain", &Torus(false), 0, false, {false, 3}, 2});
  ExpectPartsOfTheBuild({"plain-contours", &Torus(true), 0, true, {true, 1}, 4});
  ExpectPartsOfTheBuild({"shared", &Ball(), 2, true, {true, 3}, 2});
}

// A part's pages handed to WriteSvoPart as they were read.
SvoPartPages PagesOf(const SvoPart& part) {
  return [&part](const SvoPartPageSink& take) -> Status {
    for (const SvoPartPage& page : part.pages) {
      PagedSvoWriter::EncodedPage encoded;
      encoded.key = page.key;
      StatusOr<std::vector<std::uint8_t>> bytes = part.PageBytes(page);
      if (!bytes.ok()) return bytes.status();
      encoded.bytes = std::move(*bytes);
      encoded.levels = page.levels;
      StatusOr<std::vector<std::uint8_t>> shell = part.ShellBytes(page);
      if (!shell.ok()) return shell.status();
      SVOKIT_RETURN_IF_ERROR(take(std::move(encoded), std::move(*shell)));
    }
    return Status::Ok();
  };
}

TEST(SvoPart, WritingAReadPartAgainGivesItsBytes) {
  for (const Case& c : {Case{"bricks", &Torus(true), 3, true, {true, 7}, 2},
                        Case{"plain", &Torus(false), 0, false, {false, 3}, 2}}) {
    SCOPED_TRACE(c.name);
    test::TempDir dir;
    for (const fs::path& path : WriteParts(c, dir)) {
      const StatusOr<SvoPart> part = ReadSvoPart(path);
      ASSERT_TRUE(part.ok()) << part.status().message();
      ASSERT_FALSE(part->pages.empty());
      const fs::path again = dir / "again.svopart";
      ASSERT_TRUE(WriteSvoPart(again, part->head, part->top, PagesOf(*part)).ok());
      EXPECT_TRUE(test::ReadBytes(again) == test::ReadBytes(path)) << path.filename();
    }
  }
}

TEST(SvoPart, AFailingPageSourceLeavesNoFile) {
  test::TempDir dir;
  const Case c{"bricks", &Torus(true), 3, true, {true, 3}, 1};
  const StatusOr<SvoPart> part = ReadSvoPart(WriteParts(c, dir)[0]);
  ASSERT_TRUE(part.ok()) << part.status().message();
  const std::vector<std::string> before = dir.Files();
  const Status written = WriteSvoPart(dir / "failed.svopart", part->head, part->top,
                                      [&](const SvoPartPageSink& take) -> Status {
                                        SVOKIT_RETURN_IF_ERROR(PagesOf(*part)(take));
                                        return Status::BadInput("the build stopped");
                                      });
  EXPECT_FALSE(written.ok());
  EXPECT_NE(written.message().find("the build stopped"), std::string::npos) << written.message();
  EXPECT_EQ(dir.Files(), before);
}

// ---------------------------------------------------------------------------------------------
// Parts damaged by hand: the container written again with one section changed, so every checksum
// holds and only the part's own checks can refuse it.

constexpr const char* kSectionOrder[] = {"GRID", "PART", "PAGE", "PTAB", "SHEL", "TOPC", "META"};

container::Tag TagOf(const char* name) {
  return {name[0], name[1], name[2], name[3]};
}

/// A change to a section's bytes; false drops the section.
using Change = std::function<bool(std::vector<std::uint8_t>&)>;

// `from`'s sections, `change` applied to `section`'s, written to `to` as format `version`.
void Rewrite(const fs::path& from, const fs::path& to, const char* section, const Change& change,
             std::uint32_t version = kSvoPartFormat.version) {
  const StatusOr<container::Reader> file = container::Reader::Open(from, kSvoPartFormat);
  ASSERT_TRUE(file.ok()) << file.status().message();
  container::FormatId format = kSvoPartFormat;
  format.version = version;
  container::Writer writer(format, 0);
  for (const char* name : kSectionOrder) {
    const std::optional<std::span<const std::uint8_t>> bytes = file->Find(TagOf(name));
    ASSERT_TRUE(bytes) << name;
    std::vector<std::uint8_t> copy(bytes->begin(), bytes->end());
    if (std::string(name) == section && !change(copy)) continue;
    writer.AddSection(TagOf(name), std::move(copy));
  }
  ASSERT_TRUE(writer.WriteFile(to).ok());
}

// The section `grow` bytes longer (zeros) or, negative, shorter.
Change Resized(std::int64_t grow) {
  return [grow](std::vector<std::uint8_t>& bytes) {
    bytes.resize(static_cast<std::size_t>(static_cast<std::int64_t>(bytes.size()) + grow));
    return true;
  };
}

// The T at `offset` replaced by `value` of what it was.
template <class T>
Change Replaced(std::size_t offset, std::function<T(T)> value) {
  return [offset, value](std::vector<std::uint8_t>& bytes) {
    T v{};
    std::memcpy(&v, bytes.data() + offset, sizeof(T));
    v = value(v);
    std::memcpy(bytes.data() + offset, &v, sizeof(T));
    return true;
  };
}

template <class T>
Change Set(std::size_t offset, T value) {
  return Replaced<T>(offset, [value](T) { return value; });
}

TEST(SvoPart, DamagedPartsAreRefusedWithOneLineNamingTheFile) {
  test::TempDir dir;
  const Case c{"bricks", &Torus(true), 3, true, {true, 3}, 3};
  const std::vector<fs::path> parts = WriteParts(c, dir);
  const fs::path first = parts[0], middle = parts[1];
  const StatusOr<SvoPart> read = ReadSvoPart(middle);
  ASSERT_TRUE(read.ok()) << read.status().message();
  ASSERT_GE(read->pages.size(), 2u);
  const std::uint64_t entry = 24 + 24 * read->pages[0].levels.size();

  // Written again unchanged: the same bytes.
  Rewrite(middle, dir / "same.svopart", "PART", Resized(0));
  ASSERT_TRUE(test::ReadBytes(dir / "same.svopart") == test::ReadBytes(middle));

  // The same bytes labelled version 2: its bricks would be by the older filter.
  Rewrite(middle, dir / "v2.svopart", "PART", Resized(0), 2);
  const StatusOr<SvoPart> v2 = ReadSvoPart(dir / "v2.svopart");
  ASSERT_FALSE(v2.ok());
  EXPECT_NE(v2.status().message().find("v2.svopart: a version-2 part"), std::string::npos)
      << v2.status().message();

  const auto expect_refused = [&](const fs::path& from, const char* section, const Change& change,
                                  const std::string& why) {
    SCOPED_TRACE(std::string(section) + ": " + why);
    const fs::path damaged = dir / "damaged.svopart";
    Rewrite(from, damaged, section, change);
    const StatusOr<SvoPart> part = ReadSvoPart(damaged);
    ASSERT_FALSE(part.ok());
    const std::string& message = part.status().message();
    EXPECT_EQ(part.status().code(), StatusCode::kBadInput);
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    EXPECT_NE(message.find(damaged.string()), std::string::npos) << message;
    EXPECT_NE(message.find(why), std::string::npos) << message;
  };
  // PART (formats/svopart.md): flags 8 (the .svo's shared-colour bit), 32 and 2^31 are no part's
  // flags; part ≥ parts; no parts; first > end; end > cells; another depth; brick sides but 0, 2
  // and 3; a field short.
  const std::string inconsistent = "the part's header is inconsistent";
  for (const std::uint32_t flag : {8u, 32u, 1u << 31}) {
    expect_refused(middle, "PART",
                   Replaced<std::uint32_t>(48, [=](std::uint32_t f) { return f | flag; }),
                   inconsistent);
  }
  expect_refused(middle, "PART", Set<std::uint32_t>(0, 3), inconsistent);
  expect_refused(middle, "PART", Set<std::uint32_t>(0, 7), inconsistent);
  expect_refused(middle, "PART", Set<std::uint32_t>(4, 0), inconsistent);
  expect_refused(middle, "PART", Set<std::uint32_t>(4, 1), inconsistent);
  expect_refused(middle, "PART", Set<std::uint64_t>(24, read->head.end + 1), inconsistent);
  expect_refused(middle, "PART", Set<std::uint64_t>(32, read->head.cells + 1), inconsistent);
  expect_refused(middle, "PART", Set<std::uint32_t>(40, read->head.frame.depth() + 1),
                 inconsistent);
  for (const std::uint32_t side : {1u, 4u, 5u}) {
    expect_refused(middle, "PART", Set<std::uint32_t>(44, side), inconsistent);
  }
  expect_refused(middle, "PART", Resized(-4), "PART is truncated");

  // PTAB: short of an entry's last bytes or of a whole entry, a page's or shell's size off by
  // one, a key repeated.
  const std::string unfilled = "the page table does not fill the pages";
  expect_refused(middle, "PTAB", Resized(-8), "PTAB is truncated");
  expect_refused(middle, "PTAB", Resized(-static_cast<std::int64_t>(entry)), unfilled);
  expect_refused(middle, "PTAB", Replaced<std::uint64_t>(8, [](std::uint64_t n) { return n + 1; }),
                 unfilled);
  expect_refused(middle, "PTAB", Replaced<std::uint64_t>(16, [](std::uint64_t n) { return n + 1; }),
                 unfilled);
  expect_refused(middle, "PTAB", Set<std::uint64_t>(entry, read->pages[0].key),
                 "page keys are not ascending");
  // PAGE and SHEL longer than the table says.
  expect_refused(middle, "PAGE", Resized(1), unfilled);
  expect_refused(middle, "SHEL", Resized(1), unfilled);
  // TOPC: words in a part other than 0; a word too many or too few in part 0.
  expect_refused(middle, "TOPC", Resized(12), "the top contours are inconsistent");
  expect_refused(first, "TOPC", Resized(12), "the top contours are inconsistent");
  expect_refused(first, "TOPC", Resized(-12), "TOPC is truncated");
  // A required section missing.
  for (const char* section : kSectionOrder) {
    expect_refused(
        middle, section, [](std::vector<std::uint8_t>&) { return false; },
        std::string("required section '") + section + "' is missing");
  }
  // A byte of PAGE or SHEL changed behind its checksum: they are read with pread, not mapped,
  // and their checksums still hold them.
  for (const char* section : {"PAGE", "SHEL"}) {
    SCOPED_TRACE(section);
    const StatusOr<container::Frame> frame = container::Frame::Open(middle, kSvoPartFormat);
    ASSERT_TRUE(frame.ok());
    const container::Frame::Section* s = frame->Find(TagOf(section));
    ASSERT_NE(s, nullptr);
    ASSERT_GT(s->size, 0u);
    std::vector<std::uint8_t> bytes = test::ReadBytes(middle);
    bytes[s->offset + s->size / 2] ^= 0x40;
    const fs::path damaged = dir / "flipped.svopart";
    std::ofstream(damaged, std::ios::binary)
        .write(reinterpret_cast<const char*>(bytes.data()),
               static_cast<std::streamsize>(bytes.size()));
    const StatusOr<SvoPart> part = ReadSvoPart(damaged);
    ASSERT_FALSE(part.ok());
    EXPECT_EQ(part.status().message(),
              damaged.string() + ": section '" + section + "' checksum mismatch (file is corrupt)");
  }
}

}  // namespace
}  // namespace svokit
