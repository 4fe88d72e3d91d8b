// Every tool that writes maps each failure of the environment to the exit code of the table in
// README.md ("Conventions"): 4 when the output cannot be written (disk full, no permission), 5 when
// memory runs out, 2 when the output would replace the input. Each failure is one line on stderr
// that names the output or the input, and leaves no file behind.

#include <sys/stat.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "tests/cli/run_tool.hpp"

namespace svokit::test {
namespace {

namespace fs = std::filesystem;

// The inputs every case reads: a textured mesh, and the chain's files made from it at 64³.
class ExitCodes : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    inputs_ = new ChainInputs;
    inputs_->Make(64, 300, true);
  }
  static void TearDownTestSuite() {
    delete inputs_;
    inputs_ = nullptr;
  }
  static std::string Input(const std::string& name) { return inputs_->Path(name); }

  struct Run {
    std::string tool;
    std::vector<std::string> args;
    std::string output;  ///< the file the run writes
  };
  // One run per tool and output format, each writing into `out`.
  static std::vector<Run> Writers(const fs::path& out) {
    const std::string mesh = Input("uv-torus.obj"), svm = Input("t.svm"), vfrag = Input("t.vfrag"),
                      svo = Input("t.svo");
    std::vector<Run> runs = {
        {"svo-import", {mesh, "-o", (out / "o.svm").string()}, (out / "o.svm").string()},
        {"svo-voxelize",
         {svm, "-r", "128", "-o", (out / "o.vfrag").string()},
         (out / "o.vfrag").string()},
        {"svo-voxelize",
         {svm, "-r", "128", "-o", (out / "o.ply").string()},
         (out / "o.ply").string()},
        {"svo-voxelize",
         {svm, "-r", "300", "--memory-limit", "1G", "-o", (out / "c.vfrag").string()},
         (out / "c.vfrag").string()},
        {"svo-build",
         {vfrag, "--mesh", svm, "-o", (out / "o.svo").string()},
         (out / "o.svo").string()},
        {"svo-build",
         {vfrag, "--mesh", svm, "--memory-limit", "1G", "-o", (out / "ob.svo").string()},
         (out / "ob.svo").string()},
        {"mesh2svo", {svm, "-r", "64", "-o", (out / "m.svo").string()}, (out / "m.svo").string()},
        {"mesh2svo",
         {svm, "-r", "300", "--bricks", "none", "--memory-limit", "1G", "-o",
          (out / "p.svo").string()},
         (out / "p.svo").string()},
        {"mesh2svo",
         {svm, "-r", "300", "--bricks", "none", "--pages", "1/2", "-o",
          (out / "p.svopart").string()},
         (out / "p.svopart").string()},
        {"svo-merge",
         {Input("0.svopart"), Input("1.svopart"), "-o", (out / "merged.svo").string()},
         (out / "merged.svo").string()},
        {"mesh2svo",
         {svm, "-r", "300", "--memory-limit", "1G", "-o", (out / "pb.svo").string()},
         (out / "pb.svo").string()},
        {"mesh2svo",
         {svm, "-r", "300", "--pages", "1/2", "-o", (out / "pb.svopart").string()},
         (out / "pb.svopart").string()},
        {"svo-merge",
         {Input("b0.svopart"), Input("b1.svopart"), "-o", (out / "merged-b.svo").string()},
         (out / "merged-b.svo").string()},
        {"svo-inspect",
         {svo, "--render", (out / "r.png").string(), "--size", "1024x1024"},
         (out / "r.png").string()},
        {"svo-inspect",
         {svo, "--slice", "z=8", (out / "s.png").string()},
         (out / "s.png").string()},
        {"svo-bake", {svo, "--ao", "-o", (out / "ao.svo").string()}, (out / "ao.svo").string()},
        {"svo-bake",
         {svo, "--ao", "--mesh", mesh, "--vertex-out", (out / "ao.ply").string()},
         (out / "ao.ply").string()},
    };
    for (const char* ext : {"vdb", "vox", "binvox", "ply", "xyz"}) {
      const std::string o = (out / (std::string("e.") + ext)).string();
      runs.push_back({"svo-export", {svo, "-o", o}, o});
    }
    return runs;
  }

  // Exit `code`, one line on stderr "TOOL: NAME: ...`needle`...", nothing in `out` afterwards.
  static void ExpectFailure(const Run& run, const ToolResult& r, int code, const std::string& name,
                            const std::string& needle, const fs::path& out) {
    const std::string what = run.tool + " -o " + fs::path(run.output).filename().string();
    EXPECT_EQ(r.exit_code, code) << what << ": " << r.err;
    ASSERT_EQ(r.ErrLines().size(), 1u) << what << ": " << r.err;
    EXPECT_EQ(r.err.rfind(run.tool + ": " + name + ": ", 0), 0u) << what << ": " << r.err;
    EXPECT_NE(r.err.find(needle), std::string::npos) << what << ": " << r.err;
    std::vector<std::string> left;
    for (const auto& entry : fs::directory_iterator(out)) left.push_back(entry.path().string());
    EXPECT_TRUE(left.empty()) << what << " left " << left.front();
  }

  static ChainInputs* inputs_;
};

ChainInputs* ExitCodes::inputs_ = nullptr;

std::vector<std::string> Quiet(std::vector<std::string> args) {
  args.push_back("-q");
  return args;
}

