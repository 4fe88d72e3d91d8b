// Textures as the tools bake them: third-party decoders print nothing of their own, and a file
// that is not an image is never stored in a normalized mesh.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "svokit/core/file_io.hpp"
#include "svokit/formats/svm/svm.hpp"
#include "tests/cli/run_tool.hpp"

namespace svokit::test {
namespace {

namespace fs = std::filesystem;

// The torus and its material in `dir`, its texture the given bytes.
void TexturedTorus(const TempDir& dir, const std::vector<std::uint8_t>& png) {
  const fs::path data = SVOKIT_DATA_DIR;
  fs::copy_file(data / "uv-torus.obj", dir / "uv-torus.obj");
  fs::copy_file(data / "uv-torus.mtl", dir / "uv-torus.mtl");
  dir.Write("uv-torus.png", png);
}

// libpng printed "libpng error: IDAT: CRC error", unprefixed, even with -q (through OpenImageIO).
// PNG is decoded by stb_image, which prints nothing: stderr is empty or svokit's warnings alone.
TEST(TextureCli, QuietPrintsNothingOfThirdPartyDecoders) {
  TempDir dir;
  std::vector<std::uint8_t> png = *ReadFileBytes(fs::path(SVOKIT_DATA_DIR) / "uv-torus.png");
  const std::string text(png.begin(), png.end());
  const std::size_t idat = text.find("IDAT");
  ASSERT_NE(idat, std::string::npos);
  const std::size_t length = static_cast<std::size_t>(png[idat - 4]) << 24 |
                             static_cast<std::size_t>(png[idat - 3]) << 16 |
                             static_cast<std::size_t>(png[idat - 2]) << 8 | png[idat - 1];
  png[idat + 4 + length] ^= 1;  // the IDAT chunk's CRC
  TexturedTorus(dir, png);
  const ToolResult r = RunTool("mesh2svo",
                               {(dir / "uv-torus.obj").string(), "-r", "16", "--attributes",
                                "color", "-o", (dir / "out.svo").string(), "-q"},
                               60);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  for (const std::string& line : r.ErrLines()) {
    EXPECT_EQ(line.rfind("mesh2svo: ", 0), 0u) << "unprefixed: " << line;
  }
}

// An MTL naming a file that is not an image: svo-import warns and the .svm holds none of its bytes.
TEST(TextureCli, FilesThatAreNotImagesAreNeverStored) {
  TempDir dir;
  const std::string secret = "root:x:0:0:root:/root:/bin/bash secret-marker-4711\n";
  TexturedTorus(dir, std::vector<std::uint8_t>(secret.begin(), secret.end()));
  const ToolResult r = RunTool(
      "svo-import", {(dir / "uv-torus.obj").string(), "-o", (dir / "out.svm").string()}, 60);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("unsupported image format"), std::string::npos) << r.err;
  StatusOr<Mesh> mesh = ReadSvm(dir / "out.svm");
  ASSERT_TRUE(mesh.ok()) << mesh.status().message();
  EXPECT_TRUE(mesh->textures.empty());
}

}  // namespace
}  // namespace svokit::test
