// The tools given hostile inputs as a user could: special files where files are expected, a glTF
// naming a huge file, paths that are not UTF-8. Each tool runs with a time and memory bound, so a
// hang or an unbounded read fails the test instead of blocking the suite.

#include <fcntl.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <chrono>
#include <cstring>
#include <thread>

#include <nlohmann/json.hpp>

#include "tests/cli/run_tool.hpp"

namespace svokit::test {
namespace {

namespace fs = std::filesystem;

// Every tool run of this suite is bounded: a hang or an endless read fails the test.
ToolResult RunToolBounded(const std::string& tool, const std::vector<std::string>& args,
                          int seconds = 60) {
  return RunTool(tool, args, seconds);
}

// Exit 2 and one line on stderr that contains `needle`.
void ExpectRefused(const ToolResult& r, const std::string& needle) {
  EXPECT_EQ(r.exit_code, 2) << r.err;
  ASSERT_EQ(r.ErrLines().size(), 1u) << r.err;
  EXPECT_NE(r.err.find(needle), std::string::npos) << r.err;
}

// A FIFO given as the .svo hung every reader: opening it waited for a writer.
TEST(HostileInput, FifoAsSvoIsRefusedAtOnce) {
  TempDir dir;
  const auto fifo = dir / "fifo.svo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const std::string expected = fifo.string() + ": is a FIFO, not a regular file";
  ExpectRefused(RunToolBounded("svo-inspect", {fifo.string(), "-q"}), expected);
  ExpectRefused(RunToolBounded("svo-validate", {fifo.string(), "-q"}), expected);
  ExpectRefused(RunToolBounded("svo-export", {fifo.string(), "-o", (dir / "o.xyz").string(), "-q"}),
                expected);
}

TEST(HostileInput, FifoOrDirectoryAsMeshIsRefused) {
  TempDir dir;
  const auto fifo = dir / "fifo.obj";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  fs::create_directory(dir / "dir.obj");
  for (const fs::path& input : {fifo, dir / "dir.obj"}) {
    ExpectRefused(RunToolBounded("svo-import", {input.string(), "-q"}), input.string());
    ExpectRefused(RunToolBounded("mesh2svo",
                                 {input.string(), "-o", (dir / "o.svo").string(), "-r", "8", "-q"}),
                  input.string());
  }
}

// A texture that is /dev/zero was read without end (the reader doubled its buffer): now it is a
// warning naming why, and the material keeps its base colour.
TEST(HostileInput, TextureThatIsADeviceIsAWarning) {
  TempDir dir;
  fs::copy_file(DataDir() / "uv-torus.obj", dir / "uv-torus.obj");
  fs::copy_file(DataDir() / "uv-torus.mtl", dir / "uv-torus.mtl");
  fs::create_symlink("/dev/zero", dir / "uv-torus.png");
  // The link leads out of the model's folder: /dev is allowed, so that the device is found.
  const ToolResult r = RunToolBounded(
      "svo-import", {(dir / "uv-torus.obj").string(), "--json", "-q", "--asset-path", "/dev"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["warnings"][0],
            "material 'torus': texture 'uv-torus.png' is a character device, not a regular file, "
            "using base colour");
}

// A 300-byte glTF whose buffer declares 48 bytes but names a 6 GiB (sparse) file read all of it.
TEST(HostileInput, GltfBufferReadsOnlyItsDeclaredBytes) {
  TempDir dir;
  std::string bin;
  for (float f : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f})
    bin.append(reinterpret_cast<char*>(&f), 4);
  for (std::uint32_t i : {0u, 1u, 2u}) bin.append(reinterpret_cast<char*>(&i), 4);
  ASSERT_EQ(bin.size(), 48u);
  fs::resize_file(dir.Write("huge.bin", bin), std::uint64_t{6} << 30);
  const auto gltf = dir.Write("small.gltf", R"({"asset": {"version": "2.0"},
 "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
 "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
 "buffers": [{"uri": "huge.bin", "byteLength": 48}],
 "bufferViews": [{"buffer": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 12}],
 "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"},
               {"bufferView": 1, "componentType": 5125, "count": 3, "type": "SCALAR"}]})");
  const ToolResult r = RunToolBounded("svo-import", {gltf.string(), "--json", "-q"}, 30);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["triangles"], 1);
}

