// svo-build and mesh2svo as a user runs them: the two routes give the same file, the files do
// not depend on the thread count, and bad input is one line on stderr, exit 2, no output left.

#include <gtest/gtest.h>

#include <fstream>
#include <functional>
#include <sstream>

#include "svokit/formats/provenance.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/formats/vfrag/vfrag.hpp"
#include "tests/cli/run_tool.hpp"

namespace svokit::test {
namespace {

std::string Torus() {
  return (DataDir() / "uv-torus.obj").string();
}

// Runs a tool that must succeed.
void RunOk(const std::string& tool, const std::vector<std::string>& args) {
  const ToolResult r = RunTool(tool, args);
  ASSERT_EQ(r.exit_code, 0) << tool << ": " << r.err;
}

TEST(SvoBuildCli, ChainEqualsMesh2svoByteForByte) {
  TempDir dir;
  const std::string vfrag = (dir / "t.vfrag").string();
  RunOk("svo-voxelize", {Torus(), "-o", vfrag, "-r", "48", "-q"});
  const std::string chained = (dir / "chain.svo").string(), direct = (dir / "direct.svo").string();
  ToolResult build =
      RunTool("svo-build", {vfrag, "-o", chained, "--mesh", Torus(), "-q", "--json"});
  ASSERT_EQ(build.exit_code, 0) << build.err;
  EXPECT_TRUE(build.err.empty()) << build.err;
  EXPECT_NE(build.out.find("chain.svo"), std::string::npos) << build.out;
  ToolResult m2s = RunTool("mesh2svo", {Torus(), "-o", direct, "-r", "48", "-q", "--json"});
  ASSERT_EQ(m2s.exit_code, 0) << m2s.err;
  EXPECT_NE(m2s.out.find("\"triangles\": 2304"), std::string::npos) << m2s.out;
  const std::string a = ReadText(chained), b = ReadText(direct);
  ASSERT_FALSE(a.empty());
  auto sa = ReadSvo(chained), sb = ReadSvo(direct);
  ASSERT_TRUE(sa.ok()) << sa.status().message();
  ASSERT_TRUE(sb.ok()) << sb.status().message();
  EXPECT_EQ(sa->metadata, sb->metadata) << "both routes must record the same metadata";
  EXPECT_TRUE(*sa == *sb) << "the octrees differ";
  EXPECT_TRUE(a == b) << "files differ: " << a.size() << " vs " << b.size() << " bytes";
  ExpectValidSvo(chained, Torus());
  ExpectValidSvo(direct, Torus());

  // What the file holds: the voxels of the .vfrag, bricks 3 with colour and normal, contours,
  // and metadata naming the source and the options.
  auto voxels = ReadVfrag(vfrag);
  ASSERT_TRUE(voxels.ok());
  EXPECT_EQ(sa->LevelKeys(sa->depth),
            std::vector<std::uint64_t>(voxels->keys.begin(), voxels->keys.end()));
  EXPECT_EQ(sa->grid, voxels->grid);
  EXPECT_EQ(sa->depth, 6u);
  EXPECT_EQ(sa->brick_side, 3u);
  EXPECT_TRUE(sa->has_color && sa->has_normal && sa->has_contours);
  const Provenance meta = ParseProvenance(sa->metadata);
  EXPECT_EQ(meta.source, "uv-torus.obj") << sa->metadata;
  EXPECT_EQ(meta.triangles, 2304u);
  EXPECT_EQ(meta.grid, (GridFit{48, 0, 0})) << sa->metadata;
  EXPECT_EQ(meta.voxelize, (VoxelSettings{VoxelMode::kConservative, true, true, false}));
  EXPECT_EQ(meta.build, BuildSettings{}) << sa->metadata;
}

TEST(SvoBuildCli, ChainEqualsMesh2svoWithOtherOptions) {
  TempDir dir;
  const std::string vfrag = (dir / "t.vfrag").string();
  RunOk("svo-voxelize",
        {Torus(), "-o", vfrag, "-r", "40", "--mode", "thin", "--attributes", "color", "-q"});
  RunOk("svo-build",
        {vfrag, "-o", (dir / "a.svo").string(), "--bricks", "2", "--no-contours", "-q"});
  RunOk("mesh2svo", {Torus(), "-o", (dir / "b.svo").string(), "-r", "40", "--mode", "thin",
                     "--attributes", "color", "--bricks", "2", "--no-contours", "-q"});
  auto sa = ReadSvo(dir / "a.svo");
  ASSERT_TRUE(sa.ok()) << sa.status().message();
  EXPECT_EQ(sa->brick_side, 2u);
  EXPECT_TRUE(sa->has_color);
  EXPECT_FALSE(sa->has_normal);
  EXPECT_EQ(sa->mode, VoxelMode::kThin);
  auto sb = ReadSvo(dir / "b.svo");
  ASSERT_TRUE(sb.ok()) << sb.status().message();
  EXPECT_EQ(sa->metadata, sb->metadata);
  EXPECT_TRUE(ReadText(dir / "a.svo") == ReadText(dir / "b.svo"));
  ExpectValidSvo((dir / "a.svo").string(), Torus());  // thin, bricks 2, no contours
}

TEST(SvoBuildCli, NoContoursNeedsNoMesh) {
  TempDir dir;
  const std::string vfrag = (dir / "t.vfrag").string();
  RunOk("svo-voxelize", {Torus(), "-o", vfrag, "-r", "32", "-q"});
  ToolResult r = RunTool("svo-build", {vfrag, "-o", (dir / "n.svo").string(), "--no-contours"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  auto svo = ReadSvo(dir / "n.svo");
  ASSERT_TRUE(svo.ok()) << svo.status().message();
  EXPECT_FALSE(svo->has_contours);
  for (const SvoLevel& lv : svo->levels) EXPECT_TRUE(lv.contours.empty());
  EXPECT_EQ(svo->brick_side, 3u);
  EXPECT_FALSE(ParseProvenance(svo->metadata).build->contours) << svo->metadata;
  // Without bricks either: nodes only.
  RunOk("svo-build",
        {vfrag, "-o", (dir / "bare.svo").string(), "--bricks", "none", "--no-contours", "-q"});
  auto bare = ReadSvo(dir / "bare.svo");
  ASSERT_TRUE(bare.ok());
  EXPECT_EQ(bare->brick_side, 0u);
  EXPECT_EQ(bare->LevelKeys(bare->depth), svo->LevelKeys(svo->depth));
  EXPECT_LT(std::filesystem::file_size(dir / "bare.svo"),
            std::filesystem::file_size(dir / "n.svo"));
  ExpectValidSvo((dir / "n.svo").string(), Torus());
  ExpectValidSvo((dir / "bare.svo").string(), Torus());
}

TEST(SvoBuildCli, ThreadCountDoesNotChangeTheFile) {
  TempDir dir;
  for (const char* threads : {"1", "2"}) {
    RunOk("mesh2svo", {Torus(), "-o", (dir / fmt::format("m{}.svo", threads)).string(), "-r", "64",
                       "-j", threads, "-q"});
  }
  const std::string one = ReadText(dir / "m1.svo");
  ASSERT_GT(one.size(), 1000u);
  EXPECT_TRUE(one == ReadText(dir / "m2.svo")) << "mesh2svo -j 1 and -j 2 differ";

  const std::string vfrag = (dir / "t.vfrag").string();
  RunOk("svo-voxelize", {Torus(), "-o", vfrag, "-r", "64", "-q"});
  for (const char* threads : {"1", "2"}) {
    RunOk("svo-build", {vfrag, "-o", (dir / fmt::format("b{}.svo", threads)).string(), "--mesh",
                        Torus(), "-j", threads, "-q"});
  }
  EXPECT_TRUE(ReadText(dir / "b1.svo") == ReadText(dir / "b2.svo"))
      << "svo-build -j 1 and -j 2 differ";
  EXPECT_TRUE(ReadText(dir / "b1.svo") == one) << "svo-build differs from mesh2svo at 64";
  ExpectValidSvo((dir / "m1.svo").string(), Torus());
}

// mesh2svo on the torus at 300 (4³ page cubes; bricks, colour, normal and contours) into `out`,
// with `extra` options.
ToolResult Mesh2svoTorus300(const std::filesystem::path& out, std::vector<std::string> extra) {
  std::vector<std::string> args = {Torus(), "-o", out.string(), "-r", "300", "-q"};
  args.insert(args.end(), extra.begin(), extra.end());
  return RunTool("mesh2svo", args);
}

// mesh2svo --memory-limit builds page by page into the same file; sizes it cannot parse and
// limits too small for one page are one-line errors that leave no file.
TEST(SvoBuildCli, MemoryLimitWritesTheSameFile) {
  TempDir dir;
  auto run = [&](const std::string& name, std::vector<std::string> extra) {
    return Mesh2svoTorus300(dir / name, std::move(extra));
  };
  ASSERT_EQ(run("whole.svo", {}).exit_code, 0);
  for (const char* limit : {"64M", "1G", "100000000"}) {
    const ToolResult r = run("paged.svo", {"--memory-limit", limit});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_TRUE(ReadText(dir / "paged.svo") == ReadText(dir / "whole.svo")) << limit;
  }
  ExpectValidSvo((dir / "paged.svo").string(), Torus());
  for (const auto& [args, message] : std::vector<std::pair<std::vector<std::string>, std::string>>{
           {{"--memory-limit", "4Q"}, "expected a size"},
           {{"--memory-limit", "0"}, "expected a size"},
           {{"--memory-limit", "1M"}, "too small"}}) {
    const ToolResult r = run("bad.svo", args);
    EXPECT_NE(r.exit_code, 0) << args[1];
    ASSERT_EQ(r.ErrLines().size(), 1u) << r.err;
    EXPECT_NE(r.err.find(message), std::string::npos) << r.err;
    EXPECT_FALSE(std::filesystem::exists(dir / "bad.svo"));
  }
}

// svo-build --memory-limit reads the .vfrag a page at a time: the file svo-build writes whole
// (and so mesh2svo's), with bricks of either side and contours or without; a damaged .vfrag is a
// one-line error that leaves no file.
TEST(SvoBuildCli, BuildFromAVfragByPagesWritesTheSameFile) {
  TempDir dir;
  const std::string vfrag = (dir / "t.vfrag").string(), svm = (dir / "t.svm").string();
  RunOk("svo-import", {Torus(), "-o", svm, "-q"});
  RunOk("svo-voxelize", {svm, "-o", vfrag, "-r", "300", "-q"});
  for (const std::vector<std::string>& options :
       std::vector<std::vector<std::string>>{{"--mesh", svm},
                                             {"--bricks", "2", "--no-contours"},
                                             {"--bricks", "none", "--mesh", svm}}) {
    std::vector<std::string> whole = {vfrag, "-o", (dir / "whole.svo").string(), "-q"};
    whole.insert(whole.end(), options.begin(), options.end());
    RunOk("svo-build", whole);
    for (const char* threads : {"1", "2"}) {
      std::vector<std::string> paged = {
          vfrag, "-o", (dir / "paged.svo").string(), "-q", "--memory-limit", "64M", "-j", threads};
      paged.insert(paged.end(), options.begin(), options.end());
      RunOk("svo-build", paged);
      EXPECT_TRUE(ReadText(dir / "paged.svo") == ReadText(dir / "whole.svo"))
          << options[0] << " " << options[1] << ", -j " << threads;
    }
  }
  // A flipped byte in the keys (caught as a key out of order or outside the grid, else by the
  // checksum) and in the per-voxel arrays (by the checksum).
  const std::string bytes = ReadText(vfrag);
  auto set = ReadVfrag(vfrag);
  ASSERT_TRUE(set.ok());
  for (const auto& [at, expect] : std::vector<std::pair<std::size_t, std::string>>{
           {4096, "bad.vfrag: "}, {bytes.size() - 2 * set->size(), "checksum mismatch"}}) {
    std::string damaged = bytes;
    damaged[at] = static_cast<char>(damaged[at] ^ 0x10);
    const std::filesystem::path bad = dir / "bad.vfrag";
    { std::ofstream(bad, std::ios::binary) << damaged; }
    const ToolResult r = RunTool("svo-build", {bad.string(), "-o", (dir / "bad.svo").string(),
                                               "--no-contours", "--memory-limit", "64M", "-q"});
    EXPECT_EQ(r.exit_code, 2) << r.err;
    ASSERT_EQ(r.ErrLines().size(), 1u) << r.err;
    EXPECT_NE(r.err.find(expect), std::string::npos) << r.err;
    EXPECT_FALSE(std::filesystem::exists(dir / "bad.svo"));
  }
}

// Without --memory-limit, each tool goes page (or cube) by page when the whole run would not fit
// in half the memory it may count on (SVOKIT_MACHINE_MEMORY stands in for a small machine or
// a batch job's allocation), says so, and writes the same file.
TEST(SvoBuildCli, ASmallMachineGoesByPagesByItselfToTheSameFile) {
  TempDir dir;
  const std::string vfrag = (dir / "t.vfrag").string();
  const auto small = [](const char* size) {
    return RunOptions{120, 0, 0, {"env", std::string("SVOKIT_MACHINE_MEMORY=") + size}};
  };
  struct Case {
    std::string tool;
    std::vector<std::string> args;
    const char* machine;
    std::string says;
  };
  const std::vector<Case> cases = {
      {"svo-voxelize",
       {Torus(), "-r", "1000", "-o", "{out}"},
       "32M",
       "voxelize    by cubes within"},
      {"mesh2svo", {Torus(), "-r", "300", "-o", "{out}"}, "40M", "build       by pages within"},
      {"svo-build", {"{vfrag}", "--no-contours", "-o", "{out}"}, "40M", "by pages within"}};
  RunOk("svo-voxelize", {Torus(), "-o", vfrag, "-r", "300", "-q"});
  for (const Case& c : cases) {
    const std::string ext = c.tool == "svo-voxelize" ? ".vfrag" : ".svo";
    std::vector<std::string> whole, small_run;
    for (const std::string& a : c.args) {
      const std::string v = a == "{vfrag}" ? vfrag : a;
      whole.push_back(v == "{out}" ? (dir / ("whole" + ext)).string() : v);
      small_run.push_back(v == "{out}" ? (dir / ("small" + ext)).string() : v);
    }
    RunOk(c.tool, whole);
    const ToolResult r = RunTool(c.tool, small_run, small(c.machine));
    ASSERT_EQ(r.exit_code, 0) << c.tool << ": " << r.err;
    EXPECT_NE(r.out.find(c.says), std::string::npos) << c.tool << ": " << r.out;
    EXPECT_NE(r.out.find("half the machine"), std::string::npos) << r.out;
    EXPECT_TRUE(ReadText(dir / ("small" + ext)) == ReadText(dir / ("whole" + ext))) << c.tool;
    // A machine far larger: the whole run, as before.
    const ToolResult big = RunTool(c.tool, small_run, small("1T"));
    ASSERT_EQ(big.exit_code, 0) << big.err;
    EXPECT_EQ(big.out.find("half the machine"), std::string::npos) << big.out;
  }
}

// mesh2svo --pages K/N as separate jobs, then svo-merge: the whole build's file. A wrong set of
// parts, a part number that does not exist or a part file for an .svo are one-line errors.
TEST(SvoBuildCli, PartsMergeIntoTheSameFile) {
  TempDir dir;
  auto mesh2svo = [&](const std::string& name, std::vector<std::string> extra) {
    return Mesh2svoTorus300(dir / name, std::move(extra));
  };
  ASSERT_EQ(mesh2svo("whole.svo", {}).exit_code, 0);
  std::vector<std::string> parts;
  for (int k = 3; k-- > 0;) {
    parts.push_back((dir / fmt::format("t{}.svopart", k)).string());
    const ToolResult r =
        mesh2svo(fmt::format("t{}.svopart", k), {"--pages", fmt::format("{}/3", k)});
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  std::vector<std::string> merge = parts;
  merge.insert(merge.end(), {"-o", (dir / "merged.svo").string(), "-q", "--json"});
  const ToolResult merged = RunTool("svo-merge", merge);
  ASSERT_EQ(merged.exit_code, 0) << merged.err;
  EXPECT_NE(merged.out.find("voxels"), std::string::npos) << merged.out;
  EXPECT_TRUE(ReadText(dir / "merged.svo") == ReadText(dir / "whole.svo"));

  const ToolResult missing =
      RunTool("svo-merge", {parts[0], parts[2], "-o", (dir / "bad.svo").string(), "-q"});
  EXPECT_NE(missing.exit_code, 0);
  EXPECT_EQ(missing.ErrLines().size(), 1u) << missing.err;
  EXPECT_NE(missing.err.find("part 1 of 3 is missing"), std::string::npos) << missing.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "bad.svo"));
  for (const char* bad : {"3/3", "1", "a/2", "1/0"}) {
    const ToolResult r = mesh2svo("bad.svopart", {"--pages", bad});
    EXPECT_NE(r.exit_code, 0) << bad;
    EXPECT_NE(r.err.find("expected K/N"), std::string::npos) << r.err;
  }
  const ToolResult wrong_name = mesh2svo("bad.svo", {"--pages", "0/2"});
  EXPECT_NE(wrong_name.exit_code, 0);
  EXPECT_NE(wrong_name.err.find(".svopart"), std::string::npos) << wrong_name.err;
}

TEST(SvoBuildCli, Mesh2svoPrintsOneLinePerStageAndASummary) {
  TempDir dir;
  const std::string out = (dir / "t.svo").string();
  const ToolResult r = RunTool("mesh2svo", {Torus(), "-o", out, "-r", "32"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // Not a terminal: one line per finished stage on stderr.
  const auto lines = r.ErrLines();
  for (const char* stage : {"import", "voxelize", "octree", "bricks", "contours", "write"}) {
    EXPECT_EQ(std::count_if(lines.begin(), lines.end(),
                            [&](const std::string& l) {
                              return l.starts_with(stage) && l.find("done") != std::string::npos;
                            }),
              1)
        << stage << " in\n"
        << r.err;
  }
  auto svo = ReadSvo(out);
  ASSERT_TRUE(svo.ok()) << svo.status().message();
  ExpectValidSvo(out, Torus());
  // The summary: triangles, voxels, nodes per level (matching the file), time per stage, bytes.
  EXPECT_NE(r.out.find("2304 triangles"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find(fmt::format("voxels      {}", svo->voxel_count())), std::string::npos)
      << r.out;
  for (std::uint32_t l = 0; l <= svo->depth; ++l) {
    bool found = false;
    std::size_t start = 0;
    while (start < r.out.size() && !found) {
      const std::size_t end = r.out.find('\n', start);
      std::istringstream row(r.out.substr(start, end - start));
      std::string level, size, nodes;
      if (row >> level >> size >> nodes) {
        found = level == std::to_string(l) && nodes == std::to_string(svo->levels[l].node_count);
      }
      start = end == std::string::npos ? r.out.size() : end + 1;
    }
    EXPECT_TRUE(found) << "level " << l << " with " << svo->levels[l].node_count << " nodes in\n"
                       << r.out;
  }
  EXPECT_NE(r.out.find("time"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("total"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find(fmt::format("({} bytes)", std::filesystem::file_size(out))),
            std::string::npos)
      << r.out;
}

struct BadCase {
  std::string what;
  std::vector<std::string> args;  // "{in}" → the input directory, "{out}" → the output directory
  std::string expect;             // a part of the error line
};

// Each case: exit 2, stderr exactly one line "<tool>: ..." holding `expect`, the output
// directory left empty. Run once quiet and once with progress (the error is then the last line
// and the only one starting with the tool's name).
void ExpectBadInput(const std::string& tool, const TempDir& in, const BadCase& c) {
  for (bool quiet : {true, false}) {
    TempDir out;
    std::vector<std::string> args;
    for (std::string a : c.args) {
      if (a.starts_with("{in}")) a = in.path().string() + a.substr(4);
      if (a.starts_with("{out}")) a = out.path().string() + a.substr(5);
      args.push_back(a);
    }
    if (quiet) args.push_back("-q");
    const ToolResult r = RunTool(tool, args);
    EXPECT_EQ(r.exit_code, 2) << c.what << ": " << r.err;
    const auto lines = r.ErrLines();
    ASSERT_FALSE(lines.empty()) << c.what;
    if (quiet) {
      EXPECT_EQ(lines.size(), 1u) << c.what << ":\n" << r.err;
    }
    EXPECT_EQ(std::count_if(lines.begin(), lines.end(),
                            [&](const std::string& l) { return l.starts_with(tool + ": "); }),
              1)
        << c.what << ":\n"
        << r.err;
    EXPECT_TRUE(lines.back().starts_with(tool + ": ")) << c.what << ":\n" << r.err;
    EXPECT_NE(lines.back().find(c.expect), std::string::npos)
        << c.what << ": expected '" << c.expect << "' in\n"
        << r.err;
    EXPECT_TRUE(out.Files().empty()) << c.what << ": output left behind";
  }
}

TEST(SvoBuildCli, BadInputIsOneLineExitTwoAndNoOutput) {
  TempDir in;
  const std::string vfrag = (in / "t.vfrag").string();
  RunOk("svo-voxelize", {Torus(), "-o", vfrag, "-r", "24", "-q"});
  const std::string good = ReadText(vfrag);
  std::string corrupt = good;
  corrupt[corrupt.size() / 2] = static_cast<char>(corrupt[corrupt.size() / 2] ^ 0x10);
  in.Write("corrupt.vfrag", corrupt);
  in.Write("trunc.vfrag", good.substr(0, good.size() - 100));
  in.Write("empty.vfrag", std::string());
  // A triangle far from the torus: a valid mesh, but not the one that was voxelized.
  in.Write("far.obj", "v 100 100 100\nv 101 100 100\nv 100 101 100\nf 1 2 3\n");
  in.Write("broken.obj", "v 0 0 0\nv 1 0 0\nf 1 2 3\n");
  const std::vector<BadCase> cases = {
      {"missing input",
       {"{in}/missing.vfrag", "-o", "{out}/o.svo", "--no-contours"},
       "missing.vfrag"},
      {"corrupt input",
       {"{in}/corrupt.vfrag", "-o", "{out}/o.svo", "--no-contours"},
       "corrupt.vfrag"},
      {"truncated input",
       {"{in}/trunc.vfrag", "-o", "{out}/o.svo", "--no-contours"},
       "trunc.vfrag"},
      {"empty input", {"{in}/empty.vfrag", "-o", "{out}/o.svo", "--no-contours"}, "empty.vfrag"},
      {"not a vfrag", {Torus(), "-o", "{out}/o.svo", "--no-contours"}, "uv-torus.obj"},
      {"contours without mesh", {"{in}/t.vfrag", "-o", "{out}/o.svo"}, "--mesh"},
      {"contours without mesh names the input", {"{in}/t.vfrag", "-o", "{out}/o.svo"}, "t.vfrag"},
      {"mesh outside the grid",
       {"{in}/t.vfrag", "-o", "{out}/o.svo", "--mesh", "{in}/far.obj"},
       "far.obj"},
      {"mesh outside the grid says so",
       {"{in}/t.vfrag", "-o", "{out}/o.svo", "--mesh", "{in}/far.obj"},
       "outside"},
      {"missing mesh",
       {"{in}/t.vfrag", "-o", "{out}/o.svo", "--mesh", "{in}/nomesh.obj"},
       "nomesh.obj"},
      {"broken mesh",
       {"{in}/t.vfrag", "-o", "{out}/o.svo", "--mesh", "{in}/broken.obj"},
       "broken.obj"},
      {"bad --bricks",
       {"{in}/t.vfrag", "-o", "{out}/o.svo", "--no-contours", "--bricks", "4"},
       "--bricks"},
      {"bad --bricks word",
       {"{in}/t.vfrag", "-o", "{out}/o.svo", "--no-contours", "--bricks", "three"},
       "--bricks"},
      {"wrong output extension",
       {"{in}/t.vfrag", "-o", "{out}/o.vdb", "--no-contours"},
       "o.vdb: output must be a .svo file"},
      {"no output extension",
       {"{in}/t.vfrag", "-o", "{out}/o", "--no-contours"},
       "output must be a .svo file"},
      {"no output", {"{in}/t.vfrag", "--no-contours"}, "--output"},
      {"bad thread count",
       {"{in}/t.vfrag", "-o", "{out}/o.svo", "--no-contours", "-j", "-3"},
       "--threads"},
  };
  for (const BadCase& c : cases) ExpectBadInput("svo-build", in, c);
}

TEST(SvoBuildCli, Mesh2svoBadInputIsOneLineExitTwoAndNoOutput) {
  TempDir in;
  in.Write("nan.obj", "v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n");
  in.Write("empty.obj", "# nothing\n");
  const std::vector<BadCase> cases = {
      {"missing mesh", {"{in}/missing.obj", "-o", "{out}/o.svo", "-r", "16"}, "missing.obj"},
      {"NaN vertex", {"{in}/nan.obj", "-o", "{out}/o.svo", "-r", "16"}, "nan.obj"},
      {"no triangles", {"{in}/empty.obj", "-o", "{out}/o.svo", "-r", "16"}, "empty.obj"},
      {"no resolution", {Torus(), "-o", "{out}/o.svo"}, "--resolution N or --voxel-size S"},
      {"zero resolution", {Torus(), "-o", "{out}/o.svo", "-r", "0"}, "resolution"},
      {"bad --bricks", {Torus(), "-o", "{out}/o.svo", "-r", "16", "--bricks", "5"}, "--bricks"},
      {"wrong output extension",
       {Torus(), "-o", "{out}/o.vfrag", "-r", "16"},
       "o.vfrag: output must be a .svo file"},
      {"bad mode", {Torus(), "-o", "{out}/o.svo", "-r", "16", "--mode", "fat"}, "--mode"},
  };
  for (const BadCase& c : cases) ExpectBadInput("mesh2svo", in, c);
}

TEST(SvoBuildCli, HelpAndVersion) {
  for (const char* tool : {"svo-build", "mesh2svo"}) {
    ToolResult help = RunTool(tool, {"--help"});
    EXPECT_EQ(help.exit_code, 0) << tool;
    EXPECT_NE(help.out.find("--bricks"), std::string::npos) << tool;
    EXPECT_NE(help.out.find("--no-contours"), std::string::npos) << tool;
    ToolResult version = RunTool(tool, {"--version"});
    EXPECT_EQ(version.exit_code, 0) << tool;
    EXPECT_NE(version.out.find("svokit"), std::string::npos) << tool;
  }
}

}  // namespace
}  // namespace svokit::test
