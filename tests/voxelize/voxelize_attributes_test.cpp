// Voxel attributes end to end through Voxelize(): colours of a textured surface against the
// analytic texture average, normals of a sphere against the radial direction, determinism.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "svokit/core/file_io.hpp"
#include "svokit/core/thread_limit.hpp"
#include "svokit/formats/mesh_import.hpp"
#include "svokit/formats/vfrag/vfrag.hpp"
#include "svokit/voxelize/voxelize.hpp"
#include "tests/test_meshes.hpp"
#include "tests/test_util.hpp"

namespace svokit {
namespace {

// data/uv-torus.png's colour at UV (u, v), v up, in linear light (PROVENANCE.md; nearest texel).
Rgba TorusTexture(double u, double v) {
  const int x = std::clamp(static_cast<int>(u * 64), 0, 63);
  const int y = std::clamp(static_cast<int>((1 - v) * 64), 0, 63);
  const float r = static_cast<float>((255 * (2 * x + 1) + 64) / 128) / 255.f;
  const float g = static_cast<float>((255 * (127 - 2 * y) + 64) / 128) / 255.f;
  return {SrgbToLinear(r), SrgbToLinear(g), SrgbToLinear(64.f / 255.f), 1.f};
}

// A unit square in the plane z = 0.3 carrying the whole torus texture, tinted by a base colour.
Mesh TexturedSquare() {
  Mesh m;
  m.positions = {{0, 0, 0.3}, {1, 0, 0.3}, {1, 1, 0.3}, {0, 1, 0.3}};
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  m.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 0}, {1, 1}, {0, 1}};
  m.textures.emplace_back("uv-torus.png", *ReadFileBytes(test::DataDir() / "uv-torus.png"));
  m.materials = {{.name = "tinted", .base_color = {1.f, 0.5f, 1.f, 1.f}, .texture = 0}};
  m.material_ids = {0, 0};
  return m;
}

TEST(VoxelizeAttributes, TexturedSquareMatchesTheTextureAverage) {
  const Mesh m = TexturedSquare();
  // 64 voxels across the square: each voxel sees about one texel; 16: a 4×4 texel average.
  for (std::uint32_t resolution : {64u, 16u}) {
    Box3d b = m.Bounds();
    auto grid = GridTransform::FitResolution(b, resolution);
    ASSERT_TRUE(grid.ok());
    VoxelizeOptions options;
    options.colors = true;
    auto set = Voxelize(m, *grid, options);
    ASSERT_TRUE(set.ok()) << set.status().message();
    ASSERT_EQ(set->colors.size(), set->size());
    double worst = 0;
    int checked = 0;
    for (std::size_t i = 0; i < set->size(); ++i) {
      if (set->coverage[i] < 0.5f) continue;  // edge voxels see only part of the square
      const MortonCoord c = MortonDecode(set->keys[i]);
      const Box3d vb = grid->VoxelBounds({c.x, c.y, c.z});
      // Along the square's border, REPEAT wrapping rightly blends in the opposite edge's texels.
      if (vb.lo.x < 1.0 / 64 || vb.hi.x > 63.0 / 64 || vb.lo.y < 1.0 / 64 || vb.hi.y > 63.0 / 64) {
        continue;
      }
      // The analytic mean of the (piecewise constant) texture over the voxel's UV footprint.
      Rgba want{0, 0, 0, 0};
      constexpr int kN = 32;
      for (int sy = 0; sy < kN; ++sy) {
        for (int sx = 0; sx < kN; ++sx) {
          const double u = std::clamp(vb.lo.x + (sx + 0.5) / kN * (vb.hi.x - vb.lo.x), 0.0, 1.0);
          const double v = std::clamp(vb.lo.y + (sy + 0.5) / kN * (vb.hi.y - vb.lo.y), 0.0, 1.0);
          const Rgba t = TorusTexture(u, v);
          want.r += t.r / (kN * kN), want.g += t.g / (kN * kN), want.b += t.b / (kN * kN);
        }
      }
      want.g *= 0.5f;  // the base colour tints green
      const Rgba got = set->colors[i];
      worst = std::max({worst, std::abs(double(got.r - want.r)), std::abs(double(got.g - want.g)),
                        std::abs(double(got.b - want.b))});
      EXPECT_NEAR(got.a, 1.f, 1e-4f);
      ++checked;
    }
    EXPECT_GT(checked, static_cast<int>(resolution * resolution / 2));
    // Stated tolerance: 0.005 in linear light (measured: 3e-4 at 64, 1e-4 at 16), against a
    // texel-to-texel step of the ramp of up to ~0.03.
    EXPECT_LT(worst, 0.005) << "resolution " << resolution;
    RecordProperty("worst_colour_error_" + std::to_string(resolution), std::to_string(worst));
  }
}

