// The standard streams and signals of a hostile environment, for every tool: stderr closed or
// full never aborts a tool nor changes its exit code (diagnostics are best effort); stdout closed,
// full or a pipe nobody reads is exit 4 naming the stream (the report is the tool's product); a
// file-size limit (ulimit -f, SIGXFSZ not ignored as a shell leaves it) is exit 4 with one line
// and nothing left. Also the bounds of options that set the amount of work, and an output
// directory that does not exist.

#include <fcntl.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "tests/cli/run_tool.hpp"

namespace svokit::test {
namespace {

namespace fs = std::filesystem;

/// What a standard stream of the tool is: captured to a file, closed, /dev/full, or a pipe whose
/// reading end is closed before the tool starts (every write is EPIPE, or SIGPIPE).
enum class Stream { kCapture, kClosed, kFull, kBrokenPipe };

struct StreamSetup {
  Stream out = Stream::kCapture;
  Stream err = Stream::kCapture;
  std::uint64_t file_size = 0;  ///< > 0: RLIMIT_FSIZE, SIGXFSZ left at its default
  std::string cwd;              ///< the tool's working directory ("" = the test's)
  bool remove_cwd = false;      ///< removed once the tool is in it, before it starts
};

// The child's side of a stream: the descriptor to put on `fd`, or -1 to close it.
int StreamDescriptor(Stream stream, const std::string& capture, int broken_pipe) {
  switch (stream) {
    case Stream::kCapture:
      return ::open(capture.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    case Stream::kFull:
      return ::open("/dev/full", O_WRONLY);
    case Stream::kBrokenPipe:
      return broken_pipe;
    case Stream::kClosed:
      return -1;
  }
  return -1;
}

/// Runs `tool` with its streams set up as `setup` says, bounded to 120 s (a hang fails).
ToolResult RunWithStreams(const std::string& tool, const std::vector<std::string>& args,
                          const StreamSetup& setup) {
  TempDir capture;
  const std::string out_path = (capture / "stdout").string(),
                    err_path = (capture / "stderr").string();
  std::vector<std::string> argv_storage = {std::string(SVOKIT_BIN_DIR) + "/" + tool};
  argv_storage.insert(argv_storage.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& a : argv_storage) argv.push_back(a.data());
  argv.push_back(nullptr);
  // Nobody ever reads this pipe: its reading end is closed before the fork.
  int pipe_fds[2] = {-1, -1};
  if (::pipe(pipe_fds) != 0) return {};
  ::close(pipe_fds[0]);
  ToolResult r;
  const pid_t pid = ::fork();
  if (pid == 0) {
    // As a shell starts a command: both signals at their default (fatal) disposition.
    ::signal(SIGPIPE, SIG_DFL);
    ::signal(SIGXFSZ, SIG_DFL);
    if (setup.file_size > 0) {
      const rlimit limit{setup.file_size, setup.file_size};
      ::setrlimit(RLIMIT_FSIZE, &limit);
    }
    if (!setup.cwd.empty() && ::chdir(setup.cwd.c_str()) != 0) ::_exit(126);
    if (setup.remove_cwd && ::rmdir(setup.cwd.c_str()) != 0) ::_exit(126);
    const int in = ::open("/dev/null", O_RDONLY);
    const int out = StreamDescriptor(setup.out, out_path, pipe_fds[1]);
    const int err = StreamDescriptor(setup.err, err_path, pipe_fds[1]);
    if (in < 0 || ::dup2(in, 0) < 0) ::_exit(127);
    for (const auto& [fd, target] : {std::pair{out, 1}, std::pair{err, 2}}) {
      if (fd < 0) {
        ::close(target);
      } else if (fd != target && ::dup2(fd, target) < 0) {
        ::_exit(127);
      }
    }
    // Nothing else open: a closed stream stays closed in the tool.
    for (int fd = 3; fd < 64; ++fd) ::close(fd);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  ::close(pipe_fds[1]);
  if (pid < 0) return r;
  r.exit_code = WaitForTool(pid, 120);
  if (fs::exists(out_path)) r.out = ReadText(out_path);
  if (fs::exists(err_path)) r.err = ReadText(err_path);
  return r;
}

// The inputs of every tool: the textured torus and the chain's files made from it.
class HostileEnvironment : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    inputs_ = new ChainInputs;
    inputs_->Make(32, 200, false);
  }
  static void TearDownTestSuite() {
    delete inputs_;
    inputs_ = nullptr;
  }
  static std::string Input(const std::string& name) { return inputs_->Path(name); }

  struct Tool {
    std::string name;
    std::vector<std::string> failing;  ///< a run that fails, exit 2, before writing anything
    std::vector<std::string> working;  ///< a run that succeeds and prints its report on stdout
    std::string output;                ///< the file `working` writes, in {out}; "" for none
  };

  // Every tool, with "{out}" standing for the run's output directory.
  static std::vector<Tool> Tools() {
    const std::string mesh = Input("uv-torus.obj"), svm = Input("t.svm"), vfrag = Input("t.vfrag"),
                      svo = Input("t.svo");
    return {
        {"svo-import", {"{out}/missing.obj"}, {mesh, "-o", "{out}/o.svm"}, "o.svm"},
        {"svo-voxelize",
         {"{out}/missing.obj", "-r", "16", "-o", "{out}/o.vfrag"},
         {svm, "-r", "64", "-o", "{out}/o.vfrag"},
         "o.vfrag"},
        {"svo-build",
         {"{out}/missing.vfrag", "--no-contours", "-o", "{out}/o.svo"},
         {vfrag, "--mesh", svm, "-o", "{out}/o.svo"},
         "o.svo"},
        {"mesh2svo",
         {"{out}/missing.obj", "-r", "16", "-o", "{out}/o.svo"},
         {svm, "-r", "32", "-o", "{out}/o.svo"},
         "o.svo"},
        {"svo-merge",
         {"{out}/missing.svopart", "-o", "{out}/o.svo"},
         {Input("0.svopart"), Input("1.svopart"), "-o", "{out}/o.svo"},
         "o.svo"},
        {"svo-export",
         {"{out}/missing.svo", "-o", "{out}/o.xyz"},
         {svo, "-o", "{out}/o.xyz"},
         "o.xyz"},
        {"svo-validate", {"{out}/missing.svo"}, {svo, "--mesh", svm}, ""},
        {"svo-inspect", {"{out}/missing.svo"}, {svo, "--json", "--levels"}, ""},
        {"svo-bake",
         {"{out}/missing.svo", "--ao", "-o", "{out}/o.svo"},
         {svo, "--ao", "-o", "{out}/o.svo"},
         "o.svo"},
    };
  }

  static std::vector<std::string> In(const fs::path& out, std::vector<std::string> args) {
    for (std::string& a : args) {
      if (a.starts_with("{out}")) a = out.string() + a.substr(5);
    }
    return args;
  }
  static std::vector<std::string> Files(const fs::path& dir) {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
    return names;
  }

  static ChainInputs* inputs_;
};

ChainInputs* HostileEnvironment::inputs_ = nullptr;

std::string Show(const ToolResult& r) {
  return "exit " + std::to_string(r.exit_code) + ": " + r.err;
}

// An error line that cannot be written is lost, nothing else: the exit is the error's (before the
// fix, fmt::print threw and the tool died of SIGABRT, exit 134). stdout closed too: the report was
// never written, so its loss changes nothing either.
TEST_F(HostileEnvironment, ErrorWithStderrClosedOrFullKeepsItsExitCode) {
  for (const Tool& tool : Tools()) {
    for (const StreamSetup& setup : {StreamSetup{Stream::kCapture, Stream::kClosed},
                                     StreamSetup{Stream::kCapture, Stream::kFull},
                                     StreamSetup{Stream::kClosed, Stream::kClosed},
                                     StreamSetup{Stream::kFull, Stream::kBrokenPipe}}) {
      TempDir out;
      const ToolResult r = RunWithStreams(tool.name, In(out.path(), tool.failing), setup);
      EXPECT_EQ(r.exit_code, 2) << tool.name << " stdout " << static_cast<int>(setup.out)
                                << ", stderr " << static_cast<int>(setup.err);
      EXPECT_TRUE(Files(out.path()).empty()) << tool.name;
    }
  }
}

// Progress lines and warnings that cannot be written do not stop a run that works: exit 0, the
// report complete on stdout.
TEST_F(HostileEnvironment, WorkWithStderrClosedOrFullSucceeds) {
  for (const Tool& tool : Tools()) {
    for (const Stream err : {Stream::kClosed, Stream::kFull, Stream::kBrokenPipe}) {
      TempDir out;
      const ToolResult r =
          RunWithStreams(tool.name, In(out.path(), tool.working), {Stream::kCapture, err});
      EXPECT_EQ(r.exit_code, 0) << tool.name << " stderr " << static_cast<int>(err);
      EXPECT_FALSE(r.out.empty()) << tool.name << " printed no report";
      if (!tool.output.empty()) {
        EXPECT_TRUE(fs::exists(out / tool.output)) << tool.name;
      }
    }
  }
}

// A report that cannot be written is exit 4 and one line naming stdout and why. The output file,
// committed before the report is printed, is complete (and, with stdout closed at start, not the
// descriptor the report went to). Before the fix: exit 0 (the report silently lost), 3
// (svo-inspect's large report: fmt's exception), 141 (SIGPIPE) or 134.
TEST_F(HostileEnvironment, ReportToClosedFullOrBrokenStdoutIsFour) {
  const std::pair<Stream, const char*> cases[] = {{Stream::kClosed, "Bad file descriptor"},
                                                  {Stream::kFull, "No space left on device"},
                                                  {Stream::kBrokenPipe, "Broken pipe"}};
  for (const Tool& tool : Tools()) {
    for (const auto& [stream, reason] : cases) {
      TempDir out;
      const ToolResult r =
          RunWithStreams(tool.name, In(out.path(), tool.working), {stream, Stream::kCapture});
      const std::string what = tool.name + " (" + reason + ")";
      EXPECT_EQ(r.exit_code, 4) << what << ": " << Show(r);
      const std::vector<std::string> lines = r.ErrLines();
      if (lines.empty()) {
        ADD_FAILURE() << what << ": nothing on stderr";
        continue;
      }
      EXPECT_EQ(lines.back(),
                tool.name + ": cannot write the report to stdout: " + std::string(reason))
          << what;
      for (std::size_t i = 0; i + 1 < lines.size(); ++i) {
        EXPECT_EQ(lines[i].find("cannot"), std::string::npos) << what << ": " << lines[i];
      }
      if (tool.output.empty()) continue;
      EXPECT_EQ(Files(out.path()), std::vector<std::string>{tool.output}) << what;
      if (tool.output.ends_with(".svo")) ExpectValidSvo((out / tool.output).string());
    }
  }
}

// A file-size limit as a shell sets it (ulimit -f) with SIGXFSZ at its default: the write fails
// with EFBIG and the tool exits 4 with one line naming the output, leaving nothing. Before the
// fix: killed by SIGXFSZ (exit 153), nothing on stderr.
TEST_F(HostileEnvironment, FileSizeLimitIsFourNotSigxfsz) {
  for (const Tool& tool : Tools()) {
    if (tool.output.empty()) continue;
    TempDir out;
    std::vector<std::string> args = In(out.path(), tool.working);
    args.push_back("-q");
    StreamSetup setup;
    setup.file_size = 1024;
    const ToolResult r = RunWithStreams(tool.name, args, setup);
    EXPECT_EQ(r.exit_code, 4) << tool.name << ": " << Show(r);
    EXPECT_EQ(r.ErrLines().size(), 1u) << tool.name << ": " << r.err;
    EXPECT_EQ(r.err.rfind(tool.name + ": " + (out / tool.output).string() + ": ", 0), 0u) << r.err;
    EXPECT_NE(r.err.find("(File too large)"), std::string::npos) << r.err;
    EXPECT_TRUE(Files(out.path()).empty()) << tool.name;
  }
}

// An output whose directory does not exist cannot be written: exit 4 before any work, one line,
// for every tool that writes; also when the directory is the working directory, removed.
TEST_F(HostileEnvironment, MissingOrRemovedOutputDirectoryIsFour) {
  for (const Tool& tool : Tools()) {
    if (tool.output.empty()) continue;
    TempDir out;
    std::vector<std::string> args = In(out.path(), tool.working);
    for (std::string& a : args) {
      if (a == (out / tool.output).string()) a = (out / "gone" / tool.output).string();
    }
    const ToolResult r = RunWithStreams(tool.name, args, {});
    EXPECT_EQ(r.exit_code, 4) << tool.name << ": " << Show(r);
    EXPECT_EQ(r.ErrLines().size(), 1u) << tool.name << ": " << r.err;
    EXPECT_NE(r.err.find("gone/" + tool.output + ": output directory does not exist"),
              std::string::npos)
        << r.err;
    EXPECT_EQ(r.out, "") << tool.name << " worked before refusing";
    EXPECT_TRUE(Files(out.path()).empty()) << tool.name;

    // The working directory, removed before the tool starts: a relative output there.
    TempDir parent;
    StreamSetup setup;
    setup.cwd = (parent / "removed").string();
    setup.remove_cwd = true;
    fs::create_directory(setup.cwd);
    std::vector<std::string> relative = In(out.path(), tool.working);
    for (std::string& a : relative) {
      if (a == (out / tool.output).string()) a = tool.output;
    }
    const ToolResult in_removed = RunWithStreams(tool.name, relative, setup);
    EXPECT_EQ(in_removed.exit_code, 4)
        << tool.name << " in a removed directory: " << Show(in_removed);
    EXPECT_EQ(in_removed.ErrLines().size(), 1u) << tool.name << ": " << in_removed.err;
    EXPECT_TRUE(Files(parent.path()).empty()) << tool.name;
  }
  // svo-inspect's pictures.
  TempDir out;
  const ToolResult r = RunWithStreams(
      "svo-inspect", {Input("t.svo"), "--render", (out / "gone" / "x.png").string()}, {});
  EXPECT_EQ(r.exit_code, 4) << Show(r);
  EXPECT_EQ(r.err, "svo-inspect: " + (out / "gone" / "x.png").string() +
                       ": output directory does not exist\n");
}

class OptionBounds : public HostileEnvironment {};

// Options that set the amount of work have a documented maximum: over it is exit 2 at once, one
// line naming the option, the value and the maximum, nothing written. Before the fix these ran for
// hours (a billion rays per point).
TEST_F(OptionBounds, RaysAndReferenceOverTheMaximumAreRefused) {
  const std::string mesh = Input("uv-torus.obj"), svo = Input("t.svo");
  const std::vector<std::vector<std::string>> cases = {
      {svo, "--ao", "--mesh", mesh, "--method", "rays", "--rays", "1000000000", "--vertex-out",
       "{out}/ao.ply"},
      {svo, "--ao", "--mesh", mesh, "--reference", "1000000000", "-o", "{out}/ao.svo"},
      {svo, "--ao", "--mesh", mesh, "--rays", "65537", "--method", "rays", "--vertex-out",
       "{out}/ao.ply"},
      {svo, "--ao", "--mesh", mesh, "--reference", "65537", "-o", "{out}/ao.svo"},
  };
  for (const std::vector<std::string>& c : cases) {
    TempDir out;
    const ToolResult r = RunWithStreams("svo-bake", In(out.path(), c), {});
    std::size_t at = 0;
    while (c[at] != "--rays" && c[at] != "--reference") ++at;
    const std::string option = c[at], value = c[at + 1];
    EXPECT_EQ(r.exit_code, 2) << Show(r);
    EXPECT_EQ(r.ErrLines().size(), 1u) << r.err;
    EXPECT_EQ(r.err.rfind("svo-bake: " + option + ": " + value, 0), 0u) << r.err;
    EXPECT_NE(r.err.find("the maximum is 65536"), std::string::npos) << r.err;
    EXPECT_TRUE(Files(out.path()).empty());
  }
  // The maximum itself is accepted (the reference over the torus's vertices: a second or two).
  TempDir out;
  const ToolResult at_max = RunWithStreams(
      "svo-bake",
      In(out.path(),
         {svo, "--ao", "--mesh", mesh, "--reference", "65536", "-o", "{out}/ao.svo", "-q"}),
      {});
  EXPECT_EQ(at_max.exit_code, 0) << Show(at_max);
}

// --memory-limit '' is not "no limit": it is refused like any size that is not one.
TEST_F(OptionBounds, EmptyMemoryLimitIsRefused) {
  const std::string svm = Input("t.svm"), vfrag = Input("t.vfrag");
  const std::vector<std::pair<std::string, std::vector<std::string>>> cases = {
      {"svo-voxelize", {svm, "-r", "32", "--memory-limit", "", "-o", "{out}/o.vfrag"}},
      {"svo-build", {vfrag, "--mesh", svm, "--memory-limit", "", "-o", "{out}/o.svo"}},
      {"mesh2svo", {svm, "-r", "32", "--memory-limit", "", "-o", "{out}/o.svo"}},
  };
  for (const auto& [tool, args] : cases) {
    TempDir out;
    const ToolResult r = RunWithStreams(tool, In(out.path(), args), {});
    EXPECT_EQ(r.exit_code, 2) << tool << ": " << Show(r);
    EXPECT_EQ(r.ErrLines().size(), 1u) << tool << ": " << r.err;
    EXPECT_EQ(r.err,
              tool + ": --memory-limit '': expected a size such as 4G, 512M or a byte count\n");
    EXPECT_TRUE(Files(out.path()).empty()) << tool;
  }
}

}  // namespace
}  // namespace svokit::test
