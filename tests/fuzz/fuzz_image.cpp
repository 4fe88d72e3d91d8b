// Texture decoding as the baker does it: a name and bytes (the bytes pick the decoder: stb_image
// or the OpenImageIO plugin). The first byte picks the name, the rest is the image: seeds are real
// images of each format.

#include "svokit/mesh/texture.hpp"
#include "tests/fuzz/fuzz_target.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static constexpr const char* kNames[] = {"t.png", "t.jpg", "t.tga", "t.bmp", "t.tif",
                                           "t.exr", "t.hdr", "t.gif", "t.ppm"};
  if (size == 0) return 0;
  const char* name = kNames[data[0] % std::size(kNames)];
  const svokit::Texture texture(name, std::vector<std::uint8_t>(data + 1, data + size),
                                /*srgb=*/true);
  (void)texture.ReadInfo();
  svokit::fuzz::ExpectAccepted(texture.Decoded().status(), size);
  return 0;
}