TEST(VoxelizeAttributes, SphereNormalsPointOutward) {
  for (bool smooth : {true, false}) {
    const Mesh m = test::Icosphere(4, smooth);  // 5120 triangles
    auto grid = GridTransform::FitResolution(m.Bounds(), 64);
    VoxelizeOptions options;
    options.normals = true;
    auto set = Voxelize(m, *grid, options);
    ASSERT_TRUE(set.ok());
    double worst = 0;
    for (std::size_t i = 0; i < set->size(); ++i) {
      const MortonCoord c = MortonDecode(set->keys[i]);
      const Vec3d centre = grid->VoxelCenter({c.x, c.y, c.z});
      const Vec3d radial = centre / Length(centre);
      const Vec3f n = set->normals[i];
      ASSERT_NEAR(Length(n), 1.f, 1e-3f);  // unit, in binary16 components
      const double cosine = Dot(radial, Vec3d{n.x, n.y, n.z});
      worst = std::max(worst, std::acos(std::clamp(cosine, -1.0, 1.0)) * 180 / std::numbers::pi);
    }
    // Stated bound: 3° smooth, 5° faceted (measured 1.0° and 2.4°). A voxel of a 64-grid spans
    // ~3.6° of arc; the radial reference at its centre differs from the mean normal of the
    // surface patch inside it by a fraction of that, plus facet tilt without corner normals.
    EXPECT_LT(worst, smooth ? 3.0 : 5.0) << (smooth ? "smooth" : "faceted");
    RecordProperty(smooth ? "worst_normal_deg_smooth" : "worst_normal_deg_faceted",
                   std::to_string(worst));
  }
}

TEST(VoxelizeAttributes, DeterministicAcrossMethodsAndThreads) {
  auto mesh = ImportMesh(test::DataDir() / "uv-torus.obj");
  ASSERT_TRUE(mesh.ok());
  auto grid = GridTransform::FitResolution(mesh->Bounds(), 96);
  VoxelSet first;
  for (VoxelMethod method :
       {VoxelMethod::kTriangle, VoxelMethod::kFragment, VoxelMethod::kHybrid}) {
    for (std::size_t threads : {1u, 2u}) {
      ThreadLimit limit(threads);
      VoxelizeOptions options;
      options.method = method;
      options.hybrid_cutoff = 4;
      options.colors = options.normals = true;
      auto set = Voxelize(*mesh, *grid, options);
      ASSERT_TRUE(set.ok());
      if (first.keys.empty()) {
        first = std::move(set).value();
        continue;
      }
      EXPECT_EQ(set->keys, first.keys);
      EXPECT_EQ(set->colors, first.colors);
      EXPECT_EQ(set->normals, first.normals);
      EXPECT_EQ(set->coverage, first.coverage);
    }
  }
  // Coverage adds up to the surface area (in voxel², each voxel's share counted once).
  double coverage = 0;
  for (float c : first.coverage) coverage += c;
  EXPECT_GT(coverage, 0);
}

