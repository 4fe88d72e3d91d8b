// libsvokit_oiio: the plugin module that decodes and encodes images with OpenImageIO (see
// image_codec.hpp). svokit_oiio_decode: with `pixels` null it reads the header only; otherwise it
// decodes all pixels into the caller's buffer of `pixel_count` floats. svokit_oiio_encode: writes
// 8-bit pixels to a named file in a named format.

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <cstdio>
#include <memory>
#include <string>

#include "svokit/mesh/image_codec.hpp"

namespace {

// Most OIIO decoders read from memory through an IOProxy; for a format whose plugin cannot, the
// bytes go through a temporary file. The name only serves as a format hint.
class EncodedImageReader {
 public:
  EncodedImageReader(const std::string& name, const std::uint8_t* bytes, std::size_t size)
      : reader_(bytes, size) {
    const std::string ext = OIIO::Filesystem::extension(name);
    auto probe = OIIO::ImageInput::create(ext.empty() ? name : ext);
    if (probe && probe->supports("ioproxy")) {
      OIIO::ImageSpec config;
      OIIO::Filesystem::IOProxy* proxy = &reader_;
      config.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxy);
      input_ = OIIO::ImageInput::open(name, &config, proxy);
    } else {
      temp_ = OIIO::Filesystem::unique_path(OIIO::Filesystem::temp_directory_path() +
                                            "/svokit-%%%%-%%%%" + ext);
      if (OIIO::Filesystem::write_binary_file(temp_, OIIO::cspan<std::uint8_t>(bytes, size))) {
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

int Fail(const std::string& message, char* error, std::size_t error_size) {
  std::snprintf(error, error_size, "%s", message.c_str());
  return 1;
}

}  // namespace

extern "C" __attribute__((visibility("default"))) int svokit_oiio_decode(
    const char* name, const std::uint8_t* bytes, std::size_t size,
    svokit::SvokitImageHeader* header, float* pixels, std::size_t pixel_count, char* error,
    std::size_t error_size) {
  try {
    EncodedImageReader reader(name, bytes, size);
    OIIO::ImageInput* input = reader.input();
    if (!input) return Fail(reader.error(), error, error_size);
    const OIIO::ImageSpec& spec = input->spec();
    header->width = spec.width;
    header->height = spec.height;
    header->channels = spec.nchannels;
    header->is_float = spec.format.basetype == OIIO::TypeDesc::FLOAT ||
                       spec.format.basetype == OIIO::TypeDesc::HALF;
    std::snprintf(header->format, sizeof header->format, "%s", input->format_name());
    if (!pixels) return 0;
    const std::size_t needed = static_cast<std::size_t>(spec.width) *
                               static_cast<std::size_t>(spec.height) *
                               static_cast<std::size_t>(spec.nchannels);
    if (needed != pixel_count) return Fail("pixel buffer size mismatch", error, error_size);
    if (!input->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, pixels)) {
      return Fail(input->geterror(), error, error_size);
    }
    return 0;
  } catch (const std::exception& e) {
    return Fail(e.what(), error, error_size);
  }
}

extern "C" __attribute__((visibility("default"))) int svokit_oiio_encode(
    const char* path, const char* format, int width, int height, int channels,
    const std::uint8_t* pixels, char* error, std::size_t error_size) {
  try {
    auto output = OIIO::ImageOutput::create(format);
    if (!output) {
      const std::string message = OIIO::geterror();
      return Fail(message.empty() ? std::string("no writer for format '") + format + "'" : message,
                  error, error_size);
    }
    OIIO::ImageSpec spec(width, height, channels, OIIO::TypeDesc::UINT8);
    // Our alpha is straight: without this the PNG writer would un-premultiply the colours.
    spec.attribute("oiio:UnassociatedAlpha", 1);
    if (!output->open(path, spec) || !output->write_image(OIIO::TypeDesc::UINT8, pixels) ||
        !output->close()) {
      return Fail(output->geterror(), error, error_size);
    }
    return 0;
  } catch (const std::exception& e) {
    return Fail(e.what(), error, error_size);
  }
}
