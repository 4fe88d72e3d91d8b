// svo-voxelize as a user runs it: outputs, determinism across methods and threads, bad input.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include <fmt/ranges.h>

#include "svokit/formats/svo/svo_reader.hpp"
#include "svokit/formats/vfrag/vfrag.hpp"
#include "tests/cli/run_tool.hpp"

namespace svokit::test {
namespace {

TEST(SvoVoxelizeCli, SvmInputAndEveryMethodAndThreadCountGiveTheSameFile) {
  TempDir dir;
  const std::string svm = (dir / "torus.svm").string();
  ASSERT_EQ(
      RunTool("svo-import", {(DataDir() / "uv-torus.obj").string(), "-o", svm, "-q"}).exit_code, 0);
  std::string first;
  for (const char* method : {"triangle", "fragment", "hybrid"}) {
    for (const char* threads : {"1", "2"}) {
      const std::string out = (dir / fmt::format("{}-{}.vfrag", method, threads)).string();
      ToolResult r = RunTool("svo-voxelize", {svm, "-o", out, "-r", "96", "--method", method,
                                              "--hybrid-cutoff", "8", "-j", threads, "-q"});
      ASSERT_EQ(r.exit_code, 0) << r.err;
      const std::string bytes = ReadText(out);
      if (first.empty()) first = bytes;
      EXPECT_EQ(bytes, first) << method << " with " << threads << " threads";
    }
  }
  auto set = ReadVfrag(dir / "hybrid-2.vfrag");
  ASSERT_TRUE(set.ok()) << set.status().message();
  EXPECT_EQ(set->grid.max_dim(), 96u);
  EXPECT_GT(set->size(), 10000u);
  // Importing directly from the OBJ gives the same voxels as from the .svm.
  const std::string direct = (dir / "direct.vfrag").string();
  ASSERT_EQ(RunTool("svo-voxelize",
                    {(DataDir() / "uv-torus.obj").string(), "-o", direct, "-r", "96", "-q"})
                .exit_code,
            0);
  EXPECT_EQ(ReadVfrag(direct)->keys, set->keys);
}

// --memory-limit voxelizes one 128³ cube at a time and streams the file: the same bytes, for
// textured, multi-material and geometry-only voxels, in both modes, with 1 and 2 threads.
TEST(SvoVoxelizeCli, MemoryLimitWritesTheSameFile) {
  TempDir dir;
  const std::vector<std::pair<std::string, std::vector<std::string>>> runs = {
      {(DataDir() / "uv-torus.obj").string(), {"-r", "300"}},
      {(DataDir() / "uv-torus.obj").string(), {"-r", "300", "--mode", "thin"}},
      {(DataDir() / "uv-torus.obj").string(), {"-r", "300", "--attributes", "none"}},
      {(DataDir() / "box-room.obj").string(), {"-r", "260"}},
      {std::string(SVOKIT_ASSIMP_MODELS "/OBJ/spider.obj"), {"-r", "400"}}};
  for (const auto& [mesh, options] : runs) {
    std::vector<std::string> whole = {mesh, "-o", (dir / "whole.vfrag").string(), "-q"};
    whole.insert(whole.end(), options.begin(), options.end());
    ASSERT_EQ(RunTool("svo-voxelize", whole).exit_code, 0) << mesh;
    for (const char* threads : {"1", "2"}) {
      std::vector<std::string> cubes = {
          mesh, "-o", (dir / "cubes.vfrag").string(), "-q", "--memory-limit", "64M", "-j", threads};
      cubes.insert(cubes.end(), options.begin(), options.end());
      const ToolResult r = RunTool("svo-voxelize", cubes);
      ASSERT_EQ(r.exit_code, 0) << r.err;
      EXPECT_TRUE(ReadText(dir / "cubes.vfrag") == ReadText(dir / "whole.vfrag"))
          << mesh << " " << fmt::format("{}", fmt::join(options, " ")) << ", -j " << threads;
    }
  }
  EXPECT_GT(ReadVfrag(dir / "cubes.vfrag")->size(), 10000u);
}

TEST(SvoVoxelizeCli, ThinIsASubsetAndXyzListsTheSameVoxels) {
  TempDir dir;
  const std::string in = (DataDir() / "uv-torus.obj").string();
  ASSERT_EQ(
      RunTool("svo-voxelize", {in, "-o", (dir / "c.vfrag").string(), "-r", "40", "-q"}).exit_code,
      0);
  ASSERT_EQ(RunTool("svo-voxelize",
                    {in, "-o", (dir / "t.vfrag").string(), "-r", "40", "--mode", "thin", "-q"})
                .exit_code,
            0);
  ToolResult r =
      RunTool("svo-voxelize", {in, "-o", (dir / "c.xyz").string(), "-r", "40", "-q", "--json"});
  ASSERT_EQ(r.exit_code, 0);
  EXPECT_NE(r.out.find("voxels"), std::string::npos);
  const auto c = ReadVfrag(dir / "c.vfrag"), t = ReadVfrag(dir / "t.vfrag");
  ASSERT_TRUE(c.ok() && t.ok());
  EXPECT_LT(t->size(), c->size());
  EXPECT_TRUE(std::includes(c->keys.begin(), c->keys.end(), t->keys.begin(), t->keys.end()));
  const std::string xyz = ReadText(dir / "c.xyz");
  EXPECT_EQ(static_cast<std::size_t>(std::count(xyz.begin(), xyz.end(), '\n')), c->size() + 3);
}

// Two meshes given one --bounds share one grid (origin, voxel size, dims), as binvox's -bb gives
// several assets one; the box is recorded, so svo-bake still matches the mesh to its octree.
TEST(SvoVoxelizeCli, BoundsGiveMeshesOneGrid) {
  TempDir dir;
  const std::vector<std::string> box = {"--bounds", "-2", "-1.5", "-2", "2", "1.5", "2.5"};
  const std::string tetra = (DataDir() / "tetra.off").string();
  const std::string torus = (DataDir() / "uv-torus.obj").string();
  std::vector<GridTransform> grids;
  for (const std::string& mesh : {tetra, torus}) {
    const std::string out = (dir / (std::filesystem::path(mesh).stem().string() + ".svo")).string();
    std::vector<std::string> args = {mesh, "-r", "64", "-o", out, "-q"};
    args.insert(args.end(), box.begin(), box.end());
    const ToolResult r = RunTool("mesh2svo", args);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    StatusOr<SvoReader> reader = SvoReader::Open(out);
    ASSERT_TRUE(reader.ok()) << reader.status().message();
    grids.push_back(reader->grid());
  }
  EXPECT_EQ(grids[0].origin(), grids[1].origin());
  EXPECT_EQ(grids[0].voxel_size(), grids[1].voxel_size());
  EXPECT_EQ(grids[0].dims(), grids[1].dims());
  // The box's longest side (4.5) over 64 and its corner within a voxel, not the mesh's (the fit
  // centres the box in whole voxels).
  const double h = grids[0].voxel_size();
  EXPECT_NEAR(h, 4.5 / 64, 1e-4 * h);
  EXPECT_NEAR(grids[0].origin().x, -2, h);
  // svo-bake fits the grid as the build did, from the box in META.
  const ToolResult bake = RunTool("svo-bake", {(dir / "uv-torus.svo").string(), "--mesh", torus,
                                               "--vertex-out", (dir / "ao.ply").string(), "-q"});
  EXPECT_EQ(bake.exit_code, 0) << bake.err;
  // A mesh reaching outside the box, or a box that is not one: one line, exit 2, no file.
  for (const std::vector<std::string>& bad :
       {std::vector<std::string>{"--bounds", "0", "0", "0", "1", "1", "1"},
        std::vector<std::string>{"--bounds", "0", "0", "0", "0", "1", "1"},
        std::vector<std::string>{"--bounds", "0", "0", "0", "inf", "1", "1"}}) {
    std::vector<std::string> args = {torus, "-r", "64", "-o", (dir / "bad.svo").string(), "-q"};
    args.insert(args.end(), bad.begin(), bad.end());
    const ToolResult r = RunTool("mesh2svo", args);
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_NE(r.err.find("bounds"), std::string::npos) << r.err;
    EXPECT_FALSE(std::filesystem::exists(dir / "bad.svo"));
  }
}

TEST(SvoVoxelizeCli, BadInputIsOneLineExitTwoAndNoOutput) {
  const std::string mesh = (DataDir() / "tetra.off").string();
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{mesh, "-o", "{dir}/v.vfrag"}, "--resolution N or --voxel-size S"},
      {{mesh, "-o", "{dir}/v.vfrag", "-r", "8", "--voxel-size", "0.1"}, "excludes"},
      {{mesh, "-o", "{dir}/v.vfrag", "-r", "0"}, "resolution"},
      {{mesh, "-o", "{dir}/v.vfrag", "-r", "2000000"}, "resolution"},
      {{mesh, "-o", "{dir}/v.vfrag", "--voxel-size", "-1"}, "voxel-size"},
      {{mesh, "-o", "{dir}/v.vfrag", "--voxel-size", "1e-9"}, "exceeds the limit"},
      {{mesh, "-o", "{dir}/v.vfrag", "--voxel-size", "2e-6"}, "would hold about"},
      {{mesh, "-o", "{dir}/v.vfrag", "-r", "8", "--mode", "fat"}, "--mode"},
      {{mesh, "-o", "{dir}/v.vfrag", "-r", "8", "--method", "magic"}, "--method"},
      {{mesh, "-o", "{dir}/v.obj", "-r", "8"}, "output must be a .vfrag, .xyz, .ply file"},
      {{"{dir}/missing.svm", "-o", "{dir}/v.vfrag", "-r", "8"}, "missing.svm: no such file"},
      {{mesh, "-o", "{dir}/v.vfrag", "-r", "8", "--memory-limit", "4Q"}, "expected a size"},
      {{mesh, "-o", "{dir}/v.vfrag", "-r", "8", "--memory-limit", "1K"}, "too small"},
      {{mesh, "-o", "{dir}/v.xyz", "-r", "8", "--memory-limit", "1G"}, ".vfrag files only"},
  };
  for (const auto& [args_template, expect] : cases) {
    TempDir dir;
    std::vector<std::string> args;
    for (std::string a : args_template) {
      if (a.starts_with("{dir}")) a = dir.path().string() + a.substr(5);
      args.push_back(a);
    }
    ToolResult r = RunTool("svo-voxelize", args);
    EXPECT_EQ(r.exit_code, 2) << expect << ": " << r.err;
    // Progress lines of finished stages may precede it; the error is the one last line.
    const auto lines = r.ErrLines();
    ASSERT_FALSE(lines.empty());
    EXPECT_EQ(std::count_if(lines.begin(), lines.end(),
                            [](const std::string& l) { return l.starts_with("svo-voxelize: "); }),
              1)
        << r.err;
    EXPECT_TRUE(lines.back().starts_with("svo-voxelize: ")) << r.err;
    EXPECT_NE(lines.back().find(expect), std::string::npos) << r.err;
    EXPECT_TRUE(dir.Files().empty()) << expect;
  }
}