// VoxelizePacked: the voxels and attributes of Voxelize(), keys packed as they are found (with
// attributes) or after (without): the same .vfrag bytes for every method, thread count and mode.
TEST(VoxelizeAttributes, PackedKeysGiveTheSameFileForEveryMethodAndThreadCount) {
  auto mesh = ImportMesh(test::DataDir() / "uv-torus.obj");
  ASSERT_TRUE(mesh.ok());
  auto grid = GridTransform::FitResolution(mesh->Bounds(), 160);
  for (const VoxelMode mode : {VoxelMode::kConservative, VoxelMode::kThin}) {
    for (const bool attributes : {true, false}) {
      VoxelizeOptions options;
      options.mode = mode;
      options.colors = options.normals = attributes;
      auto reference = Voxelize(*mesh, *grid, options);
      ASSERT_TRUE(reference.ok());
      ASSERT_GT(reference->size(), 10000u);
      const std::vector<std::uint8_t> expected = EncodeVfrag(*reference, {});
      for (VoxelMethod method :
           {VoxelMethod::kTriangle, VoxelMethod::kFragment, VoxelMethod::kHybrid}) {
        for (std::size_t threads : {1u, 2u}) {
          ThreadLimit limit(threads);
          options.method = method;
          options.hybrid_cutoff = 4;
          auto packed = VoxelizePacked(*mesh, *grid, options);
          ASSERT_TRUE(packed.ok());
          EXPECT_EQ(packed->size(), reference->size());
          EXPECT_EQ(packed->coverage, reference->coverage);
          EXPECT_TRUE(EncodeVfrag(*packed, {}) == expected)
              << "mode " << static_cast<int>(mode) << " attributes " << attributes << " method "
              << static_cast<int>(method) << " threads " << threads;
        }
      }
    }
  }
  Mesh empty;
  EXPECT_FALSE(VoxelizePacked(empty, *grid, {}).ok());
}

// With attributes the voxels are found brick by brick (triangles binned to bricks by their box
// or by walking them); without, by the method's own split: the same voxels either way, for
// small triangles (box-binned), huge ones (walked, and cut into tiles by the fragment path) and
// both modes.
TEST(VoxelizeAttributes, AttributesFindTheSameVoxelsAsGeometryOnly) {
  auto torus = ImportMesh(test::DataDir() / "uv-torus.obj");
  ASSERT_TRUE(torus.ok());
  const Mesh coarse_sphere = test::Icosphere(0, false);  // 20 triangles
  const std::pair<const Mesh*, std::uint32_t> cases[] = {{&*torus, 96}, {&coarse_sphere, 200}};
  for (const auto& [mesh, resolution] : cases) {
    auto grid = GridTransform::FitResolution(mesh->Bounds(), resolution);
    ASSERT_TRUE(grid.ok());
    for (VoxelMode mode : {VoxelMode::kConservative, VoxelMode::kThin}) {
      for (VoxelMethod method : {VoxelMethod::kTriangle, VoxelMethod::kFragment}) {
        VoxelizeOptions options;
        options.mode = mode;
        options.method = method;
        auto geometry = Voxelize(*mesh, *grid, options);
        options.colors = options.normals = true;
        auto attributed = Voxelize(*mesh, *grid, options);
        ASSERT_TRUE(geometry.ok() && attributed.ok());
        EXPECT_GT(geometry->size(), 1000u);
        EXPECT_EQ(attributed->keys, geometry->keys) << resolution;
        EXPECT_EQ(attributed->normals.size(), attributed->size());
        EXPECT_EQ(attributed->coverage.size(), attributed->size());
      }
    }
  }
}

