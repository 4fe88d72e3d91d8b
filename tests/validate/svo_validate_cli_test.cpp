// svo-validate as a user runs it: exit 0 for a valid file, 1 with findings, 2 for unusable input
// (one line on stderr naming the file), and the JSON report's stable keys.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <filesystem>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "tests/cli/run_tool.hpp"

namespace svokit::test {
namespace {

std::string Torus() {
  return (DataDir() / "uv-torus.obj").string();
}

const TempDir& Files() {
  static const TempDir dir;
  static const bool made = [] {
    const ToolResult r =
        RunTool("mesh2svo", {Torus(), "-o", (dir / "t.svo").string(), "-r", "40", "-q"});
    EXPECT_EQ(r.exit_code, 0) << r.err;
    std::string bytes = ReadText(dir / "t.svo");
    bytes[bytes.size() / 2] = static_cast<char>(bytes[bytes.size() / 2] ^ 0x20);
    dir.Write("flipped.svo", bytes);
    dir.Write("far.obj", "v 100 100 100\nv 101 100 100\nv 100 101 100\nf 1 2 3\n");
    return true;
  }();
  (void)made;
  return dir;
}

TEST(SvoValidateCli, ValidFileExitsZeroWithTextAndJson) {
  const std::string svo = (Files() / "t.svo").string();
  ToolResult r = RunTool("svo-validate", {svo, "--mesh", Torus()});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_EQ(r.err.find("warning"), std::string::npos) << r.err;  // progress lines alone
  for (const char* line :
       {"structure       passed", "bricks          passed", "occupancy       passed",
        "contour_surface passed", "result          valid"}) {
    EXPECT_NE(r.out.find(line), std::string::npos) << line << " in\n" << r.out;
  }
  r = RunTool("svo-validate", {svo, "--mesh", Torus(), "--json", "-q"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["file"], svo);
  EXPECT_EQ(j["valid"], true);
  EXPECT_EQ(j["findings"], 0);
  for (const char* check : {"structure", "bricks", "contours", "occupancy", "contour_surface"}) {
    ASSERT_TRUE(j["checks"].contains(check)) << check;
    EXPECT_EQ(j["checks"][check]["status"], "passed") << check;
    for (const char* key : {"note", "findings", "counts", "stats", "examples"}) {
      EXPECT_TRUE(j["checks"][check].contains(key)) << check << "." << key;
    }
  }
  EXPECT_EQ(j["checks"]["occupancy"]["stats"]["missing"], 0);
  EXPECT_EQ(j["checks"]["occupancy"]["stats"]["matched"],
            j["checks"]["occupancy"]["stats"]["leaves"]);
}

TEST(SvoValidateCli, CorruptFileExitsOneWithFindings) {
  const ToolResult r =
      RunTool("svo-validate", {(Files() / "flipped.svo").string(), "--json", "-q"});
  EXPECT_EQ(r.exit_code, 1) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["valid"], false);
  EXPECT_EQ(j["checks"]["structure"]["status"], "failed");
  EXPECT_EQ(j["checks"]["structure"]["counts"]["section_checksum"], 1);
  EXPECT_NE(j["checks"]["structure"]["examples"][0]["message"].get<std::string>().find(
                "flipped.svo: section '"),
            std::string::npos);
}

TEST(SvoValidateCli, UnusableInputExitsTwoWithOneLine) {
  const TempDir& in = Files();
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{(in / "missing.svo").string()}, "missing.svo: cannot open"},
      {{Torus()}, "uv-torus.obj: not a svokit sparse voxel octree (.svo) file"},
      {{(in / "t.svo").string(), "--mesh", (in / "nomesh.obj").string()}, "nomesh.obj"},
      {{(in / "t.svo").string(), "--mesh", (in / "far.obj").string()},
       "far.obj: the mesh lies outside"},
      {{(in / "t.svo").string(), "--bogus"}, "--bogus"},
      {{(in / "t.svo").string(), "--memory-limit", "lots"}, "--memory-limit"},
      {{(in / "t.svo").string(), "--memory-limit", "1"}, "is too small for this file"},
      {{}, "input"},
  };
  for (const auto& [args, expect] : cases) {
    std::vector<std::string> a = args;
    a.push_back("-q");
    const ToolResult r = RunTool("svo-validate", a);
    EXPECT_EQ(r.exit_code, 2) << expect << ": " << r.err;
    const auto lines = r.ErrLines();
    ASSERT_EQ(lines.size(), 1u) << expect << ":\n" << r.err;
    EXPECT_TRUE(lines[0].starts_with("svo-validate: ")) << lines[0];
    EXPECT_NE(lines[0].find(expect), std::string::npos) << expect << " in " << lines[0];
    EXPECT_TRUE(r.out.empty()) << r.out;
  }
}