// A write the system refuses part-way (here a file-size limit: EFBIG, as ENOSPC would be) is exit
// 4 naming the output, never the hidden temporary, and leaves nothing; before the fix OpenVDB and
// OpenImageIO ignored the failed writes and a truncated .vdb or .png was put in place, exit 0.
TEST_F(ExitCodes, AWriteRefusedPartWayIsFourAndLeavesNothing) {
  TempDir out;
  for (const Run& run : Writers(out.path())) {
    const ToolResult r = RunTool(run.tool, Quiet(run.args), RunOptions{60, 0, 512, {}});
    ExpectFailure(run, r, 4, run.output, "(File too large)", out.path());
  }
}

// A real full disk: a 16 KiB file system of its own (a private mount namespace), where only
// root, or a user namespace, may mount.
TEST_F(ExitCodes, AFullDiskIsFourAndLeavesNothing) {
  if (std::system("unshare --mount --map-root-user true 2>/dev/null") != 0) {
    GTEST_SKIP() << "no mount namespaces here (unshare --mount --map-root-user fails)";
  }
  TempDir out;
  // The tool runs in the namespace with `out` mounted as a small tmpfs; the script then lists
  // what is left there on stdout, after the tool's own output.
  const std::vector<std::string> wrapper = {
      "unshare",
      "--mount",
      "--map-root-user",
      "sh",
      "-c",
      "mount -t tmpfs -o size=16k tmpfs \"$0\" && \"$@\" >/dev/null; s=$?; "
      "echo left:$(ls -A \"$0\"); exit $s",
      out.path().string()};
  for (const Run& run : Writers(out.path())) {
    if (run.output.ends_with("s.png")) continue;  // a slice of 64² pixels fits
    const ToolResult r = RunTool(run.tool, Quiet(run.args), RunOptions{60, 0, 0, wrapper});
    const std::string what = run.tool + " -o " + fs::path(run.output).filename().string();
    EXPECT_EQ(r.exit_code, 4) << what << ": " << r.err;
    ASSERT_EQ(r.ErrLines().size(), 1u) << what << ": " << r.err;
    EXPECT_EQ(r.err.rfind(run.tool + ": " + run.output + ": ", 0), 0u) << what << ": " << r.err;
    EXPECT_NE(r.err.find("(No space left on device)"), std::string::npos) << what << ": " << r.err;
    EXPECT_EQ(r.out, "left:\n") << what;
  }
}

// An output directory the user may not write into is refused before any work, exit 4. Root may
// write anywhere, so as root the tools run without capabilities (CAP_DAC_OVERRIDE among them).
TEST_F(ExitCodes, AnUnwritableDirectoryIsFourBeforeAnyWork) {
  TempDir parent;
  const fs::path out = parent / "read-only";
  fs::create_directory(out);
  fs::permissions(out, fs::perms::owner_read | fs::perms::owner_exec);
  std::vector<std::string> wrapper;
  if (::geteuid() == 0) wrapper = {"setpriv", "--bounding-set=-all", "--inh-caps=-all"};
  for (const Run& run : Writers(out)) {
    const ToolResult r = RunTool(run.tool, Quiet(run.args), RunOptions{60, 0, 0, wrapper});
    ExpectFailure(run, r, 4, run.output, "output directory is not writable (Permission denied)",
                  out);
    EXPECT_EQ(r.out, "") << run.tool << " worked before refusing";
  }
}

// Memory refused (an address-space limit) is exit 5, naming the input: the allocation that fails
// is the tool's own (std::bad_alloc) or a mapping of the output (ENOMEM).
TEST_F(ExitCodes, MemoryRunningOutIsFive) {
  if (kAddressSanitizer) GTEST_SKIP() << "AddressSanitizer reserves more than any limit tested";
  TempDir out;
  const std::string svm = Input("t.svm");
  const std::vector<Run> runs = {
      {"mesh2svo", {svm, "-r", "2048", "-o", (out / "m.svo").string()}, svm},
      {"svo-voxelize", {svm, "-r", "8192", "-o", (out / "o.vfrag").string()}, svm},
      {"svo-inspect",
       {Input("t.svo"), "--render", (out / "r.png").string(), "--size", "16384x16384"},
       Input("t.svo")},
  };
  for (const Run& run : runs) {
    const ToolResult r = RunTool(run.tool, Quiet(run.args), RunOptions{60, 256 << 20, 0, {}});
    ExpectFailure(run, r, 5, run.output, "out of memory", out.path());
  }
}

// An output that is the input, under any name (here a hard link), would be replaced by what is
// made from it: refused before any work, exit 2.
TEST_F(ExitCodes, AnOutputThatIsTheInputIsTwo) {
  TempDir dir;
  fs::copy_file(Input("t.svm"), dir / "a.svm");
  fs::create_hard_link(dir / "a.svm", dir / "alias.svm");
  const std::string ply = (DataDir() / "box-room.ply").string();
  fs::copy_file(ply, dir / "room.ply");
  const std::vector<std::pair<std::string, std::vector<std::string>>> runs = {
      {"svo-import", {(dir / "a.svm").string(), "-o", (dir / "alias.svm").string()}},
      {"svo-voxelize", {(dir / "room.ply").string(), "-r", "8", "-o", (dir / "room.ply").string()}},
  };
  for (const auto& [tool, args] : runs) {
    const ToolResult r = RunTool(tool, Quiet(args));
    EXPECT_EQ(r.exit_code, 2) << tool << ": " << r.err;
    ASSERT_EQ(r.ErrLines().size(), 1u) << r.err;
    EXPECT_NE(r.err.find(args.back() + ": is the input file"), std::string::npos) << r.err;
  }
  EXPECT_EQ(test::ReadBytes(dir / "alias.svm"), test::ReadBytes(Input("t.svm")));
  EXPECT_EQ(test::ReadBytes(dir / "room.ply"), test::ReadBytes(ply));
}

}  // namespace
}  // namespace svokit::test
