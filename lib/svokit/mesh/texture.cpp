#include "svokit/mesh/texture.hpp"

#include <mutex>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

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

namespace {

// Opens encoded bytes with OIIO. Most decoders read from memory through an IOProxy; for a format
// whose plugin cannot, the bytes go through a temporary file. The name only serves as a format
// hint.
class EncodedImageReader {
 public:
  EncodedImageReader(const std::string& name, const std::vector<std::uint8_t>& bytes)
      : reader_(bytes.data(), bytes.size()) {
    std::string ext = OIIO::Filesystem::extension(name);
    auto probe = OIIO::ImageInput::create(ext.empty() ? name : ext);
    if (probe && probe->supports("ioproxy")) {
      OIIO::ImageSpec config;
      OIIO::Filesystem::IOProxy* proxy = &reader_;
      config.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxy);
      input_ = OIIO::ImageInput::open(name, &config, proxy);
    } else {
      temp_ = OIIO::Filesystem::unique_path(OIIO::Filesystem::temp_directory_path() +
                                            "/svokit-%%%%-%%%%" + ext);
      if (OIIO::Filesystem::write_binary_file(temp_, bytes)) {
        input_ = OIIO::ImageInput::open(temp_);
      }
    }
    if (!input_) error_ = OIIO::geterror();
    if (error_.empty() && !input_) error_ = "unknown or unsupported image format";
  }
  ~EncodedImageReader() {
    input_.reset();
    if (!temp_.empty()) OIIO::Filesystem::remove(temp_);
  }
  EncodedImageReader(const EncodedImageReader&) = delete;
  EncodedImageReader& operator=(const EncodedImageReader&) = delete;

  OIIO::ImageInput* input() { return input_.get(); }
  const std::string& error() const { return error_; }

 private:
  OIIO::Filesystem::IOMemReader reader_;
  std::string temp_;
  std::unique_ptr<OIIO::ImageInput> input_;
  std::string error_;
};

}  // namespace

StatusOr<Texture::Info> Texture::ReadInfo() const {
  EncodedImageReader reader(name_, encoded_);
  OIIO::ImageInput* input = reader.input();
  if (!input) return Status::BadInput("texture '{}': cannot decode ({})", name_, reader.error());
  const OIIO::ImageSpec& spec = input->spec();
  return Info{spec.width, spec.height, spec.nchannels, input->format_name()};
}

StatusOr<const Image*> Texture::Decoded() const {
  if (!cache_) return Status::BadInput("texture '{}' has no data", name_);
  std::call_once(cache_->once, [this] {
    EncodedImageReader reader(name_, encoded_);
    OIIO::ImageInput* input = reader.input();
    if (!input) {
      cache_->status = Status::BadInput("texture '{}': cannot decode ({})", name_, reader.error());
      return;
    }
    const OIIO::ImageSpec& spec = input->spec();
    const int nc = spec.nchannels;
    if (spec.width <= 0 || spec.height <= 0 || nc <= 0) {
      cache_->status = Status::BadInput("texture '{}': empty image", name_);
      return;
    }
    std::vector<float> pixels(static_cast<std::size_t>(spec.width) * spec.height * nc);
    if (!input->read_image(0, 0, 0, nc, OIIO::TypeDesc::FLOAT, pixels.data())) {
      cache_->status =
          Status::BadInput("texture '{}': cannot decode ({})", name_, input->geterror());
      return;
    }
    Image& img = cache_->image;
    img.width = spec.width;
    img.height = spec.height;
    img.rgba.resize(static_cast<std::size_t>(img.width) * img.height * 4);
    // Grey, grey+alpha, RGB and RGBA all become linear RGBA; alpha is never sRGB-encoded.
    const bool decode_srgb = srgb_ && spec.format.basetype != OIIO::TypeDesc::FLOAT &&
                             spec.format.basetype != OIIO::TypeDesc::HALF;
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

}  // namespace svokit
