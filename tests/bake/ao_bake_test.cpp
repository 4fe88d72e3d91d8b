// What svo-bake bakes into: node AO as the mean of the voxels below (recomputed from the keys),
// the same file at every memory limit down to the least accepted,
// the AOCC section read back whole and down to a level, UV texels and their dilated gutters, and
// the check that a mesh is the octree's.

#include <gtest/gtest.h>

#include <map>

#include "svokit/bake/ao_bake.hpp"
#include "svokit/bake/bake_svo.hpp"
#include "svokit/core/bytes.hpp"
#include "svokit/formats/container/container.hpp"
#include "svokit/formats/mesh_import.hpp"
#include "svokit/formats/provenance.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/svo/build_options.hpp"
#include "svokit/svo/compact_build.hpp"
#include "svokit/svo/compact_svo.hpp"
#include "tests/bake/bake_scenes.hpp"

namespace svokit::test {
namespace {

// The sample torus (UVs, a texture) at 48³, written as a file, baked into a copy by svo-bake's
// run, both read back; and its voxels traced again on their own.
struct BakedTorus {
  TempDir dir;
  std::filesystem::path plain, baked;
  Svo svo;  ///< the baked file, read whole
  std::vector<float> voxel_ao;
};
const BakedTorus& Torus48() {
  static const BakedTorus& baked = *[] {
    auto* b = new BakedTorus;
    StatusOr<Mesh> mesh = ImportMesh(DataDir() / "uv-torus.obj");
    EXPECT_TRUE(mesh.ok());
    auto grid = GridTransform::FitResolution(mesh->Bounds(), 48);
    VoxelizeOptions vo;
    vo.colors = vo.normals = true;
    StatusOr<VoxelSet> voxels = Voxelize(*mesh, *grid, vo);
    EXPECT_TRUE(voxels.ok());
    StatusOr<CompactSvo> compact =
        BuildCompactSvo(std::move(*voxels), &*mesh, BuildOptions{}, R"({"source":"torus"})");
    EXPECT_TRUE(compact.ok());
    b->plain = b->dir / "plain.svo";
    b->baked = b->dir / "baked.svo";
    EXPECT_TRUE(WriteSvo(*compact, b->plain).ok());
    AoBakeRequest request;
    request.input = b->plain;
    request.output = b->baked;
    request.cones.distance = 2.5;
    const StatusOr<AoBakeReport> report = BakeSvoAo(request);
    EXPECT_TRUE(report.ok()) << report.status().message();
    StatusOr<Svo> read = ReadSvo(b->baked);
    EXPECT_TRUE(read.ok());
    b->svo = std::move(*read);
    // The one page's voxels (48³ is below a page), traced apart from the bake.
    StatusOr<SvoReader> reader = SvoReader::Open(b->plain);
    EXPECT_TRUE(reader.ok() && reader->page_count() == 1);
    StatusOr<std::unique_ptr<TraceOctree>> octree = TraceOctree::Open(*reader, 0);
    EXPECT_TRUE(octree.ok());
    StatusOr<ConeTracer> tracer = ConeTracer::Make(**octree, request.cones);
    StatusOr<SvoChunk> page = reader->Page(0);
    EXPECT_TRUE(tracer.ok() && page.ok());
    StatusOr<std::vector<AoPoint>> points = VoxelPoints(*page, reader->shape(), reader->grid());
    EXPECT_TRUE(points.ok());
    b->voxel_ao = tracer->Occlusion(*points);
    return b;
  }();
  return baked;
}

// Every level's AO of `svo`.
std::vector<std::vector<std::uint8_t>> AoLevels(const Svo& svo) {
  std::vector<std::vector<std::uint8_t>> ao;
  for (const SvoLevel& level : svo.levels) ao.push_back(level.ao);
  return ao;
}

TEST(NodeAo, ANodeHoldsTheMeanOfItsVoxels) {
  const Svo& svo = Torus48().svo;
  ASSERT_TRUE(svo.has_ao);
  const std::vector<std::uint64_t> voxels = svo.LevelKeys(svo.depth);
  const std::vector<float>& ao = Torus48().voxel_ao;
  for (std::uint32_t level = 0; level <= svo.depth; ++level) {
    // Sums per node key at this level, from the voxels' keys alone.
    std::map<std::uint64_t, std::pair<std::uint64_t, std::uint64_t>> sums;
    for (std::size_t i = 0; i < voxels.size(); ++i) {
      auto& [sum, count] = sums[voxels[i] >> (3 * (svo.depth - level))];
      sum += EncodeAo(ao[i]);
      ++count;
    }
    const std::vector<std::uint64_t> keys = svo.LevelKeys(level);
    ASSERT_EQ(keys.size(), svo.levels[level].ao.size());
    for (std::size_t n = 0; n < keys.size(); ++n) {
      const auto [sum, count] = sums.at(keys[n]);
      const double mean = static_cast<double>(sum) / static_cast<double>(count);
      EXPECT_LE(std::abs(svo.levels[level].ao[n] - mean), 0.5) << "level " << level;
    }
  }
  // Some voxels are occluded (the torus' inner ring), some open.
  EXPECT_LT(*std::min_element(ao.begin(), ao.end()), 0.05f);
  EXPECT_GT(*std::max_element(ao.begin(), ao.end()), 0.1f);
}

TEST(AoSection, ReadsBackWholeAndDownToALevel) {
  TempDir dir;
  const Svo& baked = Torus48().svo;
  const std::filesystem::path plain = Torus48().plain, out = dir / "baked.svo";
  BakeSettings bake;
  bake.distance = 2;
  ASSERT_TRUE(WriteBakedSvo(plain, AoLevels(baked), bake, out).ok());
  StatusOr<Svo> whole = ReadSvo(out);
  ASSERT_TRUE(whole.ok()) << whole.status().message();
  ASSERT_TRUE(whole->has_ao);
  for (std::uint32_t l = 0; l <= baked.depth; ++l)
    EXPECT_EQ(whole->levels[l].ao, baked.levels[l].ao);
  EXPECT_EQ(ParseProvenance(whole->metadata).bake, bake);
  StatusOr<Svo> top = ReadSvo(out, 2);
  ASSERT_TRUE(top.ok()) << top.status().message();
  ASSERT_EQ(top->levels.size(), 3u);
  for (std::uint32_t l = 0; l <= 2; ++l) EXPECT_EQ(top->levels[l].ao, baked.levels[l].ao);
  // The plain file has none; baking again replaces the section.
  EXPECT_FALSE(ReadSvo(plain)->has_ao);
  bake.cones = 5;
  ASSERT_TRUE(WriteBakedSvo(out, AoLevels(baked), bake, dir / "again.svo").ok());
  StatusOr<Svo> again = ReadSvo(dir / "again.svo");
  ASSERT_TRUE(again.ok());
  EXPECT_EQ(again->levels.back().ao, baked.levels.back().ao);
  EXPECT_EQ(ParseProvenance(again->metadata).bake, bake);
  // A damaged section is refused (its checksum), naming the file.
  std::vector<std::uint8_t> bytes = ReadBytes(out);
  bytes[bytes.size() - 3] ^= 0x40;
  const StatusOr<Svo> damaged = DecodeSvo(bytes, "damaged.svo");
  ASSERT_FALSE(damaged.ok());
  EXPECT_NE(damaged.status().message().find("damaged.svo"), std::string::npos);
}

// AOCC sections whose checksums hold but whose header does not fit the octree: refused by the
// strict reader naming the section, reported as kind "ao" by the lenient one (svo-validate).
TEST(AoSection, AnInconsistentSectionIsRefused) {
  const Svo& svo = Torus48().svo;
  std::uint64_t nodes = 0;
  for (const SvoLevel& level : svo.levels) nodes += level.node_count;
  const std::uint32_t levels = svo.depth + 1;
  struct Case {
    std::uint32_t levels, codec;
    std::uint64_t raw;
  };
  for (const Case& c : {Case{levels - 1, 0, nodes}, Case{levels, 0, nodes - 1},
                        Case{levels, 7, nodes}, Case{levels, 1, nodes}}) {
    StatusOr<container::Frame> frame = container::Frame::Open(Torus48().plain, kSvoFormat);
    ASSERT_TRUE(frame.ok());
    container::Writer writer(kSvoFormat, frame->flags());
    for (const container::Frame::Section& s : frame->sections()) {
      writer.AddSectionView(s.tag, s.bytes);
    }
    ByteWriter aocc;
    aocc.Put(c.levels);
    aocc.Put(c.codec);
    aocc.Put(c.raw);
    aocc.Put(c.raw);  // stored = raw: a zstd "stream" of zeros does not decode
    aocc.PutArray(std::span<const std::uint8_t>(std::vector<std::uint8_t>(c.raw, 0)));
    writer.AddSection(container::MakeTag("AOCC"), std::move(aocc.bytes()));
    const std::vector<std::uint8_t> bytes = writer.Serialize();
    const StatusOr<Svo> strict = DecodeSvo(bytes, "bad-ao.svo");
    ASSERT_FALSE(strict.ok()) << c.levels << " " << c.codec << " " << c.raw;
    EXPECT_NE(strict.status().message().find("bad-ao.svo: the AOCC"), std::string::npos)
        << strict.status().message();
    const StatusOr<LenientSvo> lenient = DecodeSvoLenient(bytes, "bad-ao.svo");
    ASSERT_TRUE(lenient.ok());
    EXPECT_EQ(lenient->issue_counts.count("ao"), 1u);
  }
}

TEST(CompareAo, MeanPercentileAndLargestDifference) {
  // Differences 0.00, 0.01, ..., 0.99 in shuffled order.
  std::vector<float> a(100), b(100, 0.5f);
  for (int i = 0; i < 100; ++i)
    a[static_cast<std::size_t>((i * 37) % 100)] = 0.5f + 0.01f * static_cast<float>(i);
  const AoErrors e = CompareAo(a, b);
  EXPECT_NEAR(e.mean, 0.495, 1e-5);
  EXPECT_NEAR(e.p95, 0.95, 1e-5);
  EXPECT_NEAR(e.max, 0.99, 1e-5);
  EXPECT_NEAR(MeanAo(b), 0.5, 1e-12);
  EXPECT_EQ(CompareAo({}, {}).max, 0);
  EXPECT_EQ(MeanAo({}), 0);
}

TEST(RasterizeUvs, TexelsOfTheUvTrianglesAndDilatedGutters) {
  // One triangle over the lower-left half of UV space: texel centres with u + v ≤ 1.
  Mesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  mesh.triangles = {{0, 1, 2}};
  mesh.uvs = {{0, 0}, {1, 0}, {0, 1}};
  EnsureDefaultMaterial(mesh);
  const int size = 16;
  StatusOr<TexelPoints> texels = RasterizeUvs(mesh, size);
  ASSERT_TRUE(texels.ok());
  int expected = 0;
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      const double u = (x + 0.5) / size, v = 1 - (y + 0.5) / size;
      expected += u + v <= 1;
    }
  }
  ASSERT_EQ(texels->texels.size(), static_cast<std::size_t>(expected));
  for (std::size_t i = 0; i < texels->texels.size(); ++i) {
    const int x = static_cast<int>(texels->texels[i] % size),
              y = static_cast<int>(texels->texels[i] / size);
    // The surface point is the texel centre's (u, v) on this triangle (x = u, y = v, z = 0).
    EXPECT_NEAR(texels->points[i].position.x, (x + 0.5) / size, 1e-12);
    EXPECT_NEAR(texels->points[i].position.y, 1 - (y + 0.5) / size, 1e-12);
    EXPECT_NEAR(texels->points[i].normal.z, 1, 1e-12);
  }
  // AO = u on the covered texels; each texel of the first gutter ring holds the mean of its
  // covered 8-neighbours, and every texel is filled with a value from the covered range.
  std::vector<float> ao;
  for (const AoPoint& p : texels->points) ao.push_back(static_cast<float>(p.position.x));
  const std::vector<std::uint8_t> pixels = AoTexture(*texels, ao);
  ASSERT_EQ(pixels.size(), static_cast<std::size_t>(size * size));
  std::vector<int> covered(size * size, 0);
  for (const std::uint32_t t : texels->texels) covered[t] = 1;
  auto value = [&](int x, int y) { return pixels[static_cast<std::size_t>(y * size + x)] / 255.0; };
  int first_ring = 0;
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      const double u = (x + 0.5) / size;
      if (covered[y * size + x]) {
        EXPECT_NEAR(value(x, y), 1 - u, 0.5 / 255 + 1e-6);
        continue;
      }
      double sum = 0;
      int n = 0;
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          const int nx = x + dx, ny = y + dy;
          if (nx < 0 || ny < 0 || nx >= size || ny >= size || !covered[ny * size + nx]) continue;
          sum += 1 - (nx + 0.5) / size;
          ++n;
        }
      }
      if (n > 0) {
        ++first_ring;
        EXPECT_NEAR(value(x, y), sum / n, 0.5 / 255 + 1e-6) << x << "," << y;
      }
      EXPECT_GE(value(x, y), 1 - (size - 0.5) / size - 1e-6);
      EXPECT_LE(value(x, y), 1 - 0.5 / size + 1e-6);
    }
  }
  EXPECT_GE(first_ring, size);
  Mesh no_uvs = mesh;
  no_uvs.uvs.clear();
  EXPECT_FALSE(RasterizeUvs(no_uvs, size).ok());
  EXPECT_FALSE(RasterizeUvs(mesh, 0).ok());
}

