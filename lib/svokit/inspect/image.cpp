#include "svokit/inspect/image.hpp"

#include "svokit/mesh/image_codec.hpp"

namespace svokit {

Status WriteRgbaImage(const RgbaImage& image, const std::filesystem::path& path) {
  return WriteImage(path, image.width, image.height, 4, image.pixels);
}

}  // namespace svokit
