// Exports re-read independently: OpenVDB reads the .vdb; PLY and xyz are read by small parsers
// written here, binvox and .vox by those of exported_files.hpp, all from the formats' specs and
// sharing no code with the writers.

#include <gtest/gtest.h>

#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>

#include <array>
#include <map>
#include <set>
#include <sstream>

#include "svokit/export/export.hpp"
#include "svokit/formats/mesh_import.hpp"
#include "svokit/svo/build_options.hpp"
#include "svokit/svo/reference_build.hpp"
#include "svokit/voxelize/voxelize.hpp"
#include "tests/export/exported_files.hpp"
#include "tests/test_util.hpp"

namespace svokit::test {
namespace {

using Rgb8 = std::array<int, 3>;

Coord CoordOf(std::uint64_t key) {
  const MortonCoord c = MortonDecode(key);
  return {c.x, c.y, c.z};
}

// A linear colour that is exactly an 8-bit sRGB triple, so brick quantization keeps it.
Rgba Srgb(int r, int g, int b) {
  return {SrgbToLinear(static_cast<float>(r) / 255.f), SrgbToLinear(static_cast<float>(g) / 255.f),
          SrgbToLinear(static_cast<float>(b) / 255.f), 1.f};
}

Rgb8 ToSrgb8(const Rgba& c) {
  const std::uint32_t v = EncodeColor(c);
  return {static_cast<int>(v & 0xff), static_cast<int>(v >> 8 & 0xff),
          static_cast<int>(v >> 16 & 0xff)};
}

struct HandVoxel {
  Coord ijk;
  Rgba color;
  Vec3f normal;
};

VoxelSet MakeVoxels(const GridTransform& grid, std::vector<HandVoxel> voxels) {
  std::sort(voxels.begin(), voxels.end(), [](const HandVoxel& a, const HandVoxel& b) {
    return MortonEncode(static_cast<std::uint32_t>(a.ijk[0]), static_cast<std::uint32_t>(a.ijk[1]),
                        static_cast<std::uint32_t>(a.ijk[2])) <
           MortonEncode(static_cast<std::uint32_t>(b.ijk[0]), static_cast<std::uint32_t>(b.ijk[1]),
                        static_cast<std::uint32_t>(b.ijk[2]));
  });
  VoxelSet set;
  set.grid = grid;
  for (const HandVoxel& v : voxels) {
    set.keys.push_back(MortonEncode(static_cast<std::uint32_t>(v.ijk[0]),
                                    static_cast<std::uint32_t>(v.ijk[1]),
                                    static_cast<std::uint32_t>(v.ijk[2])));
    set.colors.push_back(v.color);
    set.normals.push_back(v.normal);
    set.coverage.push_back(1.f);
  }
  return set;
}

// Five voxels in a 5×3×4 grid off the origin, with distinct exact colours and axis normals.
VoxelSet HandVoxels() {
  return MakeVoxels(GridTransform({-1.5, 0.25, 2.0}, 0.125, {5, 3, 4}),
                    {{{0, 0, 0}, Srgb(255, 0, 0), {1, 0, 0}},
                     {{1, 0, 0}, Srgb(0, 255, 0), {0, 1, 0}},
                     {{4, 2, 3}, Srgb(0, 0, 255), {0, 0, 1}},
                     {{2, 1, 1}, Srgb(128, 128, 128), {0, 0, -1}},
                     {{3, 2, 0}, Srgb(10, 200, 30), {-1, 0, 0}}});
}

Svo Build(const VoxelSet& set, std::uint32_t brick_side = 3) {
  BuildOptions options;
  options.brick_side = brick_side;
  options.contours = false;
  StatusOr<Svo> svo = BuildReferenceSvo(set, nullptr, options);
  if (!svo.ok()) throw std::runtime_error(svo.status().message());
  return std::move(svo).value();
}

// The textured sample torus at 64³, with colours and normals.
const VoxelSet& TorusVoxels() {
  static const VoxelSet set = [] {
    StatusOr<Mesh> mesh = ImportMesh(DataDir() / "uv-torus.obj");
    if (!mesh.ok()) throw std::runtime_error(mesh.status().message());
    const StatusOr<GridTransform> grid = GridTransform::FitResolution(mesh->Bounds(), 64);
    VoxelizeOptions options;
    options.colors = options.normals = true;
    return Voxelize(*mesh, *grid, options).value();
  }();
  return set;
}

// What a node of `level` must export as: its coordinates, world box and brick-centre attributes.
struct Node {
  Coord ijk;
  Vec3d center;
  Rgba color;
  Vec3f normal;
};

std::vector<Node> ExpectedNodes(const Svo& svo, std::uint32_t level) {
  const std::vector<std::uint64_t> keys = svo.LevelKeys(level);
  const double size = svo.NodeSize(level);
  std::vector<Node> nodes;
  for (std::size_t i = 0; i < keys.size(); ++i) {
    Node n;
    n.ijk = CoordOf(keys[i]);
    const Vec3d& o = svo.grid.origin();
    n.center = {o.x + (static_cast<double>(n.ijk[0]) + 0.5) * size,
                o.y + (static_cast<double>(n.ijk[1]) + 0.5) * size,
                o.z + (static_cast<double>(n.ijk[2]) + 0.5) * size};
    if (svo.brick_side == 3) {
      const BrickSample s = svo.Sample(level, i, 13);
      n.color = s.color;
      n.normal = s.normal;
    }
    nodes.push_back(n);
  }
  return nodes;
}

// ---------------------------------------------------------------------------------------------
// Independent readers.

struct VdbGrids {
  openvdb::BoolGrid::Ptr occupancy;
  openvdb::Vec3fGrid::Ptr color, normal;
};

VdbGrids ReadVdb(const std::filesystem::path& path) {
  openvdb::initialize();
  openvdb::io::File file(path.string());
  file.open();
  VdbGrids g;
  g.occupancy = openvdb::gridPtrCast<openvdb::BoolGrid>(file.readGrid("occupancy"));
  if (file.hasGrid("color"))
    g.color = openvdb::gridPtrCast<openvdb::Vec3fGrid>(file.readGrid("color"));
  if (file.hasGrid("normal")) {
    g.normal = openvdb::gridPtrCast<openvdb::Vec3fGrid>(file.readGrid("normal"));
  }
  file.close();
  return g;
}

Rgb8 RgbOf(std::uint32_t rgba) {
  return {static_cast<int>(rgba & 0xff), static_cast<int>(rgba >> 8 & 0xff),
          static_cast<int>(rgba >> 16 & 0xff)};
}

struct PlyPoints {
  std::string header;
  std::vector<Vec3f> position, normal;
  std::vector<Rgb8> color;
};

PlyPoints ReadPly(const std::filesystem::path& path) {
  const std::string bytes = ReadText(path);
  const std::size_t body = bytes.find("end_header\n") + 11;
  PlyPoints ply;
  ply.header = bytes.substr(0, body);
  std::istringstream header(ply.header);
  std::string line;
  std::size_t count = 0;
  std::vector<std::pair<std::string, std::string>> properties;  // type, name
  while (std::getline(header, line)) {
    std::istringstream words(line);
    std::string key, a, b;
    words >> key >> a >> b;
    if (key == "format") {
      EXPECT_EQ(a, "binary_little_endian");
    }
    if (key == "element") count = std::stoul(b);
    if (key == "property") properties.emplace_back(a, b);
  }
  Bytes in(bytes);
  in.Text(body);
  for (std::size_t i = 0; i < count; ++i) {
    std::map<std::string, float> f;
    std::map<std::string, int> u;
    for (const auto& [type, name] : properties) {
      if (type == "float") f[name] = in.Get<float>();
      if (type == "uchar") u[name] = in.Get<std::uint8_t>();
    }
    ply.position.push_back({f["x"], f["y"], f["z"]});
    if (f.count("nx")) ply.normal.push_back({f["nx"], f["ny"], f["nz"]});
    if (u.count("red")) ply.color.push_back({u["red"], u["green"], u["blue"]});
  }
  EXPECT_EQ(in.pos(), in.size());
  return ply;
}

struct Xyz {
  Vec3d origin;
  double voxel_size = 0;
  Coord dims{};
  std::vector<Coord> voxels;
};

Xyz ReadXyz(const std::filesystem::path& path) {
  std::istringstream in(ReadText(path));
  Xyz xyz;
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream words(line);
    if (line.starts_with("# origin")) {
      std::string hash, key;
      words >> hash >> key >> xyz.origin.x >> xyz.origin.y >> xyz.origin.z;
    } else if (line.starts_with("# voxel_size")) {
      std::string hash, key;
      words >> hash >> key >> xyz.voxel_size;
    } else if (line.starts_with("# dims")) {
      std::string hash, key;
      words >> hash >> key >> xyz.dims[0] >> xyz.dims[1] >> xyz.dims[2];
    } else {
      Coord c{};
      words >> c[0] >> c[1] >> c[2];
      xyz.voxels.push_back(c);
    }
  }
  return xyz;
}

void ExpectNear(const Vec3f& a, const Vec3f& b, float tolerance, const std::string& what) {
  EXPECT_NEAR(a.x, b.x, tolerance) << what;
  EXPECT_NEAR(a.y, b.y, tolerance) << what;
  EXPECT_NEAR(a.z, b.z, tolerance) << what;
}

// ---------------------------------------------------------------------------------------------

void CheckVdb(const Svo& svo, const std::filesystem::path& path, std::uint32_t level) {
  ASSERT_TRUE(Export(svo, path, level).ok());
  const VdbGrids g = ReadVdb(path);
  ASSERT_TRUE(g.occupancy);
  const std::vector<Node> nodes = ExpectedNodes(svo, level);
  EXPECT_EQ(g.occupancy->activeVoxelCount(), nodes.size());
  EXPECT_EQ(g.occupancy->getName(), "occupancy");
  EXPECT_DOUBLE_EQ(g.occupancy->voxelSize()[0], svo.NodeSize(level));
  EXPECT_EQ(static_cast<bool>(g.color), svo.has_color);
  EXPECT_EQ(static_cast<bool>(g.normal), svo.has_normal);
  const double eps = 1e-12 * (1 + std::abs(svo.grid.origin().x)) + 1e-9 * svo.NodeSize(level);
  for (const Node& n : nodes) {
    const openvdb::Coord ijk(static_cast<int>(n.ijk[0]), static_cast<int>(n.ijk[1]),
                             static_cast<int>(n.ijk[2]));
    ASSERT_TRUE(g.occupancy->tree().isValueOn(ijk));
    // The node's world centre is the grid's index-space voxel centre.
    const openvdb::Vec3d w = g.occupancy->indexToWorld(ijk);
    EXPECT_NEAR(w.x(), n.center.x, eps);
    EXPECT_NEAR(w.y(), n.center.y, eps);
    EXPECT_NEAR(w.z(), n.center.z, eps);
    if (g.color) {
      ASSERT_TRUE(g.color->tree().isValueOn(ijk));
      EXPECT_EQ(g.color->transform(), g.occupancy->transform());
      const openvdb::Vec3f c = g.color->tree().getValue(ijk);
      // Exported through a voxel set, which holds binary16 (relative error ≤ 2^-11).
      ExpectNear({c.x(), c.y(), c.z()}, {n.color.r, n.color.g, n.color.b}, 5e-4f, "colour");
    }
    if (g.normal) {
      const openvdb::Vec3f v = g.normal->tree().getValue(ijk);
      ExpectNear({v.x(), v.y(), v.z()}, n.normal, 5e-4f, "normal");
    }
  }
  if (g.color) {
    EXPECT_EQ(g.color->activeVoxelCount(), nodes.size());
  }
}

TEST(Export, VdbActiveVoxelsAreTheLeavesInWorldSpace) {
  TempDir dir;
  const Svo hand = Build(HandVoxels());
  CheckVdb(hand, dir / "hand.vdb", hand.depth);
  // The hand-made colours are exact 8-bit sRGB: the VDB carries them unchanged (linear).
  const VdbGrids g = ReadVdb(dir / "hand.vdb");
  const VoxelSet in = HandVoxels();
  for (std::size_t i = 0; i < in.size(); ++i) {
    const Coord c = CoordOf(in.keys[i]);
    const openvdb::Vec3f v = g.color->tree().getValue(
        openvdb::Coord(static_cast<int>(c[0]), static_cast<int>(c[1]), static_cast<int>(c[2])));
    ExpectNear({v.x(), v.y(), v.z()}, {in.colors[i].r, in.colors[i].g, in.colors[i].b}, 1e-6f,
               "hand colour");
    // A leaf's world box is the voxel's box of the source grid.
    const openvdb::Vec3d lo = g.occupancy->indexToWorld(
        openvdb::Vec3d(static_cast<double>(c[0]) - 0.5, static_cast<double>(c[1]) - 0.5,
                       static_cast<double>(c[2]) - 0.5));
    const Box3d box = in.grid.VoxelBounds({c[0], c[1], c[2]});
    EXPECT_NEAR(lo.x(), box.lo.x, 1e-12);
    EXPECT_NEAR(lo.y(), box.lo.y, 1e-12);
    EXPECT_NEAR(lo.z(), box.lo.z, 1e-12);
  }
  const Svo torus = Build(TorusVoxels());
  CheckVdb(torus, dir / "torus.vdb", torus.depth);
}

TEST(Export, CoarserLevelsAreTheParentNodes) {
  TempDir dir;
  const Svo torus = Build(TorusVoxels());
  for (std::uint32_t up = 1; up <= 3; ++up) {
    const std::uint32_t level = torus.depth - up;
    CheckVdb(torus, dir / "level.vdb", level);
    ASSERT_TRUE(Export(torus, dir / "level.xyz", level).ok());
    const Xyz xyz = ReadXyz(dir / "level.xyz");
    std::vector<Coord> parents;
    for (std::uint64_t key : torus.LevelKeys(torus.depth)) {
      const Coord c = CoordOf(MortonParent(key, static_cast<int>(up)));
      if (parents.empty() || parents.back() != c) parents.push_back(c);
    }
    EXPECT_EQ(xyz.voxels, parents) << "level " << level;
    EXPECT_EQ(xyz.voxel_size, torus.grid.voxel_size() * static_cast<double>(1u << up));
    EXPECT_EQ(xyz.origin, torus.grid.origin());
    for (int a = 0; a < 3; ++a) {
      EXPECT_EQ(xyz.dims[a], (torus.grid.dims()[a] + (1u << up) - 1) >> up);
    }
    // Every leaf's centre falls inside its parent's exported voxel.
    const VdbGrids g = ReadVdb(dir / "level.vdb");
    const std::vector<Node> leaves = ExpectedNodes(torus, torus.depth);
    for (std::size_t i = 0; i < leaves.size(); i += 97) {
      const openvdb::Coord parent = g.occupancy->transform().worldToIndexCellCentered(
          openvdb::Vec3d(leaves[i].center.x, leaves[i].center.y, leaves[i].center.z));
      EXPECT_EQ(parent, openvdb::Coord(static_cast<int>(leaves[i].ijk[0] >> up),
                                       static_cast<int>(leaves[i].ijk[1] >> up),
                                       static_cast<int>(leaves[i].ijk[2] >> up)));
    }
  }
  ASSERT_TRUE(Export(torus, dir / "root.xyz", 0u).ok());
  EXPECT_EQ(ReadXyz(dir / "root.xyz").voxels, (std::vector<Coord>{{0, 0, 0}}));
}

TEST(Export, BinvoxHeaderAndEveryVoxel) {
  TempDir dir;
  for (const VoxelSet& set : {HandVoxels(), TorusVoxels()}) {
    const Svo svo = Build(set);
    for (std::uint32_t level : {svo.depth, svo.depth - 1}) {
      ASSERT_TRUE(Export(svo, dir / "out.binvox", level).ok());
      const Binvox b = ReadBinvox(dir / "out.binvox");
      const std::vector<Node> nodes = ExpectedNodes(svo, level);
      const std::uint32_t shift = svo.depth - level;
      EXPECT_EQ(b.dim, ((set.grid.max_dim() - 1) >> shift) + 1);
      EXPECT_EQ(b.translate, set.grid.origin());
      EXPECT_DOUBLE_EQ(b.scale, static_cast<double>(b.dim) * svo.NodeSize(level));
      std::set<Coord> expected;
      for (const Node& n : nodes) {
        expected.insert(n.ijk);
        // binvox's own mapping of a voxel to mesh space lands on the node's centre.
        const double x =
            (static_cast<double>(n.ijk[0]) + 0.5) / static_cast<double>(b.dim) * b.scale +
            b.translate.x;
        const double y =
            (static_cast<double>(n.ijk[1]) + 0.5) / static_cast<double>(b.dim) * b.scale +
            b.translate.y;
        EXPECT_NEAR(x, n.center.x, 1e-9);
        EXPECT_NEAR(y, n.center.y, 1e-9);
      }
      EXPECT_EQ(b.voxels, expected);
    }
  }
}

TEST(Export, VoxExactPaletteForFewColours) {
  TempDir dir;
  const VoxelSet in = HandVoxels();
  const Svo svo = Build(in);
  ASSERT_TRUE(Export(svo, dir / "hand.vox").ok());
  const VoxFile vox = InSvokitFrame(ReadVox(dir / "hand.vox"), in.grid.dims());
  ASSERT_EQ(vox.sizes.size(), 1u);
  EXPECT_EQ(vox.sizes[0], (std::array<std::int32_t, 3>{5, 4, 3}));  // z-up: y and z swap
  ASSERT_EQ(vox.voxels.size(), in.size());
  for (std::size_t i = 0; i < in.size(); ++i) {
    const auto it = vox.voxels.find(CoordOf(in.keys[i]));
    ASSERT_NE(it, vox.voxels.end());
    EXPECT_EQ(RgbOf(vox.palette[it->second]), ToSrgb8(in.colors[i]));
    EXPECT_EQ(vox.palette[it->second] >> 24, 255u);
  }
  EXPECT_EQ(vox.UsedIndices().size(), 5u);
}

TEST(Export, VoxIsZUpAsMagicaVoxelIs) {
  // An L on the floor with a tower at its corner: +y (svokit's up) must become the .vox's +z, and
  // +z (towards the viewer) its −y, so the model stands as it does in a y-up viewer.
  TempDir dir;
  const std::vector<Coord> coords = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 2, 0}, {0, 0, 1}};
  std::vector<HandVoxel> voxels;
  for (const Coord& c : coords) voxels.push_back({c, Srgb(200, 10, 10), {0, 1, 0}});
  const VoxelSet in = MakeVoxels(GridTransform({0, 0, 0}, 1.0, {2, 3, 2}), voxels);
  ASSERT_TRUE(Export(Build(in, 0), dir / "l.vox").ok());
  const VoxFile vox = ReadVox(dir / "l.vox");  // in the .vox's own frame
  std::set<Coord> got;
  for (const auto& [c, index] : vox.voxels) got.insert(c);
  EXPECT_EQ(got, (std::set<Coord>{{0, 1, 0}, {1, 1, 0}, {0, 1, 1}, {0, 1, 2}, {0, 0, 0}}));
  EXPECT_EQ(vox.sizes[0], (std::array<std::int32_t, 3>{2, 2, 3}));
}

