// One fuzz target per mesh format: SVOKIT_FUZZ_EXT is the extension it is built for. The input is
// written as fuzz.EXT and imported as a user's file would be. For OBJ, the lines after a line
// "#mtl" are the material library fuzz.mtl (seeds name it with `mtllib fuzz.mtl`); for glTF, the
// bytes after a line "#bin" are its buffer fuzz.bin. A texture t.png is always there to name.

#include "svokit/core/thread_limit.hpp"
#include "svokit/formats/mesh_import.hpp"
#include "svokit/mesh/image_codec.hpp"
#include "tests/fuzz/fuzz_target.hpp"

namespace svokit::fuzz {
namespace {

constexpr const char* kExt = SVOKIT_FUZZ_EXT;

void WriteTexture() {
  static const bool written = [] {
    const std::uint8_t pixels[4 * 3] = {255, 0, 0, 0, 255, 0, 0, 0, 255, 128, 128, 128};
    return WriteImage(ScratchDir() / "t.png", 2, 2, 3, pixels).ok();
  }();
  if (!written) Fail("cannot write the texture t.png");
}

}  // namespace
}  // namespace svokit::fuzz

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace svokit;
  using namespace svokit::fuzz;
  static ThreadLimit one_thread(1);  // the same coverage for the same input
  WriteTexture();
  const std::string ext = kExt;
  std::span<const std::uint8_t> input(data, size);
  if (ext == "obj" || ext == "gltf") {
    const auto [main, second] = SplitAtLine(input, ext == "obj" ? "#mtl" : "#bin");
    WriteScratch(ext == "obj" ? "fuzz.mtl" : "fuzz.bin", second);
    input = main;
  }
  StatusOr<Mesh> mesh = ImportMesh(WriteScratch("fuzz." + ext, input));
  ExpectAccepted(mesh.status(), size);
  if (mesh.ok()) CheckMesh(*mesh);
  return 0;
}
