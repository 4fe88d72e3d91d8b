// svo-merge against parts a careless or hostile producer wrote: real parts of a real mesh, each
// decoded into its sections, pages, streams and shells, one structured field changed (a mask bit,
// a count, an offset, a level's length, a zstd level, an index, a provenance field, pages swapped
// or dropped, an array truncated) and written again through the container's own writer, so every
// checksum holds. Each mutant is merged with the other parts: the merge refuses it (bad input,
// one line naming the part, no output), or what it writes passes svo-validate's checks.
// SVOKIT_MERGE_MUTANTS sets the count (default 100; the `slow` run takes 500), the seed is fixed.

#include <gtest/gtest.h>
#include <zstd.h>

#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "svokit/core/key_gaps.hpp"
#include "svokit/formats/container/container.hpp"
#include "svokit/formats/mesh_import.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/formats/svo/svo_part.hpp"
#include "svokit/pipeline/svo_parts.hpp"
#include "svokit/svo/build_options.hpp"
#include "svokit/svo/page_borders.hpp"
#include "svokit/validate/validate.hpp"
#include "svokit/voxelize/voxelize.hpp"
#include "tests/test_util.hpp"

namespace svokit {
namespace {

namespace fs = std::filesystem;
using Bytes = std::vector<std::uint8_t>;

template <class T>
T Load(const Bytes& b, std::size_t at) {
  T v{};
  std::memcpy(&v, b.data() + at, sizeof(T));
  return v;
}
template <class T>
void Store(Bytes& b, std::size_t at, T v) {
  std::memcpy(b.data() + at, &v, sizeof(T));
}

// A chunk's streams (formats/svo.md, "Chunks"), decompressed.
struct Stream {
  std::uint8_t kind = 0;
  Bytes bytes;
};

std::optional<std::vector<Stream>> ParseChunk(const Bytes& chunk) {
  if (chunk.empty()) return std::nullopt;
  const std::uint8_t* p = chunk.data() + 1;
  const std::uint8_t* end = chunk.data() + chunk.size();
  struct Entry {
    std::uint8_t kind, codec;
    std::uint64_t decoded, stored;
  };
  std::vector<Entry> entries(chunk[0]);
  for (Entry& e : entries) {
    if (end - p < 2) return std::nullopt;
    e.kind = *p++;
    e.codec = *p++;
    if (!GetVarint(p, end, e.decoded) || !GetVarint(p, end, e.stored)) return std::nullopt;
  }
  std::vector<Stream> streams;
  for (const Entry& e : entries) {
    if (static_cast<std::uint64_t>(end - p) < e.stored) return std::nullopt;
    Stream& s = streams.emplace_back();
    s.kind = e.kind;
    s.bytes.resize(e.decoded);
    if (e.codec == 0) {
      s.bytes.assign(p, p + e.stored);
    } else if (ZSTD_decompress(s.bytes.data(), s.bytes.size(), p, e.stored) != e.decoded) {
      return std::nullopt;
    }
    p += e.stored;
  }
  return streams;
}

// The streams stored as they are (codec 0), as `--compression none` writes them.
Bytes StoreChunk(const std::vector<Stream>& streams) {
  Bytes out{static_cast<std::uint8_t>(streams.size())};
  std::uint8_t varint[kMaxVarintBytes];
  for (const Stream& s : streams) {
    out.push_back(s.kind);
    out.push_back(0);
    for (int twice = 0; twice < 2; ++twice) {
      const std::size_t n = PutVarint(s.bytes.size(), varint);
      out.insert(out.end(), varint, varint + n);
    }
  }
  for (const Stream& s : streams) out.insert(out.end(), s.bytes.begin(), s.bytes.end());
  return out;
}

// A part taken apart: its sections, PAGE and SHEL split per page as PTAB says.
struct PartParts {
  Bytes grid, head, top, meta;
  struct Page {
    Bytes entry;  // its PTAB entry; bytes 8 .. 24 (sizes) follow the blobs when written
    Bytes chunk, shell;
  };
  std::vector<Page> pages;
};

PartParts TakeApart(const fs::path& path) {
  PartParts parts;
  const StatusOr<container::Reader> file = container::Reader::Open(path, kSvoPartFormat);
  EXPECT_TRUE(file.ok()) << file.status().message();
  const auto section = [&](const char(&tag)[5]) {
    const auto bytes = file->Find(container::MakeTag(tag));
    EXPECT_TRUE(bytes.has_value()) << tag;
    return bytes ? Bytes(bytes->begin(), bytes->end()) : Bytes{};
  };
  parts.grid = section("GRID");
  parts.head = section("PART");
  parts.top = section("TOPC");
  parts.meta = section("META");
  const Bytes table = section("PTAB"), pages = section("PAGE"), shells = section("SHEL");
  const StatusOr<SvoPart> read = ReadSvoPart(path);
  EXPECT_TRUE(read.ok()) << read.status().message();
  const std::size_t entry = table.size() / std::max<std::size_t>(1, read->pages.size());
  for (std::size_t i = 0; i < read->pages.size(); ++i) {
    const SvoPartPage& page = read->pages[i];
    PartParts::Page& p = parts.pages.emplace_back();
    p.entry.assign(table.begin() + static_cast<std::ptrdiff_t>(i * entry),
                   table.begin() + static_cast<std::ptrdiff_t>((i + 1) * entry));
    p.chunk.assign(pages.begin() + static_cast<std::ptrdiff_t>(page.offset),
                   pages.begin() + static_cast<std::ptrdiff_t>(page.offset + page.size));
    p.shell.assign(
        shells.begin() + static_cast<std::ptrdiff_t>(page.shell_offset),
        shells.begin() + static_cast<std::ptrdiff_t>(page.shell_offset + page.shell_size));
  }
  return parts;
}

// Written through the container's writer: every checksum right. With `sizes`, each PTAB entry's
// sizes are its blobs' (a producer that writes its table from what it wrote).
void PutTogether(const PartParts& parts, const fs::path& path, bool sizes) {
  Bytes table, pages, shells;
  for (PartParts::Page p : parts.pages) {
    if (sizes && p.entry.size() >= 24) {
      Store<std::uint64_t>(p.entry, 8, p.chunk.size());
      Store<std::uint64_t>(p.entry, 16, p.shell.size());
    }
    table.insert(table.end(), p.entry.begin(), p.entry.end());
    pages.insert(pages.end(), p.chunk.begin(), p.chunk.end());
    shells.insert(shells.end(), p.shell.begin(), p.shell.end());
  }
  container::Writer writer(kSvoPartFormat, 0);
  writer.AddSection(container::MakeTag("GRID"), parts.grid);
  writer.AddSection(container::MakeTag("PART"), parts.head);
  writer.AddSection(container::MakeTag("PAGE"), pages);
  writer.AddSection(container::MakeTag("PTAB"), table);
  writer.AddSection(container::MakeTag("SHEL"), shells);
  writer.AddSection(container::MakeTag("TOPC"), parts.top);
  writer.AddSection(container::MakeTag("META"), parts.meta);
  ASSERT_TRUE(writer.WriteFile(path).ok());
}

// One build cut into parts, written once per test run.
struct Build {
  std::string name;
  std::vector<fs::path> parts;
  std::vector<PartParts> taken;
  std::vector<SvoPart> read;
};

std::unique_ptr<Build> MakeBuild(const test::TempDir& dir, const std::string& name,
                                 std::uint32_t bricks, bool attributes, SvoCompression compression,
                                 std::uint32_t count) {
  auto build = std::make_unique<Build>();
  build->name = name;
  static const StatusOr<Mesh> mesh = ImportMesh(test::DataDir() / "uv-torus.obj");
  EXPECT_TRUE(mesh.ok()) << mesh.status().message();
  const StatusOr<GridTransform> grid = GridTransform::FitResolution(mesh->Bounds(), 300);
  EXPECT_TRUE(grid.ok());
  VoxelizeOptions voxelize;
  voxelize.colors = voxelize.normals = attributes;
  StatusOr<std::unique_ptr<RegionVoxelizer>> regions =
      RegionVoxelizer::Create(*mesh, *grid, voxelize);
  EXPECT_TRUE(regions.ok()) << regions.status().message();
  BuildOptions options;
  options.brick_side = bricks;
  options.contours = true;
  for (std::uint32_t k = 0; k < count; ++k) {
    build->parts.push_back(dir / (name + "-" + std::to_string(k) + ".svopart"));
    const StatusOr<SvoPartStats> made =
        BuildSvoPart(**regions, options, R"({"source":"mutants"})", {k, count, 0x5eed},
                     build->parts.back(), compression, 0);
    EXPECT_TRUE(made.ok()) << made.status().message();
    build->taken.push_back(TakeApart(build->parts.back()));
    StatusOr<SvoPart> read = ReadSvoPart(build->parts.back());
    EXPECT_TRUE(read.ok()) << read.status().message();
    build->read.push_back(std::move(*read));
  }
  return build;
}

// Page `i` of `part` decoded, changed by `change` and encoded again with its shell made from it,
// as a producer that rewrites a page consistently would. False when `change` does not apply.
template <class Change>
bool Rewrite(PartParts& p, const SvoPart& part, std::size_t i, Change change) {
  StatusOr<SvoChunk> chunk = DecodeSvoPartPage(part, part.pages[i]);
  EXPECT_TRUE(chunk.ok()) << chunk.status().message();
  if (!chunk.ok() || !change(*chunk)) return false;
  p.pages[i].chunk = PagedSvoWriter(part.head.frame, {true, 1}).Encode(*chunk).bytes;
  p.pages[i].shell = EncodePageShell(*chunk, part.head.frame.shape);
  return true;
}

// One structured change to `p`, part `part` of its build as read; what it changed, for the
// report. False when it did not apply.
bool Mutate(PartParts& p, std::uint32_t part, const SvoPart& read, std::mt19937_64& rng,
            std::string& what, bool& sizes) {
  const auto pick = [&](std::uint64_t n) { return static_cast<std::size_t>(rng() % n); };
  // A field's new value: off by one, zero, all ones, a bit flipped, or random.
  const auto perturb = [&](std::uint64_t v, int bits) -> std::uint64_t {
    const std::uint64_t mask = bits == 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << bits) - 1;
    switch (pick(6)) {
      case 0:
        return (v + 1) & mask;
      case 1:
        return (v - 1) & mask;
      case 2:
        return 0;
      case 3:
        return mask;
      case 4:
        return v ^ (std::uint64_t{1} << pick(static_cast<std::uint64_t>(bits)));
      default:
        return rng() & mask;
    }
  };
  const auto field = [&](Bytes& b, std::size_t at, int bits, const std::string& name) {
    if (at + static_cast<std::size_t>(bits / 8) > b.size()) return false;
    if (bits == 32) {
      const auto old = Load<std::uint32_t>(b, at);
      const auto v = static_cast<std::uint32_t>(perturb(old, 32));
      Store<std::uint32_t>(b, at, v);
      what = fmt::format("{} {} -> {}", name, old, v);
    } else {
      const auto old = Load<std::uint64_t>(b, at);
      const auto v = perturb(old, 64);
      Store<std::uint64_t>(b, at, v);
      what = fmt::format("{} {} -> {}", name, old, v);
    }
    return true;
  };
  const std::size_t pages = p.pages.size();
  switch (pick(13)) {
    case 0: {  // a PART field
      static constexpr std::pair<std::size_t, int> kFields[] = {
          {0, 32},  {4, 32},  {8, 64},  {16, 64}, {24, 64}, {32, 64}, {40, 32},
          {44, 32}, {48, 32}, {52, 64}, {60, 32}, {64, 32}, {68, 32}};
      const auto [at, bits] = kFields[pick(std::size(kFields))];
      return field(p.head, at, bits, fmt::format("PART@{}", at));
    }
    case 1: {  // the zstd level, out of range or in it
      const std::uint32_t level =
          static_cast<std::uint32_t>(std::vector<std::int64_t>{0, 23, 100, -1, -5, 1, 22}[pick(7)]);
      Store<std::uint32_t>(p.head, 68, level);
      what = fmt::format("zstd level {}", static_cast<std::int32_t>(level));
      return true;
    }
    case 2: {  // a GRID field (dims, origin, voxel size: 4- and 8-byte fields)
      const std::size_t at = 8 * pick(p.grid.size() / 8);
      return field(p.grid, at, pick(2) ? 64 : 32, fmt::format("GRID@{}", at));
    }
    case 3: {  // a provenance field of META
      if (p.meta.size() < 4) return false;
      const std::size_t at = 1 + pick(p.meta.size() - 2);
      p.meta[at] = static_cast<std::uint8_t>('a' + pick(26));
      what = fmt::format("META byte {}", at);
      return true;
    }
    case 4: {  // a PTAB field: key, sizes, a level's counts
      if (pages == 0) return false;
      const std::size_t i = pick(pages);
      const std::size_t at = 8 * pick(p.pages[i].entry.size() / 8);
      sizes = at >= 24 || at == 0 ? pick(2) == 0 : false;
      return field(p.pages[i].entry, at, 64, fmt::format("PTAB page {} @{}", i, at));
    }
    case 5: {  // a page's size moved to the next page's (offsets shift, the fill holds)
      if (pages < 2) return false;
      const std::size_t i = pick(pages - 1);
      const std::uint64_t d = 1 + pick(16);
      Store<std::uint64_t>(p.pages[i].entry, 8, Load<std::uint64_t>(p.pages[i].entry, 8) + d);
      Store<std::uint64_t>(p.pages[i + 1].entry, 8,
                           Load<std::uint64_t>(p.pages[i + 1].entry, 8) - d);
      sizes = false;
      what = fmt::format("page {} offset +{}", i + 1, d);
      return true;
    }
    case 6:
    case 7: {  // a stream of a page: a mask bit, a byte, an array truncated or grown
      if (pages == 0) return false;
      const std::size_t i = pick(pages);
      std::optional<std::vector<Stream>> streams = ParseChunk(p.pages[i].chunk);
      if (!streams || streams->empty()) return false;
      Stream& s = (*streams)[pick(streams->size())];
      if (s.bytes.empty()) return false;
      switch (pick(4)) {
        case 0: {
          const std::size_t at = pick(s.bytes.size());
          const unsigned bit = static_cast<unsigned>(pick(8));
          s.bytes[at] ^= static_cast<std::uint8_t>(1u << bit);
          what = fmt::format("page {} stream {} byte {} bit {} flipped", i, s.kind, at, bit);
          break;
        }
        case 1: {
          const std::size_t n = 1 + pick(std::min<std::size_t>(s.bytes.size(), 8));
          s.bytes.resize(s.bytes.size() - n);
          what = fmt::format("page {} stream {} {} bytes short", i, s.kind, n);
          break;
        }
        case 2: {
          const std::size_t n = 1 + pick(8);
          s.bytes.resize(s.bytes.size() + n, static_cast<std::uint8_t>(rng()));
          what = fmt::format("page {} stream {} {} bytes long", i, s.kind, n);
          break;
        }
        default: {
          const std::size_t at = pick(s.bytes.size());
          s.bytes[at] = static_cast<std::uint8_t>(rng());
          what = fmt::format("page {} stream {} byte {} replaced", i, s.kind, at);
        }
      }
      p.pages[i].chunk = StoreChunk(*streams);
      return true;
    }
    case 8: {  // two pages swapped: whole, or their bytes under the same keys
      if (pages < 2) return false;
      const std::size_t i = pick(pages), j = (i + 1 + pick(pages - 1)) % pages;
      if (pick(2)) {
        std::swap(p.pages[i], p.pages[j]);
        what = fmt::format("pages {} and {} swapped", i, j);
      } else {
        std::swap(p.pages[i].chunk, p.pages[j].chunk);
        std::swap(p.pages[i].shell, p.pages[j].shell);
        for (std::size_t at = 24; at < p.pages[i].entry.size(); ++at) {
          std::swap(p.pages[i].entry[at], p.pages[j].entry[at]);
        }
        what = fmt::format("pages {} and {} swapped under their keys", i, j);
      }
      return true;
    }
    case 9: {  // a page dropped or given twice
      if (pages == 0) return false;
      const std::size_t i = pick(pages);
      if (pick(2)) {
        p.pages.erase(p.pages.begin() + static_cast<std::ptrdiff_t>(i));
        what = fmt::format("page {} dropped", i);
      } else {
        p.pages.insert(p.pages.begin() + static_cast<std::ptrdiff_t>(i), p.pages[i]);
        what = fmt::format("page {} given twice", i);
      }
      return true;
    }
    case 10: {  // a shell: a byte changed, truncated
      if (pages == 0) return false;
      const std::size_t i = pick(pages);
      Bytes& shell = p.pages[i].shell;
      if (shell.empty()) return false;
      if (pick(2)) {
        const std::size_t at = pick(shell.size());
        shell[at] = static_cast<std::uint8_t>(shell[at] + 1 + pick(255));
        what = fmt::format("page {} shell byte {} changed", i, at);
      } else {
        const std::size_t n = 1 + pick(std::min<std::size_t>(shell.size(), 16));
        shell.resize(shell.size() - n);
        what = fmt::format("page {} shell {} bytes short", i, n);
      }
      return true;
    }
    case 11: {  // a page rewritten consistently: a sample or a halo voxel, its shell remade
      if (pages == 0 || read.head.frame.shape.brick_side == 0) return false;
      const std::size_t i = pick(pages);
      return Rewrite(p, read, i, [&](SvoChunk& c) {
        if (pick(3) == 0) {
          if (c.halo_keys.empty()) return false;
          const std::size_t h = pick(c.halo_keys.size());
          if (c.halo_colors.empty() || pick(2) == 0) {
            c.halo_keys.erase(c.halo_keys.begin() + static_cast<std::ptrdiff_t>(h));
            if (!c.halo_colors.empty()) c.halo_colors.erase(c.halo_colors.begin() + h);
            if (!c.halo_normals.empty()) c.halo_normals.erase(c.halo_normals.begin() + h);
            what = fmt::format("page {} halo voxel {} dropped, shell remade", i, h);
          } else {
            const float r = c.halo_colors[h].r;
            c.halo_colors[h].r = Half(r < 0.5f ? r + 0.25f : r - 0.25f);
            what = fmt::format("page {} halo voxel {} recoloured, shell remade", i, h);
          }
          return true;
        }
        if (c.samples.empty()) return false;
        LevelSamples& level = c.samples[pick(c.samples.size())];
        if (level.opacity.empty()) return false;
        const std::size_t at = pick(level.opacity.size());
        if (!level.color.empty() && pick(2) == 0) {
          level.color[at] ^= 0x00ff00ffu;
          what = fmt::format("page {} sample {} recoloured, shell remade", i, at);
        } else {
          level.opacity[at] = static_cast<std::uint8_t>(level.opacity[at] ^ 0x5a);
          what = fmt::format("page {} sample {} opacity changed, shell remade", i, at);
        }
        return true;
      });
    }
    default: {  // the top contours: a count, a key or a word
      if (part != 0 || p.top.size() < 20) return false;
      // The first level: its count, then entries of 12 bytes.
      const std::uint64_t n = Load<std::uint64_t>(p.top, 0);
      if (n == 0) return false;
      const std::size_t e = 8 + 12 * pick(n);
      switch (pick(3)) {
        case 0:
          return field(p.top, 0, 64, "TOPC count");
        case 1:
          return field(p.top, e, 64, "TOPC key");
        default:
          return field(p.top, e + 8, 32, "TOPC word");
      }
    }
  }
}

int MutantCount() {
  const char* n = std::getenv("SVOKIT_MERGE_MUTANTS");
  return n != nullptr ? std::atoi(n) : 100;
}

// A part whose brick sample was rewritten with its shell made again passes every structural
// check: only building the page once more refuses it, and --trust-samples takes it as written.
TEST(MergeMutants, ASampleRewrittenConsistentlyIsRefusedUnlessTrusted) {
  test::TempDir dir;
  const std::unique_ptr<Build> build = MakeBuild(dir, "bricks", 3, true, {true, 3}, 2);
  ASSERT_TRUE(MergeSvoParts(build->parts, dir / "merged.svo").ok());
  PartParts mutant = build->taken[1];
  ASSERT_TRUE(Rewrite(mutant, build->read[1], 0, [](SvoChunk& c) {
    LevelSamples& level = c.samples.back();
    level.color[level.color.size() / 2] ^= 0x00ff00ffu;
    return true;
  }));
  PutTogether(mutant, dir / "mutant.svopart", true);
  const std::vector<fs::path> parts = {build->parts[0], dir / "mutant.svopart"};
  fs::remove(dir / "merged.svo");
  const StatusOr<SvoFileStats> refused = MergeSvoParts(parts, dir / "merged.svo");
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.status().code(), StatusCode::kBadInput);
  EXPECT_NE(refused.status().message().find("mutant.svopart: page"), std::string::npos)
      << refused.status().message();
  EXPECT_NE(refused.status().message().find("brick samples are not those its voxels make"),
            std::string::npos)
      << refused.status().message();
  EXPECT_FALSE(fs::exists(dir / "merged.svo"));