// The validator sees the mesh in the voxelizer's frame (the same transform and snapping), so any
// mesh that builds validates: vanishing and astronomic extents, far offsets, and triangles that
// snapping collapses to a point or a segment beside ordinary ones.
TEST(SvoValidateCli, AnyMeshThatBuildsValidates) {
  const TempDir dir;
  const auto tetrahedron = [](double size, double offset) {
    std::string obj;
    for (const auto& [x, y, z] :
         {std::array<double, 3>{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}}) {
      obj += fmt::format("v {} {} {}\n", offset + size * x, offset + size * y, offset + size * z);
    }
    return obj + "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
  };
  const std::vector<std::pair<std::string, std::string>> meshes = {
      {"extent-1e-30", tetrahedron(1e-30, 0)},
      {"extent-1e-300", tetrahedron(1e-300, 0)},
      {"extent-1e38", tetrahedron(1e38, -5e37)},
      {"coords-1e38",
       "v -1e38 -1e38 -1e38\nv 1e38 -1e38 -1e38\nv -1e38 1e38 -1e38\n"
       "v -1e38 -1e38 1e38\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"},
      {"offset-1e20", tetrahedron(1e18, 1e20)},
      {"offset-minus-1e20", tetrahedron(3e17, -1e20)},
      // A unit triangle at the origin and one near 1e20: the first snaps to a point.
      {"point-beside-1e20",
       "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1e20 1e20 1e20\n"
       "v 1.0001e20 1e20 1e20\nv 1e20 1.0001e20 1e20\nf 1 2 3\nf 4 5 6\n"},
      // A needle 1e-9 wide along a long diagonal: it snaps to a segment.
      {"segment-beside-tetrahedron",
       tetrahedron(1, 0) + "v 0 0 0\nv 1 1 1\nv 1 1.000000001 1\nf 5 6 7\n"},
  };
  // Where a voxel is finer than the coordinates' precision the mesh does not build (exit 2).
  dir.Write("below-precision.obj", tetrahedron(1e4, 1e20));
  const ToolResult refused = RunTool("mesh2svo", {(dir / "below-precision.obj").string(), "-o",
                                                  (dir / "below.svo").string(), "-r", "100", "-q"});
  EXPECT_EQ(refused.exit_code, 2) << refused.err;
  EXPECT_NE(refused.err.find("finer than the coordinates' precision"), std::string::npos)
      << refused.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "below.svo"));
  for (const auto& [name, obj] : meshes) {
    const std::string mesh = (dir / (name + ".obj")).string();
    const std::string svo = (dir / (name + ".svo")).string();
    dir.Write(name + ".obj", obj);
    for (const char* resolution : {"16", "100"}) {
      ToolResult r = RunTool("mesh2svo", {mesh, "-o", svo, "-r", resolution, "-q"});
      ASSERT_EQ(r.exit_code, 0) << name << " at " << resolution << ": " << r.err;
      r = RunTool("svo-validate", {svo, "--mesh", mesh, "--json", "-q"});
      ASSERT_EQ(r.exit_code, 0) << name << " at " << resolution << ":\n" << r.out << r.err;
      const auto j = nlohmann::json::parse(r.out);
      EXPECT_EQ(j["valid"], true) << name;
      // Every triangle counts, the collapsed ones too.
      const auto faces = static_cast<int>(std::count(obj.begin(), obj.end(), 'f'));
      EXPECT_EQ(j["checks"]["occupancy"]["stats"]["triangles"], faces) << name;
    }
  }
}

// A pruned build: the same bytes whole and by pages, valid against the octree it was pruned from
// (and its bricks unvouched for without it); refused where every voxel is needed, and refused
// without bricks, for a solid and with a malformed tolerance, leaving no file.
TEST(SvoValidateCli, PrunedOctreeValidatesAgainstItsFullOctree) {
  const TempDir dir;
  const std::string full = (dir / "full.svo").string(), pruned = (dir / "pruned.svo").string(),
                    paged = (dir / "paged.svo").string();
  const std::vector<std::string> build = {Torus(),        "-r",           "256",
                                          "--attributes", "color,normal", "-q"};
  const auto with = [&](std::vector<std::string> extra) {
    std::vector<std::string> args = build;
    args.insert(args.end(), extra.begin(), extra.end());
    return args;
  };
  ASSERT_EQ(RunTool("mesh2svo", with({"-o", full})).exit_code, 0);
  ToolResult r = RunTool("mesh2svo", with({"-o", pruned, "--prune", "default", "--json"}));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto report = nlohmann::json::parse(r.out);
  EXPECT_GT(report["pruned"]["leaves"], 0);
  EXPECT_LT(report["pruned"]["page_nodes_after"], report["pruned"]["page_nodes_before"]);
  EXPECT_LT(report["pruned"]["chunk_bytes_after"], report["pruned"]["chunk_bytes_before"]);
  r = RunTool("mesh2svo", with({"-o", paged, "--prune", "default", "--memory-limit", "24M"}));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(ReadText(paged), ReadText(pruned));

  r = RunTool("svo-validate", {pruned, "--reference", full, "--json", "-q"});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["checks"]["bricks"]["status"], "passed");
  EXPECT_EQ(j["checks"]["pruned_leaves"]["status"], "passed");
  EXPECT_GT(j["checks"]["pruned_leaves"]["stats"]["leaves"], 0);
  r = RunTool("svo-validate", {pruned, "--json", "-q"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["checks"]["pruned_leaves"]["status"], "skipped");
  // The full octree as its own reference is refused: it is not pruned from anything.
  r = RunTool("svo-validate", {pruned, "--reference", pruned, "-q"});
  EXPECT_EQ(r.exit_code, 1);

  const std::string ply = (dir / "x.ply").string();
  r = RunTool("svo-export", {pruned, "-o", ply, "-q"});
  EXPECT_EQ(r.exit_code, 2);
  ASSERT_EQ(r.ErrLines().size(), 1u) << r.err;
  EXPECT_NE(r.err.find("pruned.svo: a pruned octree"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(ply));
  const std::string refused = (dir / "refused.svo").string();
  for (const std::vector<std::string>& bad :
       {std::vector<std::string>{"--prune", "default", "--bricks", "none"},
        {"--prune", "default", "--fill", "solid"},
        {"--prune", "color=0.1,shape=2"}}) {
    std::vector<std::string> args = with({"-o", refused});
    args.insert(args.end(), bad.begin(), bad.end());
    r = RunTool("mesh2svo", args);
    EXPECT_EQ(r.exit_code, 2) << bad.back();
    EXPECT_NE(r.err.find("--prune"), std::string::npos) << r.err;
    EXPECT_FALSE(std::filesystem::exists(refused));
  }
}

}  // namespace
}  // namespace svokit::test