// Number options: nan is refused and inf is not, consistently; messages show the value as given,
// never DBL_MAX or a 300-digit count in full.
TEST(SvoVoxelizeCli, NumberOptionsAreRefusedWithShortMessages) {
  TempDir dir;
  const std::string mesh = (DataDir() / "uv-torus.obj").string();
  const std::string out = (dir / "t.vfrag").string();
  struct Case {
    std::vector<std::string> args;
    int exit_code;
  };
  const std::vector<Case> cases = {
      {{"-r", "8", "--hybrid-cutoff", "nan"}, 2},
      {{"-r", "8", "--hybrid-cutoff", "-1"}, 2},
      {{"-r", "8", "--hybrid-cutoff", "inf"}, 0},
      {{"--voxel-size", "-1"}, 2},
      {{"--voxel-size", "inf"}, 2},
      {{"--voxel-size", "nan"}, 2},
      {{"--voxel-size", "1e-300"}, 2},
  };
  for (const Case& c : cases) {
    std::vector<std::string> args = {mesh, "-o", out, "-q"};
    args.insert(args.end(), c.args.begin(), c.args.end());
    const ToolResult r = RunTool("svo-voxelize", args);
    const std::string what = c.args[c.args.size() - 2] + " " + c.args.back();
    EXPECT_EQ(r.exit_code, c.exit_code) << what << ": " << r.err;
    if (c.exit_code == 0) continue;
    ASSERT_EQ(r.ErrLines().size(), 1u) << what << ": " << r.err;
    EXPECT_LT(r.err.size(), 200u) << what << ": " << r.err;
    EXPECT_EQ(r.err.find("179769313486"), std::string::npos) << what << ": " << r.err;
  }
}

