// Every tool's --help as a newcomer reads it: values as words and choices ("conservative|thin",
// not CLI11's enum maps), defaults after the descriptions, and one example at the end.

#include <gtest/gtest.h>

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

}  // namespace
}  // namespace svokit::test
