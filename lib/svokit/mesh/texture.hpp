#pragma once
// Textures are kept as their original encoded bytes (PNG, JPEG, TGA, EXR, ...) and decoded lazily
// (image_codec.hpp): importing never pays for images nobody samples, and a normalized mesh file
// embeds the exact source bytes.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "svokit/core/status.hpp"
#include "svokit/core/vec.hpp"

namespace svokit {

/// A decoded image: linear-light RGBA floats, row 0 at the top (as stored in image files).
struct Image {
  int width = 0;
  int height = 0;
  std::vector<float> rgba;  // width * height * 4

  Rgba Texel(int x, int y) const {
    const float* p = &rgba[(static_cast<std::size_t>(y) * width + x) * 4];
    return {p[0], p[1], p[2], p[3]};
  }
};

class Texture {
 public:
  Texture() = default;
  /// `name`: the path or URI as the source file wrote it; `encoded`: the image file's bytes;
  /// `srgb`: whether colour channels are sRGB-encoded (base-colour maps are, per OBJ and glTF).
  Texture(std::string name, std::vector<std::uint8_t> encoded, bool srgb = true);

  const std::string& name() const { return name_; }
  const std::vector<std::uint8_t>& encoded() const { return encoded_; }
  bool srgb() const { return srgb_; }

  /// Width, height and channels from the header only (no pixel decoding).
  struct Info {
    int width = 0, height = 0, channels = 0;
    std::string format;
  };
  StatusOr<Info> ReadInfo() const;

  /// Decodes on first use (thread-safe; later calls return the cached image or error).
  StatusOr<const Image*> Decoded() const;

  /// Decodes without caching, `shrink` times downsampled by 2 × 2 (a box filter in linear light
  /// over each block of 2^shrink × 2^shrink texels; blocks at the right and bottom edges average
  /// the texels they have).
  StatusOr<Image> Decode(int shrink = 0) const;

 private:
  struct Cache;
  std::string name_;
  std::vector<std::uint8_t> encoded_;
  bool srgb_ = true;
  std::shared_ptr<Cache> cache_;
};

}  // namespace svokit
