// The .vfrag `FILL` section (`svo-voxelize --fill solid`): a solid's interior cubes round trip
// exactly, through the section and through a file written in place; a surface's file has none;
// and every kind of damage to the section is refused with one line naming the file (truncated,
// unknown method, wrong depth, a cube outside the grid, keys not increasing, bytes left over).

#include <gtest/gtest.h>

#include <cstring>

#include "svokit/core/key_gaps.hpp"
#include "svokit/core/morton.hpp"
#include "svokit/formats/container/container.hpp"
#include "svokit/formats/vfrag/vfrag.hpp"
#include "svokit/voxelize/solid_fill.hpp"
#include "svokit/voxelize/voxelize.hpp"
#include "tests/test_meshes.hpp"
#include "tests/test_util.hpp"

namespace svokit {
namespace {

void ExpectSameInterior(const InteriorCubes& got, const InteriorCubes& want) {
  EXPECT_EQ(got.depth, want.depth);
  EXPECT_EQ(got.method, want.method);
  EXPECT_EQ(got.open_edges, want.open_edges);
  ASSERT_EQ(got.levels.size(), want.levels.size());
  for (std::size_t l = 0; l < want.levels.size(); ++l) {
    EXPECT_EQ(got.levels[l], want.levels[l]) << "level " << l;
  }
  EXPECT_EQ(got.voxel_count(), want.voxel_count());
}

// The icosphere's interior at `resolution` (or, with holes, its winding-number interior).
struct Filled {
  Mesh mesh;
  GridTransform grid;
  VoxelSet voxels;
  InteriorCubes interior;
};

Filled Fill(Mesh mesh, std::uint32_t resolution) {
  Filled f;
  f.mesh = std::move(mesh);
  f.grid = *GridTransform::FitResolution(f.mesh.Bounds(), resolution);
  VoxelizeOptions vo;
  vo.colors = vo.normals = true;
  auto voxels = Voxelize(f.mesh, f.grid, vo);
  EXPECT_TRUE(voxels.ok()) << voxels.status().message();
  f.voxels = std::move(*voxels);
  auto interior = FillInterior(f.mesh, f.grid, f.voxels.keys);
  EXPECT_TRUE(interior.ok()) << interior.status().message();
  f.interior = std::move(*interior);
  return f;
}

Mesh Holed() {
  Mesh m = test::Icosphere(3, false);
  m.triangles.erase(m.triangles.begin() + 100, m.triangles.begin() + 104);
  m.material_ids.clear();
  EnsureDefaultMaterial(m);
  return m;
}

TEST(VfragFill, InteriorSectionRoundTrips) {
  const Filled closed = Fill(test::Icosphere(3), 64);
  ASSERT_EQ(closed.interior.method, FillMethod::kColumns);
  ASSERT_GT(closed.interior.cube_count(), 100u);
  const Filled open = Fill(Holed(), 48);
  ASSERT_EQ(open.interior.method, FillMethod::kWindingNumber);
  ASSERT_GT(open.interior.open_edges, 0u);
  ASSERT_GT(open.interior.cube_count(), 0u);
  for (const Filled* f : {&closed, &open}) {
    const std::vector<std::uint8_t> bytes = EncodeInteriorSection(f->interior);
    EXPECT_EQ(EncodeInteriorSection(f->interior), bytes);
    auto back = DecodeInteriorSection(bytes, f->grid, "s.vfrag");
    ASSERT_TRUE(back.ok()) << back.status().message();
    ExpectSameInterior(*back, f->interior);
    // Compact: a header and about a byte or two a cube.
    EXPECT_LT(bytes.size(), 16 + 3 * f->interior.cube_count() + 2 * f->interior.levels.size());
  }
  // No cube at all (a surface that encloses no voxel centre) is a valid interior too.
  InteriorCubes none;
  none.depth = closed.interior.depth;
  none.levels.resize(none.depth + 1);
  auto back = DecodeInteriorSection(EncodeInteriorSection(none), closed.grid, "s.vfrag");
  ASSERT_TRUE(back.ok()) << back.status().message();
  ExpectSameInterior(*back, none);
}

// A 5 × 6 × 7 grid (depth 3) and an interior in it: cubes of 2³ and of one voxel.
GridTransform SmallGrid() {
  return GridTransform({-1, 2, 0.5}, 0.25, {5, 6, 7});
}
InteriorCubes SmallInterior() {
  InteriorCubes in;
  in.depth = 3;
  in.levels.resize(4);
  in.levels[2] = {MortonEncode(0, 0, 0), MortonEncode(1, 1, 1)};
  in.levels[3] = {MortonEncode(4, 0, 0), MortonEncode(4, 5, 6)};
  std::sort(in.levels[3].begin(), in.levels[3].end());
  return in;
}

void ExpectRefused(const StatusOr<InteriorCubes>& r, const std::string& expect) {
  ASSERT_FALSE(r.ok()) << "accepted: " << expect;
  EXPECT_EQ(r.status().code(), StatusCode::kBadInput);
  EXPECT_EQ(r.status().message().rfind("bad.vfrag: ", 0), 0u) << r.status().message();
  EXPECT_EQ(r.status().message().find('\n'), std::string::npos) << r.status().message();
  EXPECT_NE(r.status().message().find(expect), std::string::npos) << r.status().message();
}

TEST(VfragFill, EachDamageIsRefusedWithOneLine) {
  const GridTransform grid = SmallGrid();
  const InteriorCubes good = SmallInterior();
  const std::vector<std::uint8_t> bytes = EncodeInteriorSection(good);
  {
    auto ok = DecodeInteriorSection(bytes, grid, "bad.vfrag");
    ASSERT_TRUE(ok.ok()) << ok.status().message();
    ExpectSameInterior(*ok, good);
  }
  const auto decode = [&](const std::vector<std::uint8_t>& b) {
    return DecodeInteriorSection(b, grid, "bad.vfrag");
  };
  // Truncated: inside the header, and at every byte after it.
  ExpectRefused(decode({bytes.begin(), bytes.begin() + 15}), "truncated");
  ExpectRefused(decode({}), "truncated");
  for (std::size_t n = 16; n < bytes.size(); ++n) {
    auto r = decode({bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(n)});
    ASSERT_FALSE(r.ok()) << "cut to " << n << " bytes";
    EXPECT_EQ(r.status().message().rfind("bad.vfrag: FILL", 0), 0u) << r.status().message();
  }
  // Methods: 0 and 1 only, and 0 (exact crossings) exactly when no edge is open.
  for (const auto& [method, open_edges] :
       std::vector<std::pair<std::uint32_t, std::uint64_t>>{{2, 0}, {2, 5}, {0, 3}, {1, 0}}) {
    std::vector<std::uint8_t> b = bytes;
    std::memcpy(b.data() + 4, &method, 4);
    std::memcpy(b.data() + 8, &open_edges, 8);
    ExpectRefused(decode(b), "unknown method");
  }
  {
    std::vector<std::uint8_t> b = bytes;
    const std::uint32_t one = 1;
    const std::uint64_t open = 7;
    std::memcpy(b.data() + 4, &one, 4);
    std::memcpy(b.data() + 8, &open, 8);
    auto r = decode(b);
    ASSERT_TRUE(r.ok()) << r.status().message();
    EXPECT_EQ(r->method, FillMethod::kWindingNumber);
    EXPECT_EQ(r->open_edges, 7u);
  }
  // Another depth than the grid's.
  {
    InteriorCubes deeper = good;
    deeper.depth = 4;
    deeper.levels.resize(5);
    ExpectRefused(decode(EncodeInteriorSection(deeper)), "depth 4");
  }
  // Cubes outside the grid: a key beyond its level, or a cube past the grid's dimensions.
  {
    InteriorCubes beyond = good;
    beyond.levels[1] = {8};  // level 1 has keys 0 .. 7
    ExpectRefused(decode(EncodeInteriorSection(beyond)), "outside the grid");
    InteriorCubes past = good;
    past.levels[3].push_back(MortonEncode(5, 0, 0));  // x = 5 of 5
    std::sort(past.levels[3].begin(), past.levels[3].end());
    ExpectRefused(decode(EncodeInteriorSection(past)), "outside the grid");
    InteriorCubes past_z = good;
    past_z.levels[1] = {MortonEncode(0, 0, 1)};  // voxels z = 4 .. 7 of 7: z = 4 is inside
    EXPECT_TRUE(decode(EncodeInteriorSection(past_z)).ok());
    past_z.levels[1] = {MortonEncode(0, 1, 1)};  // y = 4 .. 7 of 6: inside; and x 0
    EXPECT_TRUE(decode(EncodeInteriorSection(past_z)).ok());
    past_z.levels[2] = {MortonEncode(0, 0, 0), MortonEncode(3, 0, 0)};  // x = 6 .. 7 of 5
    ExpectRefused(decode(EncodeInteriorSection(past_z)), "outside the grid");
  }
  // Keys not increasing: repeated, or a smaller after a larger (its gap wraps past 2^63).
  for (const std::vector<std::uint64_t>& level :
       std::vector<std::vector<std::uint64_t>>{{MortonEncode(4, 0, 0), MortonEncode(4, 0, 0)},
                                               {MortonEncode(4, 5, 6), MortonEncode(4, 0, 0)}}) {
    InteriorCubes unordered = good;
    unordered.levels[3] = level;
    auto r = decode(EncodeInteriorSection(unordered));
    ASSERT_FALSE(r.ok()) << "keys not increasing accepted";
    EXPECT_EQ(r.status().message().rfind("bad.vfrag: FILL", 0), 0u) << r.status().message();
    EXPECT_EQ(r.status().message().find('\n'), std::string::npos);
  }
  // A count beyond the bytes left.
  {
    std::vector<std::uint8_t> b(bytes.begin(), bytes.begin() + 16);
    std::uint8_t varint[kMaxVarintBytes];
    b.insert(b.end(), varint, varint + PutVarint(std::uint64_t{1} << 40, varint));
    b.push_back(0);
    ExpectRefused(decode(b), "damaged");
  }
  // Fewer levels than the depth's, and bytes after the last level.
  {
    InteriorCubes short_levels = good;
    short_levels.levels.resize(3);
    ASSERT_FALSE(decode(EncodeInteriorSection(short_levels)).ok());
    std::vector<std::uint8_t> b = bytes;
    b.push_back(0);
    ExpectRefused(decode(b), "after its last level");
  }
}

// A .vfrag with one section replaced (its layout and checksums as a writer makes them).
std::vector<std::uint8_t> WithSection(const std::vector<std::uint8_t>& file, container::Tag tag,
                                      const std::vector<std::uint8_t>& bytes) {
  auto frame = container::Frame::FromBytes(file, "v.vfrag", kVfragFormat);
  EXPECT_TRUE(frame.ok() && frame->issues().empty());
  container::Writer w(kVfragFormat, frame->flags());
  for (const container::Frame::Section& s : frame->sections()) {
    if (s.tag == tag) {
      w.AddSection(tag, bytes);
    } else {
      w.AddSection(s.tag, {s.bytes.begin(), s.bytes.end()});
    }
  }
  return w.Serialize();
}

TEST(VfragFill, SolidFileWrittenInPlaceHoldsTheInterior) {
  const Filled f = Fill(test::Icosphere(3), 64);
  test::TempDir dir;
  const Provenance meta{"ico.obj", 1280, GridFit{64},
                        VoxelSettings{VoxelMode::kConservative, true, true, true}};
  VoxelizeOptions vo;
  vo.colors = vo.normals = true;
  {
    VfragFileWriter file(dir / "s.vfrag", meta, true);
    auto packed = VoxelizePacked(f.mesh, f.grid, vo, file);
    ASSERT_TRUE(packed.ok()) << packed.status().message();
    ASSERT_TRUE(file.Commit(*packed, &f.interior).ok());
  }
  {
    VfragFileWriter file(dir / "p.vfrag", meta);
    auto packed = VoxelizePacked(f.mesh, f.grid, vo, file);
    ASSERT_TRUE(packed.ok());
    ASSERT_TRUE(file.Commit(*packed).ok());
  }
  auto solid = ReadVfragInterior(dir / "s.vfrag");
  ASSERT_TRUE(solid.ok()) << solid.status().message();
  ASSERT_TRUE(solid->has_value());
  ExpectSameInterior(**solid, f.interior);
  auto surface = ReadVfragInterior(dir / "p.vfrag");
  ASSERT_TRUE(surface.ok()) << surface.status().message();
  EXPECT_FALSE(surface->has_value());
  // The voxels are the surface's either way.
  auto a = ReadVfrag(dir / "s.vfrag"), b = ReadVfrag(dir / "p.vfrag");
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_EQ(a->keys, f.voxels.keys);
  EXPECT_EQ(a->keys, b->keys);
  EXPECT_EQ(a->colors, b->colors);

  // A solid writer needs the interior, a surface's takes none: an error, and no file.
  {
    VfragFileWriter file(dir / "x.vfrag", meta, true);
    auto packed = VoxelizePacked(f.mesh, f.grid, vo, file);
    ASSERT_TRUE(packed.ok());
    EXPECT_FALSE(file.Commit(*packed).ok());
  }
  {
    VfragFileWriter file(dir / "y.vfrag", meta);
    auto packed = VoxelizePacked(f.mesh, f.grid, vo, file);
    ASSERT_TRUE(packed.ok());
    EXPECT_FALSE(file.Commit(*packed, &f.interior).ok());
  }
  EXPECT_EQ(dir.Files(), (std::vector<std::string>{"p.vfrag", "s.vfrag"}));

  // A FILL that is damaged inside a sound container (checksums right) is refused naming the file.
  const std::vector<std::uint8_t> clean = test::ReadBytes(dir / "s.vfrag");
  InteriorCubes outside = f.interior;
  outside.levels[1] = {8};  // level 1 has keys 0 .. 7
  for (const auto& [section, expect] :
       std::vector<std::pair<std::vector<std::uint8_t>, std::string>>{
           {EncodeInteriorSection(outside), "outside the grid"},
           {std::vector<std::uint8_t>(8, 0), "truncated"}}) {
    const auto path =
        dir.Write("bad.vfrag", WithSection(clean, container::MakeTag("FILL"), section));
    auto r = ReadVfragInterior(path);
    ASSERT_FALSE(r.ok()) << expect;
    EXPECT_EQ(r.status().message().rfind(path.string() + ": FILL", 0), 0u) << r.status().message();
    EXPECT_NE(r.status().message().find(expect), std::string::npos) << r.status().message();
  }
  // The rewrite itself is faithful.
  EXPECT_EQ(WithSection(clean, container::MakeTag("FILL"), EncodeInteriorSection(f.interior)),
            clean);
}

}  // namespace
}  // namespace svokit
