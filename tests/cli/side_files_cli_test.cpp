// Side files where users bake: a material library naming /etc/passwd is never read into an output;
// every tool that imports prints each import warning (one line, "TOOL: warning: FILE: ...") and
// counts it in its summary; --strict makes any warning exit 2 with nothing written; --asset-path
// allows a folder; and no side output may replace a file the import read.

#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tests/cli/run_tool.hpp"
#include "tests/test_util.hpp"

namespace svokit::test {
namespace {

namespace fs = std::filesystem;

const std::string kTriangle = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n";

// A textured triangle in `dir`: m.obj naming m.mtl, whose material `m` has map_Kd `texture`.
fs::path TexturedTriangle(const TempDir& dir, const std::string& texture) {
  dir.Write("m.mtl", "newmtl m\nKd 1 0 0\nmap_Kd " + texture + "\n");
  return dir.Write("m.obj", "mtllib m.mtl\n" + kTriangle + "usemtl m\nf 1/1 2/2 3/3\n");
}

// Lines of `r`'s stderr that are warnings of `tool`.
std::vector<std::string> WarningLines(const ToolResult& r, const std::string& tool) {
  std::vector<std::string> warnings;
  for (const std::string& line : r.ErrLines()) {
    if (line.starts_with(tool + ": warning: ")) warnings.push_back(line);
  }
  return warnings;
}

// The first line of /etc/passwd ("root:x:0:0:..."), which no output may hold.
std::string PasswdLine() {
  const std::string passwd = ReadText("/etc/passwd");
  return passwd.substr(0, passwd.find('\n'));
}

// An MTL naming ../../../../etc/passwd (as many ".." as it takes) read that file and embedded its
// bytes in the .svm, exit 0: now the texture is refused with a warning naming the option, and
// neither output holds a byte of it.
TEST(SideFilesCli, PasswdIsNeverReadIntoAnOutput) {
  TempDir dir;
  const std::string up = "../../../../../../../../../../../../../../../../";
  const fs::path obj = TexturedTriangle(dir, up + "etc/passwd");
  const std::string line = PasswdLine();
  ASSERT_FALSE(line.empty());

  const ToolResult import =
      RunTool("svo-import", {obj.string(), "-o", (dir / "m.svm").string(), "-q"}, 60);
  ASSERT_EQ(import.exit_code, 0) << import.err;
  const std::vector<std::string> warnings = WarningLines(import, "svo-import");
  ASSERT_EQ(warnings.size(), 1u) << import.err;
  EXPECT_NE(
      warnings[0].find("svo-import: warning: " + obj.string() + ": material 'm': texture '" + up +
                       "etc/passwd' resolves to /etc/passwd, outside the model's folder"),
      std::string::npos)
      << warnings[0];
  EXPECT_NE(warnings[0].find("--asset-path"), std::string::npos) << warnings[0];
  EXPECT_EQ(ReadText(dir / "m.svm").find(line), std::string::npos);

  const ToolResult bake =
      RunTool("mesh2svo", {obj.string(), "-r", "8", "-o", (dir / "m.svo").string(), "-q"}, 60);
  ASSERT_EQ(bake.exit_code, 0) << bake.err;
  EXPECT_EQ(WarningLines(bake, "mesh2svo").size(), 1u) << bake.err;
  EXPECT_EQ(ReadText(dir / "m.svo").find(line), std::string::npos);
}

struct WarningCase {
  std::string name;
  std::string texture;             // map_Kd; empty: the OBJ names a library that is missing
  std::vector<std::string> extra;  // more options
  std::string expect;              // in the warning
};

const std::vector<WarningCase>& WarningCases() {
  static const std::vector<WarningCase> cases = {
      {"missing texture", "skin.png", {}, "material 'm': texture 'skin.png' not found"},
      {"missing library", "", {}, "material library 'nowhere.mtl' not found"},
      {"device texture",
       "/dev/zero",
       {"--asset-path", "/dev"},
       "texture '/dev/zero' is a character device"},
  };
  return cases;
}

fs::path WarningModel(const TempDir& dir, const WarningCase& c) {
  if (!c.texture.empty()) return TexturedTriangle(dir, c.texture);
  return dir.Write("m.obj", "mtllib nowhere.mtl\n" + kTriangle + "f 1 2 3\n");
}

// mesh2svo and svo-voxelize baked the base colour, exit 0, and printed nothing (only svo-import
// warned): each warning is now one line on stderr and counted in the summary; with --strict the
// run is exit 2 and writes nothing.
TEST(SideFilesCli, BakingToolsPrintImportWarningsAndStrictRefuses) {
  struct Tool {
    std::string name, output;
  };
  for (const Tool& tool : {Tool{"mesh2svo", "o.svo"}, Tool{"svo-voxelize", "o.vfrag"}}) {
    for (const WarningCase& c : WarningCases()) {
      SCOPED_TRACE(tool.name + ", " + c.name);
      TempDir dir;
      const fs::path obj = WarningModel(dir, c);
      std::vector<std::string> args = {obj.string(), "-r", "8", "-o", (dir / tool.output).string()};
      args.insert(args.end(), c.extra.begin(), c.extra.end());
      const ToolResult r = RunTool(tool.name, args, 60);
      ASSERT_EQ(r.exit_code, 0) << r.err;
      const std::vector<std::string> warnings = WarningLines(r, tool.name);
      ASSERT_EQ(warnings.size(), 1u) << r.err;
      EXPECT_TRUE(warnings[0].starts_with(tool.name + ": warning: " + obj.string() + ": "))
          << warnings[0];
      EXPECT_NE(warnings[0].find(c.expect), std::string::npos) << warnings[0];
      EXPECT_NE(r.out.find("warnings    1\n"), std::string::npos) << r.out;

      fs::remove(dir / tool.output);
      args.push_back("--strict");
      const ToolResult strict = RunTool(tool.name, args, 60);
      EXPECT_EQ(strict.exit_code, 2) << strict.err;
      EXPECT_FALSE(fs::exists(dir / tool.output));
      const std::vector<std::string> lines = strict.ErrLines();
      ASSERT_FALSE(lines.empty());
      EXPECT_NE(lines.back().find("--strict"), std::string::npos) << strict.err;
      EXPECT_EQ(dir.Files().size(), fs::exists(dir / "m.mtl") ? 2u : 1u);
    }
  }
}

// The other importing tools print the same warning, count it (--json too), and refuse with
// --strict.
TEST(SideFilesCli, EveryImportingToolWarnsAndCounts) {
  TempDir dir;
  const fs::path obj = TexturedTriangle(dir, "skin.png");
  const std::string svo = (dir / "m.svo").string();
  ASSERT_EQ(RunTool("mesh2svo", {obj.string(), "-r", "8", "-o", svo, "-q"}, 60).exit_code, 0);
  const std::string expect = obj.string() + ": material 'm': texture 'skin.png' not found";

  const ToolResult import = RunTool("svo-import", {obj.string(), "--json", "-q"}, 60);
  ASSERT_EQ(import.exit_code, 0) << import.err;
  ASSERT_EQ(WarningLines(import, "svo-import").size(), 1u) << import.err;
  EXPECT_EQ(nlohmann::json::parse(import.out)["warnings"].size(), 1u);

  const ToolResult validate = RunTool("svo-validate", {svo, "--mesh", obj.string(), "--json"}, 60);
  ASSERT_EQ(validate.exit_code, 0) << validate.err;
  ASSERT_EQ(WarningLines(validate, "svo-validate").size(), 1u) << validate.err;
  EXPECT_NE(validate.err.find(expect), std::string::npos) << validate.err;
  EXPECT_EQ(nlohmann::json::parse(validate.out)["warnings"], 1);

  const ToolResult bake = RunTool("svo-bake",
                                  {svo, "--ao", "--mesh", obj.string(), "--vertex-out",
                                   (dir / "ao.ply").string(), "-q", "--json"},
                                  60);
  ASSERT_EQ(bake.exit_code, 0) << bake.err;
  ASSERT_EQ(WarningLines(bake, "svo-bake").size(), 1u) << bake.err;
  EXPECT_EQ(nlohmann::json::parse(bake.out)["warnings"], 1);

  for (const auto& [tool, args] : std::vector<std::pair<std::string, std::vector<std::string>>>{
           {"svo-import", {obj.string(), "-o", (dir / "s.svm").string()}},
           {"svo-validate", {svo, "--mesh", obj.string()}},
           {"svo-bake",
            {svo, "--ao", "--mesh", obj.string(), "--vertex-out", (dir / "s.ply").string()}}}) {
    SCOPED_TRACE(tool);
    std::vector<std::string> strict = args;
    strict.insert(strict.end(), {"--strict", "-q"});
    const ToolResult r = RunTool(tool, strict, 60);
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_FALSE(fs::exists(dir / "s.svm"));
    EXPECT_FALSE(fs::exists(dir / "s.ply"));
  }
}

// A .svm keeps its materials' missing textures: baking it warns again, and --strict refuses it.
TEST(SideFilesCli, ReimportedSvmWarnsAgain) {
  TempDir dir;
  const fs::path obj = TexturedTriangle(dir, "skin.png");
  const std::string svm = (dir / "m.svm").string();
  ASSERT_EQ(RunTool("svo-import", {obj.string(), "-o", svm, "-q"}, 60).exit_code, 0);
  const ToolResult r = RunTool("mesh2svo", {svm, "-r", "8", "-o", (dir / "m.svo").string()}, 60);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::vector<std::string> warnings = WarningLines(r, "mesh2svo");
  ASSERT_EQ(warnings.size(), 1u) << r.err;
  EXPECT_NE(warnings[0].find(svm + ": material 'm': texture 'skin.png'"), std::string::npos)
      << warnings[0];
  EXPECT_EQ(RunTool("mesh2svo", {svm, "-r", "8", "-o", (dir / "s.svo").string(), "--strict"}, 60)
                .exit_code,
            2);
  EXPECT_FALSE(fs::exists(dir / "s.svo"));
}

// --asset-path DIR lets a texture outside the model's folder be read; without it the texture is
// refused with a warning naming the option.
TEST(SideFilesCli, AssetPathAllowsATextureFolder) {
  TempDir dir;
  fs::create_directories(dir / "model");
  fs::create_directories(dir / "shared");
  fs::copy_file(DataDir() / "uv-torus.png", dir / "shared" / "t.png");
  dir.Write("model/m.mtl", "newmtl m\nKd 1 0 0\nmap_Kd ../shared/t.png\n");
  const fs::path obj =
      dir.Write("model/m.obj", "mtllib m.mtl\n" + kTriangle + "usemtl m\nf 1/1 2/2 3/3\n");
  const std::vector<std::string> args = {obj.string(), "-r", "8", "-o", (dir / "m.svo").string()};
  const ToolResult refused = RunTool("mesh2svo", args, 60);
  ASSERT_EQ(refused.exit_code, 0) << refused.err;
  const std::vector<std::string> warnings = WarningLines(refused, "mesh2svo");
  ASSERT_EQ(warnings.size(), 1u) << refused.err;
  EXPECT_NE(warnings[0].find("--asset-path"), std::string::npos) << warnings[0];

  std::vector<std::string> allowed = args;
  allowed.insert(allowed.end(), {"--asset-path", (dir / "shared").string()});
  const ToolResult r = RunTool("mesh2svo", allowed, 60);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(WarningLines(r, "mesh2svo").empty()) << r.err;
  EXPECT_NE(r.out.find("warnings    0\n"), std::string::npos) << r.out;
}

// svo-bake --texture-out over the mesh's own texture succeeded (only the .svo was compared):
// every side output is checked against every input the import read, and refused in one line.
TEST(SideFilesCli, SideOutputOverAnInputIsRefused) {
  TempDir dir;
  for (const char* name : {"uv-torus.obj", "uv-torus.mtl", "uv-torus.png"}) {
    fs::copy_file(DataDir() / name, dir / name);
  }
  const std::string obj = (dir / "uv-torus.obj").string(), svo = (dir / "t.svo").string();
  ASSERT_EQ(RunTool("mesh2svo", {obj, "-r", "16", "-o", svo, "-q"}, 120).exit_code, 0);
  const std::string png = ReadText(dir / "uv-torus.png");
  const ToolResult r = RunTool(
      "svo-bake",
      {svo, "--ao", "--mesh", obj, "--texture-out", (dir / "uv-torus.png").string(), "-q"}, 120);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  ASSERT_EQ(r.ErrLines().size(), 1u) << r.err;
  EXPECT_NE(r.err.find("uv-torus.png: is the input file"), std::string::npos) << r.err;
  EXPECT_EQ(ReadText(dir / "uv-torus.png"), png);
}

}  // namespace
}  // namespace svokit::test