// Typed META, and the option text files written before recorded: both say the grid fit.
TEST(CheckMeshMatchesOctree, OnlyTheOctreesOwnMeshPasses) {
  StatusOr<Mesh> torus = ImportMesh(DataDir() / "uv-torus.obj");
  ASSERT_TRUE(torus.ok());
  Provenance typed;
  typed.grid = GridFit{48, 0, 0};
  const std::string forms[2][2] = {
      {R"({"voxelize":"--resolution 48 --pad 0 --mode conservative"})", ProvenanceJson(typed)},
      {R"({"triangles":2304,"voxelize":"--resolution 48 --pad 0"})", ProvenanceJson([&] {
         Provenance p = typed;
         p.triangles = 2304;
         return p;
       }())}};
  for (int form = 0; form < 2; ++form) {
    SCOPED_TRACE(forms[0][form]);
    const GridTransform& grid = Torus48().svo.grid;
    EXPECT_TRUE(CheckMeshMatchesOctree(*torus, grid, forms[0][form], "uv-torus.obj").ok());
    Mesh moved = *torus;
    for (Vec3d& p : moved.positions) p.x += 1e-3;
    const Status s = CheckMeshMatchesOctree(moved, grid, forms[0][form], "moved.obj");
    ASSERT_FALSE(s.ok());
    EXPECT_NE(s.message().find("moved.obj"), std::string::npos);
    EXPECT_FALSE(CheckMeshMatchesOctree(Icosphere(2), grid, forms[0][form], "sphere").ok());
    // Same bounds, another triangle count (one triangle dropped, its corners still used).
    EXPECT_TRUE(CheckMeshMatchesOctree(*torus, grid, forms[1][form], "uv-torus.obj").ok());
    Mesh fewer = *torus;
    fewer.triangles.pop_back();
    fewer.material_ids.pop_back();
    const Status count = CheckMeshMatchesOctree(fewer, grid, forms[1][form], "fewer.obj");
    ASSERT_FALSE(count.ok());
    EXPECT_NE(count.message().find("has 2303 triangles, the octree's 2304"), std::string::npos)
        << count.message();
  }
}

}  // namespace
}  // namespace svokit::test