TEST(Export, VoxSplitsGridsLargerThan256IntoPlacedModels) {
  TempDir dir;
  std::vector<HandVoxel> voxels;
  const std::vector<Coord> coords = {{0, 0, 0},      {255, 0, 0},    {256, 0, 0}, {599, 19, 299},
                                     {300, 10, 257}, {257, 19, 255}, {1, 1, 299}, {512, 0, 0}};
  for (std::size_t i = 0; i < coords.size(); ++i) {
    voxels.push_back({coords[i], Srgb(static_cast<int>(30 * i), 255, 0), {0, 0, 1}});
  }
  const VoxelSet in = MakeVoxels(GridTransform({0, 0, 0}, 1.0, {600, 20, 300}), voxels);
  const Svo svo = Build(in, 0);  // no bricks: occupancy only, every voxel gets the one colour
  ASSERT_TRUE(Export(svo, dir / "big.vox").ok());
  const VoxFile vox = InSvokitFrame(ReadVox(dir / "big.vox"), in.grid.dims());
  // Tiles (x/256, z/256): (0,0), (1,0), (2,0), (0,1), (1,1), (2,1).
  ASSERT_EQ(vox.sizes.size(), 6u);
  for (const auto& s : vox.sizes) {
    for (int a = 0; a < 3; ++a) {
      EXPECT_GE(s[a], 1);
      EXPECT_LE(s[a], 256);
    }
  }
  std::set<Coord> expected(coords.begin(), coords.end()), got;
  for (const auto& [c, index] : vox.voxels) got.insert(c);
  EXPECT_EQ(got, expected);
  EXPECT_EQ(vox.UsedIndices(), (std::set<std::uint32_t>{1}));

  // With colours the same split holds; each voxel keeps its exact colour (8 ≤ 255 colours).
  const Svo colored = Build(in);
  ASSERT_TRUE(Export(colored, dir / "big.vox").ok());
  const VoxFile vox2 = InSvokitFrame(ReadVox(dir / "big.vox"), in.grid.dims());
  for (std::size_t i = 0; i < in.size(); ++i) {
    EXPECT_EQ(RgbOf(vox2.ColorAt(CoordOf(in.keys[i]))), ToSrgb8(in.colors[i]));
  }
}

