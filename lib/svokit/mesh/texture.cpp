#include "svokit/mesh/texture.hpp"

#include <algorithm>
#include <mutex>

#include "svokit/core/file_io.hpp"
#include "svokit/mesh/image_codec.hpp"
#include "svokit/mesh/importers.hpp"

namespace svokit {

struct Texture::Cache {
  std::once_flag once;
  Image image;
  Status status;
};

Texture::Texture(std::string name, std::vector<std::uint8_t> encoded, bool srgb)
    : name_(std::move(name)),
      encoded_(std::move(encoded)),
      srgb_(srgb),
      cache_(std::make_shared<Cache>()) {}

StatusOr<Texture::Info> Texture::ReadInfo() const {
  StatusOr<ImageHeader> h = ReadImageHeader(name_, encoded_);
  if (!h.ok()) return h.status();
  return Info{h->width, h->height, h->channels, h->format};
}

StatusOr<const Image*> Texture::Decoded() const {
  if (!cache_) return Status::BadInput("texture '{}' has no data", name_);
  std::call_once(cache_->once, [this] {
    ImageHeader header;
    StatusOr<std::vector<float>> decoded = DecodeImagePixels(name_, encoded_, header);
    if (!decoded.ok()) {
      cache_->status = decoded.status();
      return;
    }
    const std::vector<float>& pixels = *decoded;
    const int nc = header.channels;
    Image& img = cache_->image;
    img.width = header.width;
    img.height = header.height;
    img.rgba.resize(static_cast<std::size_t>(img.width) * img.height * 4);
    // Grey, grey+alpha, RGB and RGBA all become linear RGBA; alpha is never sRGB-encoded.
    const bool decode_srgb = srgb_ && !header.is_float;
    const std::size_t n = static_cast<std::size_t>(img.width) * img.height;
    for (std::size_t i = 0; i < n; ++i) {
      const float* src = &pixels[i * nc];
      float c[4] = {src[0], src[0], src[0], 1.f};
      if (nc == 2) c[3] = src[1];
      if (nc >= 3) c[1] = src[1], c[2] = src[2];
      if (nc >= 4) c[3] = src[3];
      for (int k = 0; k < 3; ++k) img.rgba[i * 4 + k] = decode_srgb ? SrgbToLinear(c[k]) : c[k];
      img.rgba[i * 4 + 3] = c[3];
    }
  });
  if (!cache_->status.ok()) return cache_->status;
  return &cache_->image;
}

namespace detail {

void AttachTextureFile(const SideFileRule& rule, const std::filesystem::path& folder,
                       const std::string& reference, SideFileSyntax syntax, Material& material,
                       Mesh& mesh) {
  // glTF names its images by URI: the name kept is the decoded one ("my tex.png").
  const std::string uri = syntax == SideFileSyntax::kUri ? PercentDecode(reference) : reference;
  StatusOr<std::filesystem::path> file = rule.Resolve(reference, syntax, folder);
  if (!file.ok()) {
    material.missing_texture = uri;
    mesh.warnings.push_back(
        fmt::format("material '{}': texture '{}' {}: not read, using base colour", material.name,
                    uri, file.status().message()));
    return;
  }
  StatusOr<std::vector<std::uint8_t>> bytes = ReadFileBytes(*file, kSideFileLimit);
  if (!bytes.ok() || bytes->empty()) {
    material.missing_texture = uri;
    const std::string why = bytes.ok() ? std::string() : UnreadableReason(bytes.status(), *file);
    mesh.warnings.push_back(
        why.empty() ? fmt::format("material '{}': texture '{}' not found, using base colour",
                                  material.name, uri)
                    : fmt::format("material '{}': texture '{}' {}, using base colour",
                                  material.name, uri, why));
    return;
  }
  mesh.side_files.push_back(*file);
  // Several materials often share one image: embed it once.
  for (std::size_t i = 0; i < mesh.textures.size(); ++i) {
    if (mesh.textures[i].name() == uri && mesh.textures[i].encoded() == *bytes) {
      material.texture = static_cast<std::int32_t>(i);
      return;
    }
  }
  mesh.textures.emplace_back(uri, std::move(bytes).value());
  material.texture = static_cast<std::int32_t>(mesh.textures.size() - 1);
}

}  // namespace detail

}  // namespace svokit
