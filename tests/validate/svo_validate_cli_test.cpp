// svo-validate as a user runs it: exit 0 for a valid file, 1 with findings, 2 for unusable input
// (one line on stderr naming the file), and the JSON report's stable keys.

#include <gtest/gtest.h>

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
  ToolResult r = RunTool("svo-validate", {svo, "--mesh", Torus(), "-q"});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_TRUE(r.err.empty()) << r.err;
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

}  // namespace
}  // namespace svokit::test
