// svo-export as a user runs it: svo-import → svo-voxelize → svo-build → svo-export to every
// format, coarser levels, thread counts, and bad input. Contents are checked in tests/svo.

#include <gtest/gtest.h>

#include <set>

#include "svokit/formats/vfrag/vfrag.hpp"
#include "tests/cli/run_tool.hpp"

namespace svokit::test {
namespace {

// The sample torus through the whole chain once: torus.vfrag, torus.xyz (svo-voxelize's own) and
// torus.svo (bricks, no contours) in a directory that lives as long as the test program.
const TempDir& Chain() {
  static const TempDir dir;
  static const bool made = [] {
    const std::string svm = (dir / "torus.svm").string(), vfrag = (dir / "torus.vfrag").string();
    const std::vector<std::vector<std::string>> steps = {
        {"svo-import", (DataDir() / "uv-torus.obj").string(), "-o", svm, "-q"},
        {"svo-voxelize", svm, "-o", vfrag, "-r", "48", "-q"},
        {"svo-voxelize", svm, "-o", (dir / "torus.xyz").string(), "-r", "48", "-q"},
        {"svo-build", vfrag, "-o", (dir / "torus.svo").string(), "--no-contours", "-q"},
    };
    for (const auto& step : steps) {
      const ToolResult r = RunTool(step[0], {step.begin() + 1, step.end()});
      EXPECT_EQ(r.exit_code, 0) << step[0] << ": " << r.err;
    }
    ExpectValidSvo((dir / "torus.svo").string(), svm);
    return true;
  }();
  (void)made;
  return dir;
}

std::size_t CountLines(const std::string& text) {
  return static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n'));
}

TEST(SvoExportCli, EveryFormatFromTheChain) {
  const TempDir& chain = Chain();
  const std::string svo = (chain / "torus.svo").string();
  const StatusOr<VoxelSet> voxels = ReadVfrag(chain / "torus.vfrag");
  ASSERT_TRUE(voxels.ok()) << voxels.status().message();
  TempDir out;
  for (const char* ext : {"vdb", "binvox", "vox", "ply", "xyz"}) {
    const std::filesystem::path path = out / (std::string("torus.") + ext);
    const ToolResult r = RunTool("svo-export", {svo, "-o", path.string(), "-q", "--json"});
    ASSERT_EQ(r.exit_code, 0) << ext << ": " << r.err;
    EXPECT_TRUE(r.err.empty()) << r.err;
    EXPECT_NE(r.out.find(path.string()), std::string::npos) << r.out;
    EXPECT_GT(std::filesystem::file_size(path), 0u) << ext;
  }
  // The leaves are the voxels: the export's xyz is svo-voxelize's, byte for byte.
  EXPECT_EQ(ReadText(out / "torus.xyz"), ReadText(chain / "torus.xyz"));
  EXPECT_EQ(CountLines(ReadText(out / "torus.xyz")), voxels->size() + 3);
  EXPECT_TRUE(ReadText(out / "torus.binvox").starts_with("#binvox 1\ndim 48 48 48\n"));
  EXPECT_TRUE(ReadText(out / "torus.vox").starts_with("VOX "));
  EXPECT_NE(ReadText(out / "torus.ply").find(fmt::format("element vertex {}\n", voxels->size())),
            std::string::npos);
  // Nothing but the outputs: no temporaries left behind.
  EXPECT_EQ(out.Files(), (std::vector<std::string>{"torus.binvox", "torus.ply", "torus.vdb",
                                                   "torus.vox", "torus.xyz"}));
}

TEST(SvoExportCli, CoarserLevelsAndAnyThreadCount) {
  const std::string svo = (Chain() / "torus.svo").string();
  TempDir out;
  // A 48×13×48 grid → depth 6; level 5 has nodes of two voxels, level 0 is the root alone.
  ASSERT_EQ(
      RunTool("svo-export", {svo, "-o", (out / "l5.xyz").string(), "--level", "5", "-q"}).exit_code,
      0);
  const std::string l5 = ReadText(out / "l5.xyz");
  EXPECT_NE(l5.find("# dims 24 7 24\n"), std::string::npos) << l5.substr(0, 100);
  EXPECT_LT(CountLines(l5), CountLines(ReadText(Chain() / "torus.xyz")));
  ASSERT_EQ(
      RunTool("svo-export", {svo, "-o", (out / "l0.xyz").string(), "--level", "0", "-q"}).exit_code,
      0);
  EXPECT_TRUE(ReadText(out / "l0.xyz").ends_with("# dims 1 1 1\n0 0 0\n"));

  for (const char* ext : {"binvox", "vox", "ply", "xyz"}) {
    std::string first;
    for (const char* threads : {"1", "2"}) {
      const std::filesystem::path path = out / fmt::format("t{}.{}", threads, ext);
      ASSERT_EQ(
          RunTool("svo-export", {svo, "-o", path.string(), "-j", threads, "--level", "4", "-q"})
              .exit_code,
          0);
      if (first.empty()) first = ReadText(path);
      EXPECT_EQ(ReadText(path), first) << ext << " with " << threads << " threads";
    }
  }
}

// The files in `dir`, by name.
std::set<std::string> FilesIn(const std::filesystem::path& dir) {
  std::set<std::string> names;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    names.insert(e.path().filename().string());
  }
  return names;
}

TEST(SvoExportCli, DagsFromTheOctreeAndStraightFromTheMesh) {
  TempDir out;
  const std::string mesh = (DataDir() / "uv-torus.obj").string();
  const std::string svo = (out / "torus.svo").string();
  ASSERT_EQ(RunTool("mesh2svo", {mesh, "-r", "96", "-o", svo, "-q"}).exit_code, 0);
  for (const auto& [ext, colors] :
       {std::pair<std::string, std::string>{"dag.bin", "uncompressed_colors.bin"},
        {"svdag", "dagcolors"}}) {
    const std::string exported = (out / ("exported." + ext)).string();
    const ToolResult r = RunTool("svo-export", {svo, "-o", exported, "--json"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    for (const char* key : {"\"bits_per_voxel\"", "\"level_nodes\"", "\"mean_error\""}) {
      EXPECT_NE(r.out.find(key), std::string::npos) << key << " in " << r.out;
    }
    // mesh2svo builds its scratch octree whole or by pages, on any thread count: the same files.
    for (const std::vector<std::string>& more :
         {std::vector<std::string>{}, {"--memory-limit", "48M", "--threads", "1"}}) {
      std::vector<std::string> args = {mesh, "-r", "96", "-o", (out / ("direct." + ext)).string(),
                                       "-q"};
      args.insert(args.end(), more.begin(), more.end());
      const ToolResult m = RunTool("mesh2svo", args);
      ASSERT_EQ(m.exit_code, 0) << m.err;
      EXPECT_EQ(ReadText(out / ("direct." + ext)), ReadText(exported)) << ext;
      EXPECT_EQ(ReadText(out / ("direct." + colors)), ReadText(out / ("exported." + colors)))
          << colors;
    }
  }
  // Nothing but the outputs: the scratch octrees are gone.
  EXPECT_EQ(FilesIn(out.path()),
            (std::set<std::string>{
                "torus.svo", "exported.dag.bin", "exported.uncompressed_colors.bin",
                "exported.svdag", "exported.dagcolors", "direct.dag.bin",
                "direct.uncompressed_colors.bin", "direct.svdag", "direct.dagcolors"}));
  // svo-build makes the same DAG from the voxels, whole or by pages, and needs no mesh for it.
  TempDir built;
  const std::string vfrag = (built / "torus.vfrag").string();
  ASSERT_EQ(RunTool("svo-voxelize", {mesh, "-r", "96", "-o", vfrag, "-q"}).exit_code, 0);
  for (const std::vector<std::string>& more :
       {std::vector<std::string>{}, {"--memory-limit", "48M", "--threads", "1"}}) {
    std::vector<std::string> args = {vfrag, "-o", (built / "built.svdag").string(), "-q"};
    args.insert(args.end(), more.begin(), more.end());
    const ToolResult b = RunTool("svo-build", args);
    ASSERT_EQ(b.exit_code, 0) << b.err;
    EXPECT_EQ(ReadText(built / "built.svdag"), ReadText(out / "exported.svdag"));
    EXPECT_EQ(ReadText(built / "built.dagcolors"), ReadText(out / "exported.dagcolors"));
  }
  EXPECT_EQ(FilesIn(built.path()),
            (std::set<std::string>{"torus.vfrag", "built.svdag", "built.dagcolors"}));
  // A DAG is made whole, not by parts.
  TempDir parts;
  const ToolResult p = RunTool(
      "mesh2svo", {mesh, "-r", "96", "-o", (parts / "x.dag.bin").string(), "--pages", "0/2", "-q"});
  EXPECT_EQ(p.exit_code, 2) << p.err;
  EXPECT_NE(p.err.find("svo-merge"), std::string::npos) << p.err;
  EXPECT_TRUE(FilesIn(parts.path()).empty());
}

TEST(SvoExportCli, BadInputIsOneLineExitTwoAndNoOutput) {
  const std::string svo = (Chain() / "torus.svo").string();
  TempDir inputs;
  const std::string bytes = ReadText(svo);
  const std::string truncated = inputs.Write("truncated.svo", bytes.substr(0, bytes.size() / 2));
  std::string flipped = bytes;
  flipped[flipped.size() / 2] = static_cast<char>(flipped[flipped.size() / 2] ^ 0x5a);
  const std::string corrupt = inputs.Write("corrupt.svo", flipped);
  const std::string garbage = inputs.Write("garbage.svo", std::string("not an octree\n"));

  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"{dir}/missing.svo", "-o", "{dir}/out.vdb"}, "missing.svo"},
      {{truncated, "-o", "{dir}/out.vdb"}, "truncated.svo"},
      {{corrupt, "-o", "{dir}/out.vox"}, "corrupt.svo"},
      {{garbage, "-o", "{dir}/out.xyz"}, "garbage.svo"},
      {{svo, "-o", "{dir}/out.stl"},
       "output must be a .vdb, .nvdb, .binvox, .vox, .ply, .xyz, .obj, .glb, .svdag, .ssvdag, "
       ".dag.bin file"},
      {{svo, "-o", "{dir}/out.svdag", "--level", "1"}, "level 2 or deeper"},
      {{svo, "-o", "{dir}/out.dag.bin", "--level", "2"}, "HashDAG file needs level 3 or deeper"},
      {{svo, "-o", "{dir}/out.ssvdag", "--level", "2"}, ".ssvdag file needs level 3 or deeper"},
      {{svo, "-o", "{dir}/out.svdag", "--colors", "hashdag"}, "goes beside a .dag.bin"},
      {{svo, "-o", "{dir}/out.svdag", "--colors", "rgb"}, "--colors"},
      {{svo, "-o", "{dir}/out"}, "output must be a .vdb"},
      {{svo, "-o", "{dir}/out.vdb", "--level", "7"},
       "torus.svo: level 7 exceeds the octree's depth 6"},
      {{svo, "-o", "{dir}/out.vdb", "--level", "-1"}, "--level"},
      {{svo, "-o", "{dir}/out.vdb", "--level", "x"}, "--level"},
      {{svo, "-o", "{dir}/taken.xyz"}, "taken.xyz: is a directory"},
      {{svo}, "--output is required"},
  };
  for (const auto& [args_template, expect] : cases) {
    TempDir dir;
    std::filesystem::create_directory(dir / "taken.xyz");
    std::vector<std::string> args;
    for (std::string a : args_template) {
      if (a.starts_with("{dir}")) a = dir.path().string() + a.substr(5);
      args.push_back(a);
    }
    for (const bool quiet : {true, false}) {
      if (quiet) args.push_back("-q");
      const ToolResult r = RunTool("svo-export", args);
      EXPECT_EQ(r.exit_code, 2) << expect << ": " << r.err;
      const auto lines = r.ErrLines();
      ASSERT_FALSE(lines.empty()) << expect;
      // Quiet: the error is the only line; otherwise finished stages' lines may precede it.
      if (quiet) {
        EXPECT_EQ(lines.size(), 1u) << r.err;
      }
      EXPECT_EQ(std::count_if(lines.begin(), lines.end(),
                              [](const std::string& l) { return l.starts_with("svo-export: "); }),
                1)
          << r.err;
      EXPECT_NE(lines.back().find(expect), std::string::npos) << r.err;
      EXPECT_EQ(dir.Files(), (std::vector<std::string>{"taken.xyz"})) << expect;
      if (quiet) args.pop_back();
    }
  }
}

}  // namespace
}  // namespace svokit::test
