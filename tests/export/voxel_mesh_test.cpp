// Voxel meshes (.obj with its .mtl, .glb): read back by svokit's own importers and by assimp, they
// are closed (every unit edge of the voxel grid crossed as often in each direction, so merged
// rectangles with T-junctions count too), cover exactly the faces between a voxel and an empty
// neighbour (counted here from the keys), carry each voxel's colour, and merging keeps the area
// while cutting the face count. Read page by page they are the whole octree's files.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <set>

#include "svokit/core/morton.hpp"
#include "svokit/export/export.hpp"
#include "svokit/export/voxel_writers.hpp"
#include "svokit/svo/sample_codec.hpp"
#include "tests/export/exported_files.hpp"
#include "tests/formats/paged_torus.hpp"

namespace svokit {
namespace {

using Point = std::array<std::int64_t, 3>;

// Faces between a voxel and no voxel, counted from the keys alone.
std::uint64_t BoundaryFaces(const std::vector<std::uint64_t>& keys) {
  std::set<Point> filled;
  for (const std::uint64_t k : keys) {
    const MortonCoord c = MortonDecode(k);
    filled.insert({c.x, c.y, c.z});
  }
  return test::BoundaryFaces(filled);
}

// The mesh's directed edges in grid units, axis-aligned ones cut into unit steps; closed when every
// step is taken as often backwards as forwards. Also its area in grid units (faces of one voxel).
struct Closure {
  std::int64_t unbalanced = 0;
  double area = 0;
};
Closure Check(const Mesh& mesh, const GridTransform& grid) {
  const double h = grid.voxel_size();
  auto to_grid = [&](const Vec3d& p) {
    const Vec3d o = grid.origin();
    return Point{std::llround((p.x - o.x) / h), std::llround((p.y - o.y) / h),
                 std::llround((p.z - o.z) / h)};
  };
  std::map<std::pair<Point, Point>, std::int64_t> steps;
  Closure out;
  for (const Triangle& t : mesh.triangles) {
    const std::array<Point, 3> v{to_grid(mesh.positions[t[0]]), to_grid(mesh.positions[t[1]]),
                                 to_grid(mesh.positions[t[2]])};
    const Vec3d e1 = mesh.positions[t[1]] - mesh.positions[t[0]];
    const Vec3d e2 = mesh.positions[t[2]] - mesh.positions[t[0]];
    out.area += Length(Cross(e1, e2)) / 2 / (h * h);
    for (int k = 0; k < 3; ++k) {
      const Point a = v[k], b = v[(k + 1) % 3];
      int moving = 0, axis = 0;
      for (int c = 0; c < 3; ++c) {
        if (a[c] != b[c]) ++moving, axis = c;
      }
      if (moving != 1) {
        ++steps[{a, b}];
        --steps[{b, a}];
        continue;
      }
      const std::int64_t dir = b[axis] > a[axis] ? 1 : -1;
      for (Point p = a; p != b;) {
        Point q = p;
        q[axis] += dir;
        ++steps[{p, q}];
        --steps[{q, p}];
        p = q;
      }
    }
  }
  for (const auto& [edge, n] : steps) out.unbalanced += std::abs(n);
  return out;
}

class VoxelMesh : public ::testing::Test {
 protected:
  std::filesystem::path Out(const std::string& name) {
    written_.push_back(std::filesystem::temp_directory_path() /
                       ("svokit_vmesh_" + std::to_string(::getpid()) + "_" + name));
    return written_.back();
  }
  void TearDown() override {
    for (auto p : written_) {
      std::filesystem::remove_all(p);
      std::filesystem::remove(p.replace_extension(".mtl"));
    }
  }
  std::vector<std::filesystem::path> written_;
};

TEST_F(VoxelMesh, ClosedWithEveryBoundaryFaceAndEachVoxelsColour) {
  const test::PagedFile torus =
      test::BuildPagedFile(test::DataDir() / "uv-torus.obj", 96, "vm_torus");
  const test::PagedFile spider =
      test::BuildPagedFile(test::AssimpModels() / "OBJ" / "spider.obj", 80, "vm_spider");
  for (const test::PagedFile* built : {&torus, &spider}) {
    StatusOr<Svo> svo = ReadSvo(built->path);
    ASSERT_TRUE(svo.ok());
    const VoxelSet voxels = LevelVoxels(*svo, svo->depth);
    const std::uint64_t boundary = BoundaryFaces({voxels.keys.begin(), voxels.keys.end()});
    EXPECT_EQ(NaiveFaceCount(voxels), boundary);
    std::map<Point, std::uint32_t> color_of;  // voxel → its linear RGBA8
    for (std::size_t i = 0; i < voxels.size(); ++i) {
      const MortonCoord c = MortonDecode(voxels.keys[i]);
      const Rgba rgba = voxels.color(i);
      color_of[{c.x, c.y, c.z}] =
          EncodeUnorm8(rgba.r) | EncodeUnorm8(rgba.g) << 8 | EncodeUnorm8(rgba.b) << 16;
    }
    for (const std::string ext : {"obj", "glb"}) {
      std::uint64_t naive_triangles = 0;
      for (const bool merge : {false, true}) {
        SCOPED_TRACE(built->path.filename().string() + " ." + ext + (merge ? " merged" : ""));
        const std::filesystem::path out = Out(std::string("mesh.") + ext);
        ExportOptions options;
        options.merge_faces = merge;
        ASSERT_TRUE(ExportSvo(*svo, out, options).ok());
        StatusOr<Mesh> mesh = ImportMesh(out);
        ASSERT_TRUE(mesh.ok()) << mesh.status().message();
        const Closure closure = Check(*mesh, voxels.grid);
        EXPECT_EQ(closure.unbalanced, 0);
        const auto area = static_cast<double>(boundary);
        EXPECT_NEAR(closure.area, area, 1e-6 * area);
        if (!merge) {
          EXPECT_EQ(mesh->triangle_count(), 2 * boundary);
          naive_triangles = mesh->triangle_count();
        } else {
          EXPECT_LT(mesh->triangle_count(), naive_triangles);
        }
        if (ext == "glb" && !merge) {
          // Each face's colour is the voxel's behind it: the one its centre lies on, inward.
          ASSERT_TRUE(mesh->has_colors());
          std::size_t wrong = 0;
          for (std::size_t t = 0; t < mesh->triangles.size(); t += 2) {
            const Triangle& a = mesh->triangles[t];
            const Vec3d centre = (mesh->positions[a[0]] + mesh->positions[a[2]]) * 0.5;
            const Vec3f n = mesh->normals[3 * t];
            const Vec3d inside = centre - Vec3d{n.x, n.y, n.z} * (0.5 * voxels.grid.voxel_size());
            const Vec3d g = (inside - voxels.grid.origin()) / voxels.grid.voxel_size();
            const Point v{static_cast<std::int64_t>(std::floor(g.x)),
                          static_cast<std::int64_t>(std::floor(g.y)),
                          static_cast<std::int64_t>(std::floor(g.z))};
            const Rgba c = mesh->colors[3 * t];
            const std::uint32_t rgb =
                EncodeUnorm8(c.r) | EncodeUnorm8(c.g) << 8 | EncodeUnorm8(c.b) << 16;
            wrong += color_of.count(v) && color_of[v] == rgb ? 0 : 1;
          }
          EXPECT_EQ(wrong, 0u);
        }
        // An independent reader: assimp's, as a DCC tool's importer would.
        const std::string info = Out("info.txt").string();
        ASSERT_EQ(std::system(("assimp info " + out.string() + " > " + info + " 2>&1").c_str()), 0)
            << "assimp (Debian's assimp-utils) could not read " << out;
        const std::vector<std::uint8_t> text_bytes = test::ReadBytes(info);
        const std::string text(text_bytes.begin(), text_bytes.end());
        const auto at = text.find("Faces:");
        ASSERT_NE(at, std::string::npos) << text;
        EXPECT_EQ(std::stoull(text.substr(at + 6)), mesh->triangle_count()) << text;
      }
    }
  }
}

TEST_F(VoxelMesh, PagesGiveTheWholeOctreesFiles) {
  const test::PagedFile torus =
      test::BuildPagedFile(test::DataDir() / "uv-torus.obj", 300, "vm_paged");
  StatusOr<Svo> svo = ReadSvo(torus.path);
  ASSERT_TRUE(svo.ok());
  StatusOr<SvoReader> reader = SvoReader::Open(torus.path);
  ASSERT_TRUE(reader.ok());
  ASSERT_GT(reader->page_count(), 1u);
  for (const std::string ext : {"obj", "glb"}) {
    for (const std::uint32_t level : {svo->depth, svo->depth - 2}) {
      // The same name in two folders: an .obj names its .mtl.
      const std::filesystem::path whole = Out("whole") / ("mesh." + ext);
      const std::filesystem::path paged = Out("paged") / ("mesh." + ext);
      std::filesystem::create_directories(whole.parent_path());
      std::filesystem::create_directories(paged.parent_path());
      ASSERT_TRUE(ExportSvo(*svo, whole, {level}).ok());
      const Status s = ExportSvoPages(*reader, paged, {level}, std::uint64_t{64} << 20);
      ASSERT_TRUE(s.ok()) << s.message();
      EXPECT_TRUE(test::ReadBytes(whole) == test::ReadBytes(paged)) << ext << " level " << level;
    }
  }
  const Status small = ExportSvoPages(*reader, Out("small.glb"), {}, std::uint64_t{1} << 10);
  EXPECT_EQ(small.code(), StatusCode::kBadInput);
  EXPECT_NE(small.message().find("a voxel mesh's"), std::string::npos) << small.message();
}

}  // namespace
}  // namespace svokit