  MergeOptions trust;
  trust.trust_samples = true;
  ASSERT_TRUE(MergeSvoParts(parts, dir / "merged.svo", Progress::Silent(), trust).ok());
  const StatusOr<LenientSvo> file = ReadSvoLenient(dir / "merged.svo");
  ASSERT_TRUE(file.ok()) << file.status().message();
  EXPECT_FALSE(validate::Validate(*file, "merged.svo", {}).ok());
}

TEST(MergeMutants, EveryMutantIsRefusedOrMergesIntoAValidFile) {
  test::TempDir dir;
  // Three parts each: with bricks, colours, normals and contours, zstd; without bricks, stored.
  const std::vector<std::unique_ptr<Build>> builds = [&] {
    std::vector<std::unique_ptr<Build>> b;
    b.push_back(MakeBuild(dir, "bricks", 3, true, {true, 3}, 3));
    b.push_back(MakeBuild(dir, "plain", 0, false, {false, 3}, 3));
    return b;
  }();
  // The unchanged parts merge into a valid file, and taken apart and put together they are
  // byte for byte what was written.
  for (const auto& build : builds) {
    for (std::size_t k = 0; k < build->parts.size(); ++k) {
      ASSERT_GE(build->taken[k].pages.size(), 2u) << build->name << " part " << k;
      PutTogether(build->taken[k], dir / "again.svopart", false);
      ASSERT_TRUE(test::ReadBytes(dir / "again.svopart") == test::ReadBytes(build->parts[k]));
    }
    fs::remove(dir / "again.svopart");
  }

  std::mt19937_64 rng(20261204);
  const int count = MutantCount();
  int merged = 0, refused = 0, slipped = 0;
  std::vector<std::string> slips;
  for (int m = 0; m < count; ++m) {
    const Build& build = *builds[static_cast<std::size_t>(m) % builds.size()];
    const std::uint32_t k = static_cast<std::uint32_t>(rng() % build.parts.size());
    PartParts mutant = build.taken[k];
    std::string what;
    bool sizes = true;
    while (!Mutate(mutant, k, build.read[k], rng, what, sizes)) mutant = build.taken[k];
    const std::string label = fmt::format("mutant {} ({} part {}): {}", m, build.name, k, what);
    const fs::path part = dir / "mutant.svopart", output = dir / "merged.svo";
    PutTogether(mutant, part, sizes);
    std::vector<fs::path> paths = build.parts;
    paths[k] = part;
    const StatusOr<SvoFileStats> written = MergeSvoParts(paths, output);
    if (!written.ok()) {
      ++refused;
      const std::string& message = written.status().message();
      EXPECT_EQ(written.status().code(), StatusCode::kBadInput) << label << ": " << message;
      EXPECT_EQ(message.find('\n'), std::string::npos) << label << ": " << message;
      EXPECT_NE(message.find(".svopart"), std::string::npos) << label << ": " << message;
      EXPECT_FALSE(fs::exists(output)) << label;
      continue;
    }
    ++merged;
    const StatusOr<LenientSvo> file = ReadSvoLenient(output);
    ASSERT_TRUE(file.ok()) << label << ": " << file.status().message();
    const validate::Report report = validate::Validate(*file, output.string(), {});
    if (!report.ok()) {
      ++slipped;
      std::string first;
      for (const validate::CheckResult& c : report.checks) {
        if (c.state == validate::CheckResult::State::kFailed && !c.examples.empty()) {
          first = c.examples[0].message;
          break;
        }
      }
      slips.push_back(label + " => " + first);
    }
    fs::remove(output);
  }
  std::printf("%d mutants: %d refused, %d merged, %d merged into an invalid file\n", count, refused,
              merged, slipped);
  for (const std::string& s : slips) std::printf("  %s\n", s.c_str());
  EXPECT_EQ(slipped, 0) << "mutants merged into files svo-validate rejects";
}

}  // namespace
}  // namespace svokit