TEST(Export, VoxMedianCutPaletteOnTheTexturedTorus) {
  TempDir dir;
  const Svo svo = Build(TorusVoxels());
  ASSERT_TRUE(Export(svo, dir / "torus.vox").ok());
  const VoxFile vox = InSvokitFrame(ReadVox(dir / "torus.vox"), svo.grid.dims());
  const std::vector<Node> nodes = ExpectedNodes(svo, svo.depth);
  ASSERT_EQ(vox.voxels.size(), nodes.size());
  std::set<Rgb8> distinct;
  double sum = 0, cube_sum = 0;
  int worst = 0;
  for (const Node& n : nodes) {
    const Rgb8 want = ToSrgb8(n.color);
    distinct.insert(want);
    const Rgb8 got = RgbOf(vox.ColorAt(n.ijk));
    for (int ch = 0; ch < 3; ++ch) {
      const int e = std::abs(got[ch] - want[ch]);
      sum += e;
      worst = std::max(worst, e);
      // The fixed 6×7×6 cube's error, for comparison.
      const int steps = ch == 1 ? 6 : 5;
      const int cube = (want[ch] * steps + 127) / 255 * 255 / steps;
      cube_sum += std::abs(cube - want[ch]);
    }
  }
  const double mean = sum / (3.0 * static_cast<double>(nodes.size()));
  const double cube_mean = cube_sum / (3.0 * static_cast<double>(nodes.size()));
  RecordProperty("distinct_colours", static_cast<int>(distinct.size()));
  RecordProperty("mean_error", std::to_string(mean));
  RecordProperty("cube_mean_error", std::to_string(cube_mean));
  RecordProperty("max_error", worst);
  EXPECT_GT(distinct.size(), 255u);  // the palette really has to quantize
  EXPECT_LE(vox.UsedIndices().size(), 255u);
  EXPECT_GE(vox.UsedIndices().size(), 200u);
  // Measured: 10 778 colours → mean 2.7, max 12 (8-bit sRGB units); the fixed cube 12.3.
  EXPECT_LT(mean, 3.5) << "mean 8-bit error per channel";
  EXPECT_LT(mean, cube_mean / 2);
  EXPECT_LE(worst, 16) << "max 8-bit error per channel";
  // Deterministic: the same octree gives the same bytes.
  ASSERT_TRUE(Export(svo, dir / "again.vox").ok());
  EXPECT_EQ(ReadText(dir / "again.vox"), ReadText(dir / "torus.vox"));
}

