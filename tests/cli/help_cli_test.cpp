// Every tool's --help as a newcomer reads it: values as words and choices ("conservative|thin",
// not CLI11's enum maps), defaults after the descriptions, and one example at the end. And one
// convention for every tool's report: --json gives one JSON object with the text's keys, -q prints
// nothing on success.

#include <gtest/gtest.h>

#include <set>

#include <nlohmann/json.hpp>

#include "tests/cli/run_tool.hpp"

namespace svokit::test {
namespace {

const char* const kTools[] = {"svo-import",   "mesh2svo",    "svo-voxelize",
                              "svo-build",    "svo-merge",   "svo-export",
                              "svo-validate", "svo-inspect", "svo-bake"};

std::string Help(const std::string& tool) {
  const ToolResult r = RunTool(tool, {"--help"});
  EXPECT_EQ(r.exit_code, 0) << tool << ": " << r.err;
  return r.out;
}

void ExpectShows(const std::string& help, const std::vector<std::string>& parts,
                 const std::string& tool) {
  for (const std::string& part : parts) {
    EXPECT_NE(help.find(part), std::string::npos) << tool << " --help lacks \"" << part << "\":\n"
                                                  << help;
  }
}

TEST(HelpCli, EveryToolShowsWordsDefaultsAndAnExample) {
  for (const std::string tool : kTools) {
    const std::string help = Help(tool);
    ExpectShows(help,
                {tool == "svo-merge" ? "parts PART... REQUIRED" : "input FILE REQUIRED",
                 "-j,--threads N", "(default: 0)", "Example:\n  " + tool + " "},
                tool);
    // CLI11's type names and enum maps are not for people.
    for (const char* noise : {"ENUM", "->", "TEXT", "UINT", "FLOAT", "{false}", "OR {"}) {
      EXPECT_EQ(help.find(noise), std::string::npos) << tool << " --help shows " << noise << ":\n"
                                                     << help;
    }
  }
}

TEST(HelpCli, ChoicesAreListedOnceWithTheirDefaults) {
  for (const std::string tool : {"svo-voxelize", "mesh2svo"}) {
    ExpectShows(Help(tool),
                {"-r,--resolution N (not with --voxel-size)", "--mode conservative|thin",
                 "(default: conservative)", "--method triangle|fragment|hybrid",
                 "(default: hybrid)", "--attributes color,normal|color|normal|none",
                 "(default: color,normal)", "--hybrid-cutoff AREA", "(default: 4096)", "--pad N"},
                tool);
  }
  for (const std::string tool : {"svo-build", "mesh2svo"}) {
    ExpectShows(Help(tool), {"--bricks 3|2|none", "(default: 3)", "--contours,--no-contours"},
                tool);
  }
  ExpectShows(Help("svo-inspect"),
              {"--view front|back|left|right|top|bottom|iso", "(default: front)",
               "--shade color|normal|depth", "(default: color)", "--size WxH", "(default: 512x512)",
               "--slice AXIS=K FILE"},
              "svo-inspect");
}

TEST(HelpCli, EverySpellingOfAChoiceIsStillAccepted) {
  TempDir dir;
  const std::string mesh = (DataDir() / "uv-torus.obj").string();
  for (const std::vector<std::string>& choice :
       {std::vector<std::string>{"--attributes", "normal,color"},
        {"--attributes", "color,normal"},
        {"--mode", "THIN"},
        {"--method", "Fragment"}}) {
    std::vector<std::string> args = {mesh, "-o", (dir / "t.vfrag").string(), "-r", "16", "-q"};
    args.insert(args.end(), choice.begin(), choice.end());
    const ToolResult r = RunTool("svo-voxelize", args);
    EXPECT_EQ(r.exit_code, 0) << choice[0] << " " << choice[1] << ": " << r.err;
  }
  const ToolResult bad = RunTool("svo-voxelize", {mesh, "-o", (dir / "t.vfrag").string(), "-r",
                                                  "16", "--mode", "thick", "-q"});
  EXPECT_EQ(bad.exit_code, 2);
}

// Each tool on a small chain of files, as a pipeline runs it (its arguments after the input), and
// the keys its report has, in text and in JSON.
struct ToolRun {
  std::string tool;
  std::vector<std::string> args;
  std::vector<std::string> keys;
};
std::vector<ToolRun> Runs(const TempDir& dir) {
  const std::string mesh = (DataDir() / "tetra.off").string();
  const std::string svm = (dir / "t.svm").string(), vfrag = (dir / "t.vfrag").string();
  const std::string svo = (dir / "t.svo").string();
  const std::vector<std::string> octree = {"levels", "sections", "pages", "output"};
  auto with = [](std::vector<std::string> a, const std::vector<std::string>& b) {
    a.insert(a.end(), b.begin(), b.end());
    return a;
  };
  return {
      {"svo-import", {mesh, "-o", svm}, {"source", "triangles", "bounds", "warnings"}},
      {"svo-voxelize", {svm, "-r", "24", "-o", vfrag}, {"mesh", "grid", "voxels", "output"}},
      {"svo-build",
       {vfrag, "--mesh", mesh, "-o", svo},
       with({"input", "octree", "warnings"}, octree)},
      {"mesh2svo",
       {mesh, "-r", "24", "-o", (dir / "m.svo").string()},
       with({"mesh", "grid", "voxels", "time", "warnings"}, octree)},
      {"mesh2svo",
       {mesh, "-r", "200", "--pages", "0/2", "-o", (dir / "p0.svopart").string()},
       {"part", "time", "output"}},
      {"mesh2svo",
       {mesh, "-r", "200", "--pages", "1/2", "-o", (dir / "p1.svopart").string()},
       {"part", "output"}},
      {"svo-merge",
       {(dir / "p0.svopart").string(), (dir / "p1.svopart").string(), "-o",
        (dir / "merged.svo").string()},
       {"parts", "voxels", "sections", "pages", "time", "output"}},
      {"svo-export", {svo, "-o", (dir / "t.glb").string()}, {"octree", "level", "output"}},
      {"svo-bake",
       {svo, "-o", (dir / "ao.svo").string()},
       {"octree", "cones", "pages", "voxels", "output"}},
      {"svo-inspect", {svo}, {"file", "grid", "octree", "voxels"}},
      {"svo-validate", {svo, "--mesh", mesh}, {"file", "valid", "findings", "warnings"}},
  };
}

TEST(ReportCli, EveryToolAnswersJsonAndQuietPrintsNothing) {
  TempDir dir;
  std::set<std::string> tools;
  for (const ToolRun& run : Runs(dir)) {
    tools.insert(run.tool);
    std::vector<std::string> json = run.args, quiet = run.args;
    json.push_back("--json");
    quiet.push_back("-q");
    const ToolResult q = RunTool(run.tool, quiet);
    ASSERT_EQ(q.exit_code, 0) << run.tool << ": " << q.err;
    EXPECT_EQ(q.out + q.err, "") << run.tool << " -q";
    const ToolResult j = RunTool(run.tool, json);
    ASSERT_EQ(j.exit_code, 0) << run.tool << ": " << j.err;
    nlohmann::json report;
    ASSERT_NO_THROW(report = nlohmann::json::parse(j.out)) << run.tool << " --json:\n" << j.out;
    ASSERT_TRUE(report.is_object()) << run.tool;
    // One spelling in JSON keys and names, "color" (text and messages may say colour).
    std::vector<const nlohmann::json*> todo{&report};
    while (!todo.empty()) {
      const nlohmann::json* node = todo.back();
      todo.pop_back();
      if (node->is_object()) {
        for (const auto& [key, value] : node->items()) {
          EXPECT_EQ(key.find("colour"), std::string::npos) << run.tool << ": key " << key;
          if (key == "name" && value.is_string()) {
            EXPECT_EQ(value.get<std::string>().find("colour"), std::string::npos) << run.tool;
          }
          todo.push_back(&value);
        }
      } else if (node->is_array()) {
        for (const auto& value : *node) todo.push_back(&value);
      }
    }
    for (const std::string& key : run.keys) {
      EXPECT_TRUE(report.contains(key)) << run.tool << ": no \"" << key << "\" in\n" << j.out;
    }
  }
  EXPECT_EQ(tools.size(), std::size(kTools));
}

}  // namespace
}  // namespace svokit::test
