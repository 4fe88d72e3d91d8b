#include "svokit/mesh/image_codec.hpp"

#include <dlfcn.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <climits>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <optional>
#include <thread>

#include <fmt/format.h>

#include "svokit/core/file_io.hpp"
#include "svokit/mesh/image_headers.hpp"
#include "svokit/mesh/png_writer.hpp"
#include "svokit/mesh/stb_codec.hpp"

namespace svokit {

namespace {

constexpr const char* kPluginName = "libsvokit_oiio.so";

// The address space loading the plugin maps (its ~260 libraries: 440 MB measured with
// OpenImageIO 2.4 on Debian 12), and a thread stack per hardware thread for OpenImageIO's pool.
// Below it, a library's static constructors fail with bad_alloc or a segfault, or deadlock.
constexpr std::uint64_t kPluginAddressSpace = std::uint64_t{512} << 20;
constexpr std::uint64_t kPluginThreadStack = std::uint64_t{8} << 20;

// The address space left under RLIMIT_AS (`ulimit -v`); none when there is no limit.
std::optional<std::uint64_t> AddressSpaceLeft() {
  rlimit limit{};
  if (::getrlimit(RLIMIT_AS, &limit) != 0 || limit.rlim_cur == RLIM_INFINITY) return std::nullopt;
  std::ifstream status("/proc/self/status");
  std::uint64_t used_kb = 0;
  for (std::string line; std::getline(status, line);) {
    if (line.starts_with("VmSize:")) used_kb = std::strtoull(line.c_str() + 7, nullptr, 10);
  }
  const std::uint64_t used = used_kb << 10;
  return limit.rlim_cur > used ? limit.rlim_cur - used : 0;
}

// Refuses, as out of memory, to load the plugin into less address space than it maps.
Status CheckPluginHeadroom() {
  const std::uint64_t needed =
      kPluginAddressSpace + kPluginThreadStack * std::max(1u, std::thread::hardware_concurrency());
  const std::optional<std::uint64_t> left = AddressSpaceLeft();
  if (!left || *left >= needed) return Status::Ok();
  return Status::OutOfMemory(
      "cannot load the image plugin for OpenEXR and TIFF: it needs {} MiB of address space, {} "
      "MiB are left under the limit (ulimit -v)",
      needed >> 20, *left >> 20);
}

struct Plugin {
  SvokitDecodeFn decode = nullptr;
  SvokitEncodeFn encode = nullptr;  // null in a plugin of an older svokit
  Status error;                     // why there is no plugin
};

// Candidates, in order: $SVOKIT_PLUGIN_DIR, the running executable's ../lib and its own folder,
// the build tree this library was built in, the configured install prefix's lib (for programs of
// other projects linking the installed library), then the dynamic loader's search path.
const Plugin& LoadPlugin() {
  static Plugin plugin;
  static std::once_flag once;
  std::call_once(once, [] {
    if (plugin.error = CheckPluginHeadroom(); !plugin.error.ok()) return;
    std::vector<std::string> candidates;
    if (const char* dir = std::getenv("SVOKIT_PLUGIN_DIR")) {
      candidates.push_back(std::string(dir) + "/" + kPluginName);
    }
    char exe[PATH_MAX];
    const ssize_t n = ::readlink("/proc/self/exe", exe, sizeof exe - 1);
    if (n > 0) {
      const std::filesystem::path dir = std::filesystem::path(std::string(exe, n)).parent_path();
      candidates.push_back((dir.parent_path() / "lib" / kPluginName).string());
      candidates.push_back((dir / kPluginName).string());
    }
#ifdef SVOKIT_PLUGIN_BUILD_DIR
    candidates.push_back(std::string(SVOKIT_PLUGIN_BUILD_DIR) + "/" + kPluginName);
#endif
#ifdef SVOKIT_PLUGIN_INSTALL_DIR
    candidates.push_back(std::string(SVOKIT_PLUGIN_INSTALL_DIR) + "/" + kPluginName);
#endif
    candidates.push_back(kPluginName);
    for (const std::string& path : candidates) {
      void* handle = ::dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
      if (!handle) {
        // A plugin that is there but does not load (its libraries missing, no memory) says why.
        std::error_code ec;
        if (plugin.error.ok() && std::filesystem::is_regular_file(path, ec)) {
          const std::string why = ::dlerror();
          const bool memory = why.find("failed to map") != std::string::npos ||
                              why.find("Cannot allocate memory") != std::string::npos;
          plugin.error = Status(memory ? StatusCode::kOutOfMemory : StatusCode::kInternal,
                                fmt::format("cannot load the image plugin ({})", why));
        }
        continue;
      }
      plugin.decode = reinterpret_cast<SvokitDecodeFn>(::dlsym(handle, "svokit_oiio_decode"));
      plugin.encode = reinterpret_cast<SvokitEncodeFn>(::dlsym(handle, "svokit_oiio_encode_to"));
      if (plugin.decode) {
        plugin.error = Status::Ok();
        return;
      }
    }
    if (plugin.error.ok()) {
      plugin.error = Status::Internal("the image plugin {} was not found (set SVOKIT_PLUGIN_DIR)",
                                      kPluginName);
    }
  });
  return plugin;
}

// Decodes through the plugin: a header only when `pixels` is null.
Status CallPlugin(const std::string& name, std::span<const std::uint8_t> bytes, ImageHeader& header,
                  float* pixels, std::size_t pixel_count) {
  const Plugin& plugin = LoadPlugin();
  if (!plugin.decode) return plugin.error.WithContext(fmt::format("texture '{}'", name));
  SvokitImageHeader h{};
  char error[512] = {};
  if (plugin.decode(name.c_str(), bytes.data(), bytes.size(), &h, pixels, pixel_count, error,
                    sizeof error) != 0) {
    // Readers report one problem per line (OpenEXR's core a whole chain): the error is one line.
    std::string message = error;
    while (!message.empty() && message.back() == '\n') message.pop_back();
    std::replace(message.begin(), message.end(), '\n', ';');
    return Status::BadInput("texture '{}': cannot decode ({})", name, message);
  }
  header = {h.width, h.height, h.channels, h.is_float != 0, h.format, 4, true};
  return CheckImageSize(name, header);
}

// The fewest bytes a file of `h`'s format can hold its pixels in: the format's best compression
// (zlib 1032:1, a JPEG block in 1 bit, GIF's 12-bit LZW codes of at most 4096 pixels, RLE packets
// of 128 pixels, uncompressed rows). A shorter file is truncated or crafted, and stb would decode
// it whole from zeros: a 17-byte PPM declaring 8192² took 1.2 GB and 4 s.
std::uint64_t FewestEncodedBytes(const ImageHeader& h) {
  const auto pixels = static_cast<std::uint64_t>(h.width) * static_cast<std::uint64_t>(h.height);
  const std::string& f = h.format;
  if (f == "png") {
    const std::uint64_t raw = static_cast<std::uint64_t>(h.height) *
                              (1 + static_cast<std::uint64_t>(h.width) * h.channels *
                                       static_cast<std::uint64_t>(h.bytes_per_sample));
    return raw / 1032;
  }
  if (f == "jpeg") return pixels / 1024;
  if (f == "gif") return pixels / 16384;
  if (f == "bmp") return pixels / 8;
  if (f == "tga" || f == "psd") return pixels / 64;
  if (f == "hdr") return pixels / 16;
  if (f == "pnm") return pixels * static_cast<std::uint64_t>(h.channels);
  return 0;
}

}  // namespace

Status CheckImageSize(const std::string& name, const ImageHeader& h) {
  if (h.width <= 0 || h.height <= 0 || h.channels <= 0) {
    return Status::BadInput("texture '{}': empty image", name);
  }
  if (OverImageLimits(h.width, h.height) || h.channels > 4) {
    return Status::BadInput(
        "texture '{}': {}x{} pixels with {} channels, over the limit of {} pixels, {} per side "
        "and 4 channels",
        name, h.width, h.height, h.channels, kImagePixelLimit, kImageSideLimit);
  }
  return Status::Ok();
}

StatusOr<ImageHeader> ReadImageHeader(const std::string& name,
                                      std::span<const std::uint8_t> bytes) {
  ImageHeader header;
  if (const std::optional<stb::Header> h = stb::ReadHeader(bytes)) {
    if (!h->error.empty()) {
      return Status::BadInput("texture '{}': cannot decode ({} header: {})", name, h->format,
                              h->error);
    }
    header = {h->width,  h->height,           h->channels, h->bytes_per_sample == 4,
              h->format, h->bytes_per_sample, false};
    SVOKIT_RETURN_IF_ERROR(CheckImageSize(name, header));
    if (const std::uint64_t fewest = FewestEncodedBytes(header); bytes.size() < fewest) {
      return Status::BadInput(
          "texture '{}': cannot decode ({} header declares {}x{} pixels, which take at least {} "
          "bytes; the file has {})",
          name, header.format, header.width, header.height, fewest, bytes.size());
    }
  } else {
    const PluginImageHeader p = ReadPluginImageHeader(bytes);
    if (*p.format == '\0') {
      return Status::BadInput(
          "texture '{}': unsupported image format (svokit reads PNG, JPEG, "
          "BMP, TGA, GIF, HDR, PSD, PNM, OpenEXR and TIFF)",
          name);
    }
    if (!p.error.empty())
      return Status::BadInput("texture '{}': cannot decode ({})", name, p.error);
    // Sizes past int are over the limits: clamp for the message.
    header = {static_cast<int>(std::min<std::int64_t>(p.width, INT_MAX)),
              static_cast<int>(std::min<std::int64_t>(p.height, INT_MAX)),
              p.channels,
              p.is_float,
              p.format,
              4,
              true};
  }
  SVOKIT_RETURN_IF_ERROR(CheckImageSize(name, header));
  return header;
}

std::uint64_t ImageDecodeBytes(const ImageHeader& h, std::size_t encoded_size) {
  // Per pixel of the padded image (JPEG decodes whole 16 × 16 blocks), with 4 channels: PNG holds
  // the inflated rows and the image; JPEG its components, progressive coefficients and the image;
  // GIF the image, the background and a history; HDR floats; the others the image and a copy;
  // OpenImageIO a chunk of rows beside the floats it returns (counted by the caller).
  const std::uint64_t pixels =
      static_cast<std::uint64_t>(h.width + 16) * static_cast<std::uint64_t>(h.height + 16);
  const std::string& f = h.format;
  const std::uint64_t per_pixel = h.needs_plugin ? 4 * 4
                                  : f == "png"   ? 2 * 4 * h.bytes_per_sample
                                  : f == "jpeg"  ? 16
                                  : f == "gif"   ? 12
                                  : f == "hdr"   ? 20
                                                 : 2 * 4 * h.bytes_per_sample;
  // The encoded data gathered (PNG's IDAT chunks) and fixed tables.
  return pixels * per_pixel + 2 * std::uint64_t{encoded_size} + (std::uint64_t{4} << 20);
}

StatusOr<ImageSamples> DecodeImageSamples(const std::string& name,
                                          std::span<const std::uint8_t> bytes) {
  StatusOr<ImageHeader> header = ReadImageHeader(name, bytes);
  if (!header.ok()) return header.status();
  if (header->needs_plugin) {
    ImageHeader h;
    SVOKIT_RETURN_IF_ERROR(CallPlugin(name, bytes, h, nullptr, 0));
    auto pixels = std::make_shared<std::vector<float>>(static_cast<std::size_t>(h.width) *
                                                       h.height * h.channels);
    SVOKIT_RETURN_IF_ERROR(CallPlugin(name, bytes, h, pixels->data(), pixels->size()));
    return ImageSamples{h, std::shared_ptr<const void>(pixels, pixels->data())};
  }
  const std::uint64_t cap = ImageDecodeBytes(*header, bytes.size());
  stb::DecodeResult decoded = stb::Decode(bytes, static_cast<std::size_t>(cap));
  if (decoded.over_cap) {
    return Status::BadInput("texture '{}': needs more than {} MiB to decode a {}x{} image", name,
                            cap >> 20, header->width, header->height);
  }
  if (!decoded.samples) {
    return Status::BadInput("texture '{}': cannot decode ({})", name, decoded.error);
  }
  ImageHeader& h = *header;
  h.channels = decoded.samples->header.channels;
  SVOKIT_RETURN_IF_ERROR(CheckImageSize(name, h));
  return ImageSamples{h, std::move(decoded.samples->data)};
}

StatusOr<std::vector<float>> DecodeImagePixels(const std::string& name,
                                               std::span<const std::uint8_t> bytes,
                                               ImageHeader& header) {
  StatusOr<ImageSamples> samples = DecodeImageSamples(name, bytes);
  if (!samples.ok()) return samples.status();
  header = samples->header;
  const std::size_t n = static_cast<std::size_t>(header.width) * header.height * header.channels;
  std::vector<float> pixels(n);
  // The scales OpenImageIO converts with, so both decoders give the same floats.
  if (header.bytes_per_sample == 1) {
    const auto* s = static_cast<const std::uint8_t*>(samples->data.get());
    for (std::size_t i = 0; i < n; ++i) pixels[i] = s[i] * (1.f / 255.f);
  } else if (header.bytes_per_sample == 2) {
    const auto* s = static_cast<const std::uint16_t*>(samples->data.get());
    for (std::size_t i = 0; i < n; ++i) pixels[i] = s[i] * (1.f / 65535.f);
  } else {
    const auto* s = static_cast<const float*>(samples->data.get());
    std::copy(s, s + n, pixels.begin());
  }
  return pixels;
}

Status WriteImage(const std::filesystem::path& path, int width, int height, int channels,
                  std::span<const std::uint8_t> pixels) {
  if (width <= 0 || height <= 0 || channels < 1 || channels > 4) {
    return Status::BadInput("{}: cannot write a {}x{} image with {} channels", path.string(), width,
                            height, channels);
  }
  if (pixels.size() != static_cast<std::size_t>(width) * static_cast<std::size_t>(height) *
                           static_cast<std::size_t>(channels)) {
    return Status::Internal("{}: {} pixel bytes for a {}x{}x{} image", path.string(), pixels.size(),
                            width, height, channels);
  }
  const std::string format = LowerExtension(path);
  if (format.empty()) {
    return Status::BadInput("{}: no extension to choose an image format by", path.string());
  }
  if (format == "png") {
    StatusOr<PngWriter> png = PngWriter::Open(path, width, height, channels);
    if (!png.ok()) return png.status();
    SVOKIT_RETURN_IF_ERROR(png->WriteRows(pixels));
    return png->Commit();
  }
  const Plugin& plugin = LoadPlugin();
  if (!plugin.decode) return plugin.error.WithContext(path.string());
  if (!plugin.encode) {
    return Status::Internal("{}: the image plugin {} cannot write images (rebuild it)",
                            path.string(), kPluginName);
  }
  char error[512] = {};
  std::vector<std::uint8_t> encoded;
  const SvokitEmitFn keep = [](void* context, const std::uint8_t* bytes, std::size_t size) {
    static_cast<std::vector<std::uint8_t>*>(context)->assign(bytes, bytes + size);
  };
  const int failed = plugin.encode(format.c_str(), width, height, channels, pixels.data(), keep,
                                   &encoded, error, sizeof error);
  if (failed == 2) return Status::BadInput("{}: {}", path.string(), error);
  if (failed != 0)
    return Status::Internal("{}: cannot encode the image ({})", path.string(), error);
  return WriteFileAtomic(path, encoded);
}

}  // namespace svokit