TEST(Export, PlyPointsAtNodeCentresWithColoursAndNormals) {
  TempDir dir;
  const Svo svo = Build(TorusVoxels());
  for (std::uint32_t level : {svo.depth, svo.depth - 2}) {
    ASSERT_TRUE(Export(svo, dir / "out.ply", level).ok());
    const PlyPoints ply = ReadPly(dir / "out.ply");
    const std::vector<Node> nodes = ExpectedNodes(svo, level);
    ASSERT_EQ(ply.position.size(), nodes.size());
    ASSERT_EQ(ply.normal.size(), nodes.size());
    ASSERT_EQ(ply.color.size(), nodes.size());
    for (std::size_t i = 0; i < nodes.size(); ++i) {
      const Vec3d& c = nodes[i].center;
      ExpectNear(ply.position[i],
                 {static_cast<float>(c.x), static_cast<float>(c.y), static_cast<float>(c.z)}, 0.f,
                 "position");
      ExpectNear(ply.normal[i], nodes[i].normal, 5e-4f, "normal");  // binary16, as above
      EXPECT_EQ(ply.color[i], ToSrgb8(nodes[i].color));
    }
  }
}

TEST(Export, XyzListsTheLeavesInMortonOrder) {
  TempDir dir;
  const VoxelSet in = HandVoxels();
  ASSERT_TRUE(Export(Build(in), dir / "hand.xyz").ok());
  const Xyz xyz = ReadXyz(dir / "hand.xyz");
  EXPECT_EQ(xyz.origin, in.grid.origin());
  EXPECT_EQ(xyz.voxel_size, in.grid.voxel_size());
  EXPECT_EQ(xyz.dims, (Coord{5, 3, 4}));
  std::vector<Coord> expected;
  for (std::uint64_t key : in.keys) expected.push_back(CoordOf(key));
  EXPECT_EQ(xyz.voxels, expected);
}