// A grid of one voxel (-r 1, or a voxel larger than the mesh) holds the whole mesh in one voxel
// with its attributes. UBSan found the attribute pass copying from an empty vector's null data()
// there: the sanitizer run of this test is that regression test.
TEST(SvoVoxelizeCli, OneVoxelGridsHoldTheWholeMesh) {
  TempDir dir;
  const std::string out = (dir / "one.vfrag").string();
  for (const std::string mesh : {"tetra.off", "uv-torus.obj"}) {
    for (const std::vector<std::string>& grid :
         {std::vector<std::string>{"-r", "1"}, std::vector<std::string>{"--voxel-size", "1e308"}}) {
      std::vector<std::string> args = {(DataDir() / mesh).string(), "-o", out, "-q"};
      args.insert(args.end(), grid.begin(), grid.end());
      const ToolResult r = RunTool("svo-voxelize", args);
      ASSERT_EQ(r.exit_code, 0) << mesh << " " << grid[1] << ": " << r.err;
      Provenance meta;
      StatusOr<VoxelSet> voxels = ReadVfrag(out, &meta);
      ASSERT_TRUE(voxels.ok()) << voxels.status().message();
      ASSERT_EQ(voxels->keys.size(), 1u) << mesh << " " << grid[1];
      EXPECT_EQ(voxels->keys[0], 0u);
      ASSERT_EQ(voxels->normals.size(), 1u);
      ASSERT_EQ(voxels->colors.size(), 1u);
      // Closed surfaces: their area-weighted normals cancel out in the one voxel.
      const Vec3f n = voxels->normals[0];
      EXPECT_LT(n.x * n.x + n.y * n.y + n.z * n.z, 1.0001f) << mesh << " " << grid[1];
      EXPECT_TRUE(std::isfinite(voxels->color(0).r)) << mesh << " " << grid[1];
    }
  }
}

}  // namespace
}  // namespace svokit::test
