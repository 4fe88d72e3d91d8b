// libsvokit_oiio: the plugin module that decodes and encodes images with OpenImageIO (see
// image_codec.hpp). svokit_oiio_decode: with `pixels` null it reads the header only; otherwise it
// decodes all pixels into the caller's buffer of `pixel_count` floats. svokit_oiio_encode_to:
// encodes 8-bit pixels in a named format and hands the bytes to the caller. svokit calls it only
// for formats whose headers it has checked first (image_headers.hpp): OIIO's readers allocate what
// a header declares inside open().

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>

#include "svokit/mesh/image_codec.hpp"

namespace {

// OpenImageIO 2.4's IOMemReader bounds its copies by offset + size in wrapping arithmetic, so a
// damaged file whose offsets point far past its end makes it copy from outside the buffer
// (OpenImageIO #5262). The same reader with the bounds checked without overflow.
class BoundedMemReader final : public OIIO::Filesystem::IOMemReader {
 public:
  using IOMemReader::IOMemReader;
  std::size_t read(void* buf, std::size_t size) override {
    const std::size_t n = pread(buf, size, m_pos);
    m_pos += static_cast<std::int64_t>(n);
    return n;
  }
  std::size_t pread(void* buf, std::size_t size, std::int64_t offset) override {
    const auto all = buffer();
    const auto length = static_cast<std::uint64_t>(all.size());
    if (offset < 0 || static_cast<std::uint64_t>(offset) >= length) return 0;
    const auto n = static_cast<std::size_t>(
        std::min<std::uint64_t>(size, length - static_cast<std::uint64_t>(offset)));
    std::memcpy(buf, all.data() + offset, n);
    return n;
  }
};

// The reader the name's extension picks decodes the bytes from memory, through an IOProxy, or,
// for a format whose reader cannot, from an unnamed in-memory file (memfd): the bytes never go
// through a file name, so no file of the same name is read instead and no temporary is left.
class EncodedImageReader {
 public:
  EncodedImageReader(const std::string& name, const std::uint8_t* bytes, std::size_t size)
      : reader_(bytes, size) {
    const std::string ext = OIIO::Filesystem::extension(name);
    // A format name ("png"): given a file name, create() would try to open that file.
    input_ = OIIO::ImageInput::create(ext.empty() ? name : ext.substr(1));
    OIIO::ImageSpec spec;
    if (!input_) {
      error_ = "unknown or unsupported image format";
    } else if (input_->supports("ioproxy")) {
      if (!input_->set_ioproxy(&reader_) || !input_->open(name, spec)) Fail();
    } else {
      memfd_ = ::memfd_create("svokit-image", MFD_CLOEXEC);
      bool written = memfd_ >= 0;
      for (std::size_t done = 0; written && done < size;) {
        const ssize_t n = ::write(memfd_, bytes + done, size - done);
        written = n > 0;
        if (written) done += static_cast<std::size_t>(n);
      }
      if (!written) {
        error_ = std::string("cannot hold the image in memory (") + std::strerror(errno) + ")";
        input_.reset();
      } else if (!input_->open("/proc/self/fd/" + std::to_string(memfd_), spec)) {
        Fail();
      }
    }
  }
  ~EncodedImageReader() {
    input_.reset();
    if (memfd_ >= 0) ::close(memfd_);
  }
  EncodedImageReader(const EncodedImageReader&) = delete;
  EncodedImageReader& operator=(const EncodedImageReader&) = delete;

  OIIO::ImageInput* input() { return input_.get(); }
  const std::string& error() const { return error_; }

 private:
  void Fail() {
    error_ = input_->geterror();
    if (error_.empty()) error_ = OIIO::geterror();
    if (error_.empty()) error_ = "not a valid image";
    input_.reset();
  }

  BoundedMemReader reader_;
  int memfd_ = -1;
  std::unique_ptr<OIIO::ImageInput> input_;
  std::string error_;
};

// Returns `code`: 1 for a failure of the file or the data, 2 for a format OIIO cannot write.
int Fail(const std::string& message, char* error, std::size_t error_size, int code = 1) {
  std::snprintf(error, error_size, "%s", message.c_str());
  return code;
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

extern "C" __attribute__((visibility("default"))) int svokit_oiio_encode_to(
    const char* format, int width, int height, int channels, const std::uint8_t* pixels,
    svokit::SvokitEmitFn emit, void* context, char* error, std::size_t error_size) {
  try {
    auto output = OIIO::ImageOutput::create(format);
    if (!output) {
      const std::string message = OIIO::geterror();
      return Fail(message.empty() ? std::string("no writer for format '") + format + "'" : message,
                  error, error_size, 2);
    }
    // Encoded in memory: OIIO's writers do not all check their file writes, the caller does.
    if (!output->supports("ioproxy")) {
      return Fail(std::string("OpenImageIO cannot write '") + format + "' to memory", error,
                  error_size, 2);
    }
    OIIO::Filesystem::IOVecOutput memory;
    OIIO::ImageSpec spec(width, height, channels, OIIO::TypeDesc::UINT8);
    // Our alpha is straight: without this the PNG writer would un-premultiply the colours.
    spec.attribute("oiio:UnassociatedAlpha", 1);
    if (!output->set_ioproxy(&memory) || !output->open(std::string("image.") + format, spec) ||
        !output->write_image(OIIO::TypeDesc::UINT8, pixels) || !output->close()) {
      return Fail(output->geterror(), error, error_size);
    }
    emit(context, memory.buffer().data(), memory.buffer().size());
    return 0;
  } catch (const std::exception& e) {
    return Fail(e.what(), error, error_size);
  }
}