TEST(Export, EvenBricksAverageTheCornersAndNoBricksExportOccupancyOnly) {
  TempDir dir;
  const VoxelSet one = MakeVoxels(GridTransform({0, 0, 0}, 0.5, {2, 2, 2}),
                                  {{{1, 0, 1}, Srgb(200, 100, 50), {0, 1, 0}}});
  // Every corner of a lone voxel's 2³ brick sees only that voxel: the mean is its colour.
  ASSERT_TRUE(Export(Build(one, 2), dir / "even.ply").ok());
  const PlyPoints even = ReadPly(dir / "even.ply");
  ASSERT_EQ(even.color.size(), 1u);
  EXPECT_EQ(even.color[0], (Rgb8{200, 100, 50}));
  ExpectNear(even.normal[0], {0, 1, 0}, 0.02f, "normal");

  const Svo bare = Build(HandVoxels(), 0);
  ASSERT_TRUE(Export(bare, dir / "bare.ply").ok());
  const PlyPoints ply = ReadPly(dir / "bare.ply");
  EXPECT_EQ(ply.header.find("red"), std::string::npos);
  EXPECT_EQ(ply.header.find("nx"), std::string::npos);
  EXPECT_EQ(ply.position.size(), 5u);
  ASSERT_TRUE(Export(bare, dir / "bare.vdb").ok());
  const VdbGrids g = ReadVdb(dir / "bare.vdb");
  EXPECT_EQ(g.occupancy->activeVoxelCount(), 5u);
  EXPECT_FALSE(g.color);
  EXPECT_FALSE(g.normal);
}

