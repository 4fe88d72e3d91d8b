// Exports of a solid (`--fill solid`), re-read independently: binvox and .vox hold exactly the
// surface's voxels and the interior cubes' voxels, OpenVDB's occupancy grid the same with the
// cubes as tiles; a coarser --level holds that level's nodes and the cubes above it at its
// resolution; PLY and xyz list the surface's voxels only.

#include <gtest/gtest.h>

#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>

#include <nanovdb/NanoVDB.h>
#include <nanovdb/util/IO.h>

#include <set>

#include "svokit/core/morton.hpp"
#include "svokit/export/export.hpp"
#include "svokit/formats/mesh_import.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/svo/build_options.hpp"
#include "svokit/svo/compact_build.hpp"
#include "svokit/svo/compact_svo.hpp"
#include "svokit/svo/sample_codec.hpp"
#include "svokit/voxelize/solid_fill.hpp"
#include "svokit/voxelize/voxelize.hpp"
#include "tests/export/exported_files.hpp"
#include "tests/test_meshes.hpp"
#include "tests/test_util.hpp"

namespace svokit::test {
namespace {

Coord CoordOf(std::uint64_t key) {
  const MortonCoord c = MortonDecode(key);
  return {c.x, c.y, c.z};
}

// A solid's octree read back from its file, and the interior it was built from.
struct Solid {
  Svo svo;
  InteriorCubes interior;
};

Solid MakeSolid(const Mesh& mesh, std::uint32_t resolution, bool colors) {
  Solid s;
  const GridTransform grid = *GridTransform::FitResolution(mesh.Bounds(), resolution);
  VoxelizeOptions vo;
  vo.colors = vo.normals = colors;
  auto voxels = Voxelize(mesh, grid, vo);
  EXPECT_TRUE(voxels.ok()) << voxels.status().message();
  auto interior = FillInterior(mesh, grid, voxels->keys);
  EXPECT_TRUE(interior.ok()) << interior.status().message();
  s.interior = *interior;
  BuildOptions bo;
  bo.contours = false;
  bo.brick_side = colors ? 3 : 0;
  bo.interior = &s.interior;
  auto compact = BuildCompactSvo(std::move(*voxels), nullptr, bo);
  EXPECT_TRUE(compact.ok()) << compact.status().message();
  auto svo = DecodeSvo(EncodeSvo(*compact), "solid.svo");
  EXPECT_TRUE(svo.ok()) << svo.status().message();
  s.svo = std::move(*svo);
  EXPECT_TRUE(s.svo.solid);
  EXPECT_EQ(s.svo.InteriorVoxelCount(), s.interior.voxel_count());
  return s;
}

const Solid& Ball64() {
  static const Solid s = MakeSolid(Icosphere(4), 64, true);
  return s;
}

const Solid& Torus() {
  static const Solid s = [] {
    StatusOr<Mesh> mesh = ImportMesh(DataDir() / "uv-torus.obj");
    EXPECT_TRUE(mesh.ok()) << mesh.status().message();
    return MakeSolid(*mesh, 64, true);
  }();
  return s;
}

// An open surface: the icosphere with holes (winding numbers; split cubes are nodes).
const Solid& Holed() {
  static const Solid s = [] {
    Mesh m = Icosphere(3, false);
    std::vector<Triangle> kept;
    for (const Triangle& t : m.triangles) {
      if (t[0] % 61 == 7 || t[1] % 61 == 7 || t[2] % 61 == 7) continue;
      kept.push_back(t);
    }
    m.triangles = std::move(kept);
    m.material_ids.clear();
    EnsureDefaultMaterial(m);
    return MakeSolid(m, 64, false);
  }();
  return s;
}

// What an export of `level` must hold: its nodes, and the voxels of `level`'s resolution inside
// the interior's cubes of levels ≤ `level` (deeper cubes lie in nodes of `level`).
struct Expected {
  std::set<Coord> nodes, interior;
  std::set<Coord> All() const {
    std::set<Coord> all = nodes;
    all.insert(interior.begin(), interior.end());
    return all;
  }
};

Expected ExpectedAt(const Solid& s, std::uint32_t level) {
  Expected e;
  for (const std::uint64_t key : s.svo.LevelKeys(level)) e.nodes.insert(CoordOf(key));
  for (std::uint32_t l = 0; l <= level; ++l) {
    const std::int64_t side = std::int64_t{1} << (level - l);
    for (const std::uint64_t key : s.interior.levels[l]) {
      const Coord c = CoordOf(key);
      for (std::int64_t z = 0; z < side; ++z) {
        for (std::int64_t y = 0; y < side; ++y) {
          for (std::int64_t x = 0; x < side; ++x) {
            const Coord v{c[0] * side + x, c[1] * side + y, c[2] * side + z};
            EXPECT_FALSE(e.nodes.count(v)) << "an interior voxel is a node of level " << level;
            EXPECT_TRUE(e.interior.insert(v).second) << "cubes overlap";
          }
        }
      }
    }
  }
  return e;
}

// ---------------------------------------------------------------------------------------------

TEST(SolidExport, BinvoxHoldsTheSurfaceAndTheInterior) {
  TempDir dir;
  for (const Solid* s : {&Ball64(), &Torus(), &Holed()}) {
    for (const std::uint32_t up : {0u, 1u, 3u}) {
      const std::uint32_t level = s->svo.depth - up;
      SCOPED_TRACE("level " + std::to_string(level));
      ASSERT_TRUE(Export(s->svo, dir / "s.binvox", level).ok());
      const Expected e = ExpectedAt(*s, level);
      // The ball has cubes of 8³ voxels: even its level depth − 3 shows an interior.
      if (up == 0 || s == &Ball64()) {
        ASSERT_FALSE(e.interior.empty());
      }
      const std::set<Coord> got = ReadBinvox(dir / "s.binvox").voxels;
      EXPECT_EQ(got.size(), e.nodes.size() + e.interior.size());
      EXPECT_TRUE(got == e.All());
      if (up == 0) {
        EXPECT_EQ(got.size(), s->svo.voxel_count() + s->svo.InteriorVoxelCount());
      }
    }
  }
}

TEST(SolidExport, NanoVdbDensityIsOneThroughoutTheInterior) {
  TempDir dir;
  for (const Solid* s : {&Ball64(), &Holed()}) {
    for (const std::uint32_t up : {0u, 2u}) {
      const std::uint32_t level = s->svo.depth - up;
      SCOPED_TRACE("level " + std::to_string(level));
      ASSERT_TRUE(Export(s->svo, dir / "s.nvdb", level).ok());
      const Expected e = ExpectedAt(*s, level);
      const auto handle = nanovdb::io::readGrid((dir / "s.nvdb").string(), "density");
      const auto* grid = handle.grid<float>();
      ASSERT_NE(grid, nullptr);
      EXPECT_EQ(grid->activeVoxelCount(), e.nodes.size() + e.interior.size());
      auto at = grid->getAccessor();
      std::size_t wrong = 0;
      for (const Coord& c : e.interior) {
        const nanovdb::Coord ijk(static_cast<int>(c[0]), static_cast<int>(c[1]),
                                 static_cast<int>(c[2]));
        wrong += at.isActive(ijk) && at.getValue(ijk) == 1.f ? 0 : 1;
      }
      EXPECT_EQ(wrong, 0u) << "of " << e.interior.size() << " interior voxels";
    }
  }
}

TEST(SolidExport, VoxelMeshHasTheOutsideFacesOnly) {
  TempDir dir;
  for (const Solid* s : {&Ball64(), &Holed()}) {
    const Expected e = ExpectedAt(*s, s->svo.depth);
    const std::uint64_t outside = test::BoundaryFaces(e.All());
    ExportOptions options;
    options.merge_faces = false;
    ASSERT_TRUE(ExportSvo(s->svo, dir / "s.glb", options).ok());
    StatusOr<Mesh> mesh = ImportMesh(dir / "s.glb");
    ASSERT_TRUE(mesh.ok()) << mesh.status().message();
    EXPECT_EQ(mesh->triangle_count(), 2 * outside);
  }
}

TEST(SolidExport, VoxListsTheInteriorInTheSurfacesMeanColour) {
  TempDir dir;
  for (const Solid* s : {&Ball64(), &Torus(), &Holed()}) {
    ASSERT_TRUE(Export(s->svo, dir / "s.vox").ok());
    const VoxFile vox = InSvokitFrame(ReadVox(dir / "s.vox"), s->svo.grid.dims());
    EXPECT_EQ(vox.sizes.size(), 1u);  // within one 256³ tile: one model
    const Expected e = ExpectedAt(*s, s->svo.depth);
    std::set<Coord> got;
    for (const auto& [c, index] : vox.voxels) got.insert(c);
    EXPECT_EQ(vox.voxels.size(), s->svo.voxel_count() + s->svo.InteriorVoxelCount());
    EXPECT_TRUE(got == e.All());
    // One colour inside: the mean of the surface's voxels (sRGB of the linear mean, quantized).
    std::set<std::uint8_t> inside;
    for (const Coord& c : e.interior) inside.insert(vox.voxels.at(c));
    EXPECT_EQ(inside.size(), 1u);
    const VoxelSet surface = LevelVoxels(s->svo, s->svo.depth);
    if (!surface.has_colors() || inside.empty()) continue;
    double mean[3] = {0, 0, 0};
    for (std::size_t i = 0; i < surface.size(); ++i) {
      const Rgba c = surface.color(i);
      mean[0] += c.r;
      mean[1] += c.g;
      mean[2] += c.b;
    }
    const auto n = static_cast<double>(surface.size());
    const std::uint32_t want =
        EncodeColor(Rgba{static_cast<float>(mean[0] / n), static_cast<float>(mean[1] / n),
                         static_cast<float>(mean[2] / n), 1.f});
    const std::uint32_t got_rgb = vox.palette[*inside.begin()];
    for (int ch = 0; ch < 3; ++ch) {
      const int a = static_cast<int>(want >> (8 * ch) & 0xffu);
      const int b = static_cast<int>(got_rgb >> (8 * ch) & 0xffu);
      EXPECT_LE(std::abs(a - b), 12) << "channel " << ch;
    }
  }
}

TEST(SolidExport, VdbOccupancyFillsTheInteriorWithTiles) {
  TempDir dir;
  openvdb::initialize();
  const Solid ball128 = MakeSolid(Icosphere(4), 128, false);
  for (const Solid* s : {&ball128, &Torus(), &Holed()}) {
    for (const std::uint32_t up : {0u, 2u}) {
      const std::uint32_t level = s->svo.depth - up;
      SCOPED_TRACE("level " + std::to_string(level));
      ASSERT_TRUE(Export(s->svo, dir / "s.vdb", level).ok());
      openvdb::io::File file((dir / "s.vdb").string());
      file.open();
      const auto occupancy = openvdb::gridPtrCast<openvdb::BoolGrid>(file.readGrid("occupancy"));
      const auto color = file.hasGrid("color")
                             ? openvdb::gridPtrCast<openvdb::Vec3fGrid>(file.readGrid("color"))
                             : openvdb::Vec3fGrid::Ptr();
      file.close();
      ASSERT_TRUE(occupancy);
      const Expected e = ExpectedAt(*s, level);
      EXPECT_EQ(occupancy->activeVoxelCount(), e.nodes.size() + e.interior.size());
      std::uint64_t off = 0;
      for (const Coord& c : e.All()) {
        off += !occupancy->tree().isValueOn(
            openvdb::Coord(static_cast<int>(c[0]), static_cast<int>(c[1]), static_cast<int>(c[2])));
      }
      EXPECT_EQ(off, 0u) << "solid voxels not active";
      // Colours are the surface's: the interior is occupancy only.
      if (color) {
        EXPECT_EQ(color->activeVoxelCount(), e.nodes.size());
      }
      if (s == &ball128 && up == 0) {
        // Interior cubes of 8³ voxels and more are tiles, not voxels of leaf nodes.
        EXPECT_GT(occupancy->tree().activeTileCount(), 0u);
        EXPECT_LT(occupancy->tree().activeLeafVoxelCount(),
                  static_cast<openvdb::Index64>(occupancy->activeVoxelCount()));
      }
    }
  }
}

TEST(SolidExport, PointListsHoldTheSurfaceOnly) {
  TempDir dir;
  const Solid& s = Torus();
  ASSERT_TRUE(Export(s.svo, dir / "s.xyz").ok());
  const std::string xyz = ReadText(dir / "s.xyz");
  EXPECT_EQ(static_cast<std::uint64_t>(std::count(xyz.begin(), xyz.end(), '\n')),
            s.svo.voxel_count() + 3);
  ASSERT_TRUE(Export(s.svo, dir / "s.ply").ok());
  EXPECT_NE(
      ReadText(dir / "s.ply").find("element vertex " + std::to_string(s.svo.voxel_count()) + "\n"),
      std::string::npos);
  // LevelInterior gives the exporters the cubes at the level's resolution.
  for (std::uint32_t level = 0; level <= s.svo.depth; ++level) {
    const InteriorCubes at = LevelInterior(s.svo, level);
    EXPECT_EQ(at.depth, level);
    ASSERT_EQ(at.levels.size(), level + 1);
    for (std::uint32_t l = 0; l <= level; ++l) {
      EXPECT_EQ(at.levels[l], s.interior.levels[l]) << "level " << l << " of " << level;
    }
  }
}

}  // namespace
}  // namespace svokit::test