// A 45° square through voxel edges fills three voxels a column (the closed boxes above and below
// touch it too): more than the brick pass sizes its arrays for (2 per voxel² of projected area),
// so many groups are appended after the parallel copies. They come out in key order with their
// own attributes: the geometry pass's keys, the plane's normal, each voxel's colour (red = x / L)
// from its own part of the square, or its contact with it.
TEST(VoxelizeAttributes, MoreVoxelsThanEstimatedAreAppendedInOrder) {
  constexpr double kSide = 120;
  Mesh square;
  square.positions = {{0, 0, 0}, {kSide, 0, kSide}, {kSide, kSide, kSide}, {0, kSide, 0}};
  square.triangles = {{0, 1, 2}, {0, 2, 3}};
  const GridTransform grid({-2, -2, -2}, 1, {124, 124, 124});
  for (const bool vertex_colors : {false, true}) {
    square.colors.clear();
    if (vertex_colors) {
      for (const Triangle& t : square.triangles) {
        for (std::uint32_t v : t) {
          square.colors.push_back(
              {static_cast<float>(square.positions[v].x / kSide), 0.5f, 0.25f, 1});
        }
      }
    }
    VoxelizeOptions options;
    auto geometry = Voxelize(square, grid, options);
    options.colors = options.normals = true;
    auto attributed = Voxelize(square, grid, options);
    ASSERT_TRUE(geometry.ok() && attributed.ok());
    // Packed keys go past their estimated room the same way: the same file.
    auto packed = VoxelizePacked(square, grid, options);
    ASSERT_TRUE(packed.ok());
    EXPECT_TRUE(EncodeVfrag(*packed, {}) == EncodeVfrag(*attributed, {}));
    const std::size_t voxels = geometry->size();
    EXPECT_GT(voxels, 2 * kSide * kSide + 2 + 10000);
    EXPECT_EQ(attributed->keys, geometry->keys);
    ASSERT_EQ(attributed->normals.size(), voxels);
    ASSERT_EQ(attributed->coverage.size(), voxels);
    ASSERT_EQ(attributed->colors.size(), vertex_colors ? voxels : 1);
    const Vec3f normal{-std::numbers::sqrt2_v<float> / 2, 0, std::numbers::sqrt2_v<float> / 2};
    for (std::size_t i = 0; i < voxels; ++i) {
      const Vec3f n = attributed->normals[i];  // the plane's, to the codes' ≤ 7·10⁻⁵ rad
      ASSERT_LT(Length(Cross(n, normal)), 1e-4f) << i;
      ASSERT_GT(Dot(n, normal), 0.f) << i;
      if (!vertex_colors) continue;
      const MortonCoord c = MortonDecode(attributed->keys[i]);
      const double x = static_cast<double>(c.x) - 2;  // the voxel's low x in world units
      // Voxels touched only at an edge or a corner, whose contact rounding may clip away, take
      // the colour at the point nearest their centre: within √3/2 of it, 0.37 past the box.
      constexpr double kReach = 0.37 + 0.05;
      const double red = Rgba(attributed->color(i)).r * kSide;
      ASSERT_GE(red, std::max(0.0, x) - kReach) << i;
      ASSERT_LE(red, std::min(kSide, x + 1) + kReach) << i;
    }
  }
}

// A colour every point of the surface has is every voxel's colour: held once. Materials sharing
// one base colour count as one; two base colours, a texture or vertex colours make it per voxel,
// and voxels whose surface has one material get that colour exactly (binary16-exact colours).
TEST(VoxelizeAttributes, OneColourEverywhereIsHeldOnce) {
  const Rgba warm{0.75f, 0.25f, 0.5f, 1}, cold{0.125f, 0.5f, 1, 1};
  Mesh m = test::Icosphere(3, false);
  auto grid = GridTransform::FitResolution(m.Bounds(), 48);
  ASSERT_TRUE(grid.ok());
  VoxelizeOptions options;
  options.colors = options.normals = true;
  auto voxelize = [&] {
    auto set = Voxelize(m, *grid, options);
    EXPECT_TRUE(set.ok()) << set.status().message();
    return std::move(set).value();
  };
  // The upper half of the triangles (by centroid) get material 1.
  std::vector<std::uint32_t> halves;
  for (const Triangle& t : m.triangles) {
    halves.push_back(m.positions[t[0]].z + m.positions[t[1]].z + m.positions[t[2]].z > 0);
  }

  m.materials = {{.name = "a", .base_color = warm}};
  m.material_ids.assign(m.triangles.size(), 0);
  const VoxelSet one = voxelize();
  ASSERT_EQ(one.colors.size(), 1u);
  EXPECT_EQ(one.color(one.size() - 1), HalfRgba(warm));
  ASSERT_EQ(one.normals.size(), one.size());

  m.materials.push_back({.name = "b", .base_color = warm});
  m.material_ids = halves;
  const VoxelSet same = voxelize();
  EXPECT_EQ(same.colors, one.colors);
  EXPECT_EQ(same.normals, one.normals);
  EXPECT_EQ(same.coverage, one.coverage);

  m.materials[1].base_color = cold;
  const VoxelSet two = voxelize();
  ASSERT_EQ(two.colors.size(), two.size());
  std::size_t warm_voxels = 0, cold_voxels = 0;
  for (std::size_t i = 0; i < two.size(); ++i) {
    const MortonCoord k = MortonDecode(two.keys[i]);
    const double z = grid->VoxelCenter({k.x, k.y, k.z}).z;
    // Voxels well away from the equator see one material only.
    if (std::abs(z) < 3 * grid->voxel_size()) continue;
    EXPECT_EQ(two.colors[i], z < 0 ? HalfRgba(warm) : HalfRgba(cold)) << i;
    (z < 0 ? warm_voxels : cold_voxels)++;
  }
  EXPECT_GT(warm_voxels, 500u);
  EXPECT_GT(cold_voxels, 500u);
  EXPECT_EQ(two.normals, one.normals);

  m.materials[1].base_color = warm;
  m.colors.assign(3 * m.triangles.size(), Rgba{1, 1, 1, 1});  // white vertex colours
  const VoxelSet vertex_colored = voxelize();
  ASSERT_EQ(vertex_colored.colors.size(), vertex_colored.size());
  for (std::size_t i = 0; i < vertex_colored.size(); ++i) {
    ASSERT_EQ(vertex_colored.colors[i], HalfRgba(warm)) << i;
  }
}

}  // namespace
}  // namespace svokit

