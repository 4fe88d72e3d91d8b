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

namespace {

// Linear-light value of each 8-bit code: v/255 as OpenImageIO converts it, then the sRGB curve.
struct SrgbTable {
  float linear[256];
  SrgbTable() {
    for (int v = 0; v < 256; ++v) linear[v] = SrgbToLinear(static_cast<float>(v) * (1.f / 255.f));
  }
};

// Samples of one type as linear RGBA, `shrink` times downsampled; `to_linear(sample, channel)`
// gives a colour or alpha channel's linear value.
template <class Sample, class ToLinear>
Image ToLinearRgba(const Sample* samples, int width, int height, int channels, int shrink,
                   const ToLinear& to_linear) {
  Image img;
  const int step = 1 << shrink;
  img.width = (width + step - 1) / step;
  img.height = (height + step - 1) / step;
  img.rgba.resize(static_cast<std::size_t>(img.width) * img.height * 4);
  // Grey, grey+alpha, RGB and RGBA all become RGBA; alpha is never sRGB-encoded.
  const auto texel = [&](std::size_t i, float c[4]) {
    const Sample* src = samples + i * channels;
    c[0] = c[1] = c[2] = to_linear(src[0], 0);
    c[3] = 1.f;
    if (channels == 2) c[3] = to_linear(src[1], 3);
    if (channels >= 3) c[1] = to_linear(src[1], 1), c[2] = to_linear(src[2], 2);
    if (channels >= 4) c[3] = to_linear(src[3], 3);
  };
  if (shrink == 0) {
    const std::size_t n = static_cast<std::size_t>(width) * height;
    for (std::size_t i = 0; i < n; ++i) texel(i, &img.rgba[i * 4]);
    return img;
  }
  std::vector<double> sum(static_cast<std::size_t>(img.width) * 4);
  for (int oy = 0; oy < img.height; ++oy) {
    std::fill(sum.begin(), sum.end(), 0.0);
    const int y0 = oy * step, y1 = std::min(y0 + step, height);
    for (int y = y0; y < y1; ++y) {
      for (int x = 0; x < width; ++x) {
        float c[4];
        texel(static_cast<std::size_t>(y) * width + x, c);
        double* s = &sum[static_cast<std::size_t>(x / step) * 4];
        for (int k = 0; k < 4; ++k) s[k] += c[k];
      }
    }
    for (int ox = 0; ox < img.width; ++ox) {
      const int count = (std::min(ox * step + step, width) - ox * step) * (y1 - y0);
      for (int k = 0; k < 4; ++k) {
        img.rgba[(static_cast<std::size_t>(oy) * img.width + ox) * 4 + k] =
            static_cast<float>(sum[static_cast<std::size_t>(ox) * 4 + k] / count);
      }
    }
  }
  return img;
}

}  // namespace

StatusOr<Image> Texture::Decode(int shrink) const {
  StatusOr<ImageSamples> decoded = DecodeImageSamples(name_, encoded_);
  if (!decoded.ok()) return decoded.status();
  const ImageHeader& h = decoded->header;
  const bool srgb = srgb_ && !h.is_float;
  const int w = h.width, ht = h.height, nc = h.channels;
  shrink = std::clamp(shrink, 0, 30);
  if (h.bytes_per_sample == 1) {
    static const SrgbTable table;
    const auto* s = static_cast<const std::uint8_t*>(decoded->data.get());
    return ToLinearRgba(s, w, ht, nc, shrink, [&](std::uint8_t v, int channel) {
      return srgb && channel < 3 ? table.linear[v] : static_cast<float>(v) * (1.f / 255.f);
    });
  }
  if (h.bytes_per_sample == 2) {
    const auto* s = static_cast<const std::uint16_t*>(decoded->data.get());
    return ToLinearRgba(s, w, ht, nc, shrink, [&](std::uint16_t v, int channel) {
      const float f = static_cast<float>(v) * (1.f / 65535.f);
      return srgb && channel < 3 ? SrgbToLinear(f) : f;
    });
  }
  const auto* s = static_cast<const float*>(decoded->data.get());
  return ToLinearRgba(s, w, ht, nc, shrink, [&](float v, int channel) {
    return srgb && channel < 3 ? SrgbToLinear(v) : v;
  });
}

StatusOr<const Image*> Texture::Decoded() const {
  if (!cache_) return Status::BadInput("texture '{}' has no data", name_);
  std::call_once(cache_->once, [this] {
    StatusOr<Image> image = Decode();
    if (image.ok()) {
      cache_->image = std::move(image).value();
    } else {
      cache_->status = image.status();
    }
  });
  if (!cache_->status.ok()) return cache_->status;
  return &cache_->image;
}

namespace detail {

void AttachTextureFile(const SideFileRule& rule, const std::filesystem::path& folder,
                       const std::string& reference, SideFileSyntax syntax, Material& material,
                       Mesh& mesh, TextureUse use) {
  const bool coverage = use == TextureUse::kCoverage;
  std::int32_t& slot = coverage ? material.alpha_texture : material.texture;
  const char* fallback = coverage ? "the material is opaque" : "using base colour";
  // glTF names its images by URI: the name kept is the decoded one ("my tex.png").
  const std::string uri = syntax == SideFileSyntax::kUri ? PercentDecode(reference) : reference;
  StatusOr<std::filesystem::path> file = rule.Resolve(reference, syntax, folder);
  if (!file.ok()) {
    if (!coverage) material.missing_texture = uri;
    mesh.warnings.push_back(fmt::format("material '{}': texture '{}' {}: not read, {}",
                                        material.name, uri, file.status().message(), fallback));
    return;
  }
  StatusOr<std::vector<std::uint8_t>> bytes = ReadFileBytes(*file, kSideFileLimit);
  if (!bytes.ok() || bytes->empty()) {
    if (!coverage) material.missing_texture = uri;
    const std::string why = bytes.ok() ? std::string() : UnreadableReason(bytes.status(), *file);
    mesh.warnings.push_back(
        why.empty()
            ? fmt::format("material '{}': texture '{}' not found, {}", material.name, uri, fallback)
            : fmt::format("material '{}': texture '{}' {}, {}", material.name, uri, why, fallback));
    return;
  }
  mesh.side_files.push_back(*file);
  // Bytes that are not an image svokit reads are never stored (they may be any file at all).
  if (StatusOr<ImageHeader> header = ReadImageHeader(uri, *bytes); !header.ok()) {
    if (!coverage) material.missing_texture = uri;
    mesh.warnings.push_back(
        fmt::format("material '{}': {}; {}", material.name, header.status().message(), fallback));
    return;
  }
  // Several materials often share one image: embed it once. A coverage map is linear data.
  const bool srgb = !coverage;
  for (std::size_t i = 0; i < mesh.textures.size(); ++i) {
    if (mesh.textures[i].name() == uri && mesh.textures[i].srgb() == srgb &&
        mesh.textures[i].encoded() == *bytes) {
      slot = static_cast<std::int32_t>(i);
      return;
    }
  }
  mesh.textures.emplace_back(uri, std::move(bytes).value(), srgb);
  slot = static_cast<std::int32_t>(mesh.textures.size() - 1);
}

}  // namespace detail

}  // namespace svokit