TEST(Export, BadInputIsReportedAndLeavesNoFile) {
  TempDir dir;
  const Svo svo = Build(HandVoxels());
  struct Case {
    std::filesystem::path path;
    std::optional<std::uint32_t> level;
    std::string message;
  };
  std::filesystem::create_directory(dir / "taken.vdb");
  const std::vector<Case> cases = {
      {dir / "out.stl", std::nullopt, "unknown export format"},
      {dir / "out", std::nullopt, "unknown export format"},
      {dir / "out.vdb", svo.depth + 1, "level 4 does not exist"},
      {dir / "taken.vdb", std::nullopt, "is a directory"},
      {dir / "missing" / "out.xyz", std::nullopt, "output directory does not exist"},
      // A directory where nothing can be created: the environment refuses, not the input.
      {"/proc/svokit-export-test.vdb", std::nullopt, "cannot create the output"},
      {"/proc/svokit-export-test.binvox", std::nullopt, "cannot create the output"},
      {"/proc/svokit-export-test.vox", std::nullopt, "cannot create the output"},
  };
  for (const Case& c : cases) {
    const Status s = Export(svo, c.path, c.level);
    const bool environment =
        c.path.string().starts_with("/proc/") || c.path.parent_path().filename() == "missing";
    const StatusCode expected = environment ? StatusCode::kCannotWrite : StatusCode::kBadInput;
    EXPECT_EQ(s.code(), expected) << c.path << ": " << s.message();
    EXPECT_NE(s.message().find(c.message), std::string::npos) << s.message();
    EXPECT_NE(s.message().find(c.path.filename().string()), std::string::npos) << s.message();
  }
  EXPECT_EQ(dir.Files(), (std::vector<std::string>{"taken.vdb"}));

  // binvox stores the whole cube: a grid of 5000 along x is refused, not written for minutes.
  const VoxelSet wide =
      MakeVoxels(GridTransform({0, 0, 0}, 1.0, {5000, 1, 1}),
                 {{{0, 0, 0}, Srgb(1, 2, 3), {1, 0, 0}}, {{4999, 0, 0}, Srgb(1, 2, 3), {1, 0, 0}}});
  const Svo wide_svo = Build(wide, 0);
  const Status s = Export(wide_svo, dir / "wide.binvox");
  EXPECT_EQ(s.code(), StatusCode::kBadInput);
  EXPECT_NE(s.message().find("coarser --level"), std::string::npos) << s.message();
  EXPECT_TRUE(Export(wide_svo, dir / "wide.binvox", wide_svo.depth - 3).ok());
  EXPECT_EQ(dir.Files(), (std::vector<std::string>{"taken.vdb", "wide.binvox"}));
}

}  // namespace
}  // namespace svokit::test