// A path that is not UTF-8 made the JSON writers throw (exit 3, "invalid UTF-8 byte", the file not
// named); it is now written with \xNN escapes wherever a path goes into JSON.
TEST(HostileInput, NonUtf8PathsAreEscapedNotFatal) {
  TempDir dir;
  for (const char* ext : {".mtl", ".png"}) {
    fs::copy_file(DataDir() / (std::string("uv-torus") + ext),
                  dir / (std::string("uv-torus") + ext));
  }
  const std::string obj = (dir / "\xFF.obj").string(), svm = (dir / "\xFE.svm").string(),
                    vfrag = (dir / "\xFD.vfrag").string(), svo = (dir / "\xFC.svo").string(),
                    direct = (dir / "\xFB.svo").string();
  fs::copy_file(DataDir() / "uv-torus.obj", obj);

  ToolResult r = RunToolBounded("svo-import", {obj, "-o", svm, "--json", "-q"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["source"], (dir / "\\xFF.obj").string());
  r = RunToolBounded("svo-voxelize", {svm, "-o", vfrag, "-r", "16", "-q"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = RunToolBounded("svo-build", {vfrag, "-o", svo, "--mesh", svm, "-q"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = RunToolBounded("mesh2svo", {obj, "-o", direct, "-r", "16", "-q"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const std::string& file : {svo, direct}) {
    r = RunToolBounded("svo-inspect", {file, "--json", "-q"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto stats = nlohmann::json::parse(r.out);
    EXPECT_NE(stats.dump().find("\\\\xF"), std::string::npos) << r.out;
    r = RunToolBounded("svo-validate", {file, "--json", "-q"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(nlohmann::json::parse(r.out)["file"].get<std::string>().find("\\xF"),
              std::string::npos);
  }
}

// An output that is an existing directory is refused before the work, by every tool that writes.
TEST(HostileInput, OutputThatIsADirectoryIsRefusedFirst) {
  TempDir dir;
  const std::string mesh = (DataDir() / "uv-torus.obj").string();
  const std::string svo = (dir / "t.svo").string(), vfrag = (dir / "t.vfrag").string();
  ASSERT_EQ(RunTool("mesh2svo", {mesh, "-r", "16", "-o", svo, "-q"}).exit_code, 0);
  ASSERT_EQ(RunTool("svo-voxelize", {mesh, "-r", "16", "-o", vfrag, "-q"}).exit_code, 0);
  for (const char* name : {"d.svo", "d.svm", "d.vfrag", "d.vox"}) {
    std::filesystem::create_directory(dir / name);
  }
  const std::vector<std::pair<std::string, std::vector<std::string>>> runs = {
      {"mesh2svo", {mesh, "-r", "16", "-o", (dir / "d.svo").string()}},
      {"svo-import", {mesh, "-o", (dir / "d.svm").string()}},
      {"svo-voxelize", {mesh, "-r", "16", "-o", (dir / "d.vfrag").string()}},
      {"svo-build", {vfrag, "--no-contours", "-o", (dir / "d.svo").string()}},
      {"svo-export", {svo, "-o", (dir / "d.vox").string()}},
  };
  for (const auto& [tool, args] : runs) {
    std::vector<std::string> quiet = args;
    quiet.push_back("-q");
    const ToolResult r = RunTool(tool, quiet);
    EXPECT_EQ(r.exit_code, 2) << tool << ": " << r.err;
    ASSERT_EQ(r.ErrLines().size(), 1u) << tool << ": " << r.err;
    EXPECT_NE(r.err.find("is a directory"), std::string::npos) << tool << ": " << r.err;
    EXPECT_EQ(r.out, "") << tool << " worked before refusing";
  }
}

}  // namespace
}  // namespace svokit::test