namespace svokit {
namespace {

// VoxelizePacked() straight into a .vfrag file (VfragFileWriter: the voxelizer fills the mapped
// sections) gives WriteVfrag()'s bytes: per-voxel colours (the textured torus), a shared colour
// (the sphere), geometry only, each attribute alone, thin mode, two thread counts, and more
// voxels than the room planned (the 45° square: its regions grow and move, and its normals,
// all equal, are stored once). A file that is not committed leaves nothing behind.
TEST(VfragFileWriter, WritesTheBytesOfWriteVfrag) {
  auto torus = ImportMesh(test::DataDir() / "uv-torus.obj");
  ASSERT_TRUE(torus.ok());
  const Mesh sphere = test::Icosphere(3, false);
  Mesh square;
  square.positions = {{0, 0, 0}, {60, 0, 60}, {60, 60, 60}, {0, 60, 0}};
  square.triangles = {{0, 1, 2}, {0, 2, 3}};
  struct Case {
    const Mesh* mesh;
    std::uint32_t resolution;
    bool colors, normals;
    VoxelMode mode;
  };
  const Case cases[] = {{&*torus, 120, true, true, VoxelMode::kConservative},
                        {&*torus, 120, true, false, VoxelMode::kThin},
                        {&*torus, 120, false, true, VoxelMode::kConservative},
                        {&*torus, 120, false, false, VoxelMode::kConservative},
                        {&sphere, 100, true, true, VoxelMode::kConservative},
                        {&square, 61, true, true, VoxelMode::kConservative},
                        {&square, 61, false, false, VoxelMode::kConservative}};
  const Provenance meta{"mesh.obj", 0, GridFit{1024}};
  for (const Case& c : cases) {
    auto grid = GridTransform::FitResolution(c.mesh->Bounds(), c.resolution);
    ASSERT_TRUE(grid.ok());
    VoxelizeOptions options;
    options.colors = c.colors;
    options.normals = c.normals;
    options.mode = c.mode;
    auto reference = VoxelizePacked(*c.mesh, *grid, options);
    ASSERT_TRUE(reference.ok());
    const std::vector<std::uint8_t> expected = EncodeVfrag(*reference, meta);
    for (std::size_t threads : {1u, 2u}) {
      ThreadLimit limit(threads);
      test::TempDir dir;
      const auto path = dir / "out.vfrag";
      VfragFileWriter file(path, meta);
      auto voxels = VoxelizePacked(*c.mesh, *grid, options, file);
      ASSERT_TRUE(voxels.ok());
      EXPECT_EQ(voxels->count, reference->count);
      // Until the commit the file has no name (or, without O_TMPFILE, a hidden temporary's).
      for (const std::string& name : dir.Files()) EXPECT_EQ(name.rfind(".out.vfrag.tmp-", 0), 0u);
      ASSERT_TRUE(file.Commit(*voxels).ok());
      EXPECT_TRUE(test::ReadBytes(path) == expected)
          << c.resolution << " colours " << c.colors << " normals " << c.normals << " threads "
          << threads;
      EXPECT_EQ(dir.Files(), std::vector<std::string>{"out.vfrag"});
    }
  }
  test::TempDir dir;
  {
    VfragFileWriter file(dir / "abandoned.vfrag", meta);
    auto grid = GridTransform::FitResolution(sphere.Bounds(), 50);
    VoxelizeOptions options;
    options.colors = options.normals = true;
    ASSERT_TRUE(VoxelizePacked(sphere, *grid, options, file).ok());
  }
  EXPECT_TRUE(dir.Files().empty());
}

}  // namespace
}  // namespace svokit
