// End-to-end tests of svo-import as a user runs it: exit codes, one-line errors, no partial files.

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "tests/cli/run_tool.hpp"

namespace svokit::test {
namespace {

TEST(SvoImportCli, HelpAndVersion) {
  ToolResult r = RunTool("svo-import", {"--help"});
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.out.find("--output"), std::string::npos);
  EXPECT_NE(r.out.find("--threads"), std::string::npos);
  r = RunTool("svo-import", {"--version"});
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.out.find("svokit " SVOKIT_VERSION), std::string::npos);
}

TEST(SvoImportCli, WritesSvmAndReport) {
  TempDir dir;
  const auto out = dir / "torus.svm";
  ToolResult r = RunTool("svo-import", {(DataDir() / "uv-torus.obj").string(), "-o", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("triangles          2304"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("surface            closed"), std::string::npos);
  ASSERT_TRUE(std::filesystem::exists(out));
  // The .svm is itself an input: same mesh, same report.
  ToolResult again = RunTool("svo-import", {out.string(), "--json", "--quiet"});
  ASSERT_EQ(again.exit_code, 0) << again.err;
  EXPECT_TRUE(again.err.empty());
  const auto j = nlohmann::json::parse(again.out);
  EXPECT_EQ(j["triangles"], 2304);
  EXPECT_EQ(j["textures"][0]["width"], 64);
}

TEST(SvoImportCli, OutputIsDeterministicForAnyThreadCount) {
  TempDir dir;
  const std::string in = (DataDir() / "uv-torus.obj").string();
  ASSERT_EQ(RunTool("svo-import", {in, "-o", (dir / "a.svm").string(), "--threads", "1"}).exit_code,
            0);
  ASSERT_EQ(RunTool("svo-import", {in, "-o", (dir / "b.svm").string(), "--threads", "2"}).exit_code,
            0);
  EXPECT_EQ(ReadText(dir / "a.svm"), ReadText(dir / "b.svm"));
  // The stored source name has no directories, so moving the input does not change the output.
  std::filesystem::copy_file(DataDir() / "uv-torus.obj", dir / "uv-torus.obj");
  std::filesystem::copy_file(DataDir() / "uv-torus.mtl", dir / "uv-torus.mtl");
  std::filesystem::copy_file(DataDir() / "uv-torus.png", dir / "uv-torus.png");
  ASSERT_EQ(RunTool("svo-import", {(dir / "uv-torus.obj").string(), "-o", (dir / "c.svm").string()})
                .exit_code,
            0);
  EXPECT_EQ(ReadText(dir / "a.svm"), ReadText(dir / "c.svm"));
}

TEST(SvoImportCli, MissingTextureIsAWarningNotAnError) {
  TempDir dir;
  dir.Write("m.mtl", "newmtl skin\nKd 0.5 0.5 0.5\nmap_Kd skin.png\n");
  const auto in =
      dir.Write("m.obj", "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl skin\nf 1 2 3\n");
  ToolResult r = RunTool("svo-import", {in.string(), "-o", (dir / "m.svm").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("texture skin.png MISSING, base colour used"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("warning            material 'skin': texture 'skin.png' not found"),
            std::string::npos);
  EXPECT_TRUE(std::filesystem::exists(dir / "m.svm"));
}

struct BadCase {
  std::string file;  // written into the temp dir; empty = the input does not exist
  std::string content;
  std::vector<std::string> args;  // "{in}" and "{dir}" are substituted
  std::string expect;             // substring of the one error line
};

TEST(SvoImportCli, BadInputIsOneLineExitTwoAndNoOutput) {
  const std::string tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  const std::vector<std::string> normal = {"{in}", "-o", "{dir}/out.svm"};
  const std::vector<BadCase> cases = {
      {"", "", normal, "missing.obj: no such file"},
      {"model.xyz", "1 2 3\n", normal, "unknown mesh format '.xyz'"},
      {"noext", "v 0 0 0\n", normal, "unknown mesh format"},
      {"bad.obj", tri + "f 1 2 9\n", normal, "bad.obj:4: face refers to vertex 9"},
      {"nan.obj", "v 0 nan 0\n", normal, "non-finite"},
      {"empty.obj", "", normal, "has no triangles"},
      {"corrupt.svm", "\x89SVM\r\n\x1a\n garbage garbage garbage", normal, "corrupt.svm:"},
      {"ok.obj", tri + "f 1 2 3\n", {"{in}", "-o", "{dir}/wrong.ply"}, "must be a .svm file"},
      {"ok.obj", tri + "f 1 2 3\n", {"{in}", "--threads", "-4"}, "--threads"},
      {"ok.obj", tri + "f 1 2 3\n", {"{in}", "--no-such-option"}, "no-such-option"},
      {"ok.obj", tri + "f 1 2 3\n", {"-o", "{dir}/out.svm"}, "input is required"},
  };
  for (const BadCase& c : cases) {
    TempDir dir;
    const std::string input =
        c.file.empty() ? (dir / "missing.obj").string() : dir.Write(c.file, c.content).string();
    std::vector<std::string> args;
    for (std::string a : c.args) {
      if (a == "{in}") a = input;
      if (a.starts_with("{dir}")) a = dir.path().string() + a.substr(5);
      args.push_back(a);
    }
    const auto before = dir.Files();
    ToolResult r = RunTool("svo-import", args);
    EXPECT_EQ(r.exit_code, 2) << c.expect << "\n" << r.err;
    ASSERT_EQ(r.ErrLines().size(), 1u) << r.err;
    EXPECT_NE(r.err.find(c.expect), std::string::npos) << r.err;
    EXPECT_EQ(r.err.rfind("svo-import: ", 0), 0u) << r.err;
    EXPECT_EQ(dir.Files(), before) << "partial output left behind for " << c.expect;
    EXPECT_TRUE(r.out.empty()) << r.out;
  }
}

TEST(SvoImportCli, QuietMeansSilentStderr) {
  TempDir dir;
  ToolResult r = RunTool("svo-import", {(DataDir() / "box-room.obj").string(), "-q"});
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_TRUE(r.err.empty()) << r.err;
  r = RunTool("svo-import", {(DataDir() / "box-room.obj").string()});
  EXPECT_NE(r.err.find("import"), std::string::npos);  // progress lines when not quiet
}

}  // namespace
}  // namespace svokit::test
