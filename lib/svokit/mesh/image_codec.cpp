#include "svokit/mesh/image_codec.hpp"

#include <dlfcn.h>
#include <unistd.h>

#include <algorithm>
#include <climits>
#include <filesystem>
#include <mutex>

#include <fmt/format.h>

#include "svokit/core/file_io.hpp"

namespace svokit {

namespace {

constexpr const char* kPluginName = "libsvokit_oiio.so";

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

Status Call(const std::string& name, std::span<const std::uint8_t> bytes, ImageHeader& header,
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
  header = {h.width, h.height, h.channels, h.is_float != 0, h.format};
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

}  // namespace

StatusOr<ImageHeader> ReadImageHeader(const std::string& name,
                                      std::span<const std::uint8_t> bytes) {
  ImageHeader header;
  SVOKIT_RETURN_IF_ERROR(Call(name, bytes, header, nullptr, 0));
  return header;
}

StatusOr<std::vector<float>> DecodeImagePixels(const std::string& name,
                                               std::span<const std::uint8_t> bytes,
                                               ImageHeader& header) {
  SVOKIT_RETURN_IF_ERROR(Call(name, bytes, header, nullptr, 0));
  std::vector<float> pixels(static_cast<std::size_t>(header.width) * header.height *
                            header.channels);
  SVOKIT_RETURN_IF_ERROR(Call(name, bytes, header, pixels.data(), pixels.size()));
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
