// glTF 2.0 import: .gltf (external or data-URI buffers) and .glb. tinygltf parses the JSON and
// loads the buffers but checks neither indices nor byte ranges, so every index and every byte range
// is checked here before use. Each primitive becomes an indexed draco::Mesh (decoded from
// KHR_draco_mesh_compression, or gathered from accessors) and goes through AppendDracoMesh; the
// node's world transform is then applied to what was appended.

#include <unistd.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <draco/compression/decode.h>
#include <draco/mesh/mesh.h>
#include <nlohmann/json.hpp>

// The same configuration as tiny_gltf_impl.cpp, which compiles the implementation.
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#define TINYGLTF_USE_CPP14
#include <tiny_gltf.h>

#include "svokit/core/file_io.hpp"
#include "svokit/mesh/image_codec.hpp"
#include "svokit/mesh/importers.hpp"

namespace svokit::detail {
namespace {

// Limits against hostile files. A small node graph can expand exponentially (each node instancing
// its child twice), so node instances and the triangles that repeated instances add are capped (a
// primitive's first instance is bounded by the file's size). Accessors without a buffer view can
// claim any element count without holding data. tinygltf converts JSON values recursively.
constexpr std::size_t kMaxNodeInstances = std::size_t{1} << 22;
constexpr std::size_t kMaxInstancedTriangles = std::size_t{1} << 26;
constexpr std::size_t kMaxZeroFilledElements = std::size_t{1} << 24;
constexpr std::size_t kMaxJsonDepth = 128;

// ---------------------------------------------------------------------------------------------
// Loading

// tinygltf reports problems as multi-line text; svokit messages are one line.
std::string OneLine(std::string_view text) {
  std::string out;
  while (!text.empty()) {
    const std::size_t end = std::min(text.find('\n'), text.size());
    std::string_view line = text.substr(0, end);
    text.remove_prefix(std::min(end + 1, text.size()));
    while (!line.empty() && std::isspace(static_cast<unsigned char>(line.back()))) {
      line.remove_suffix(1);
    }
    while (!line.empty() && std::isspace(static_cast<unsigned char>(line.front()))) {
      line.remove_prefix(1);
    }
    if (line.empty()) continue;
    if (!out.empty()) out += "; ";
    out += line;
  }
  return out;
}

// tinygltf hands data-URI images to this callback; they stay encoded and OIIO decodes them lazily.
// For buffer-view images it passes an unchecked pointer into the buffer, so those are ignored here
// and read later through the bounds-checked ViewBytes.
bool KeepEncodedImage(tinygltf::Image* image, const int /*index*/, std::string* /*err*/,
                      std::string* /*warn*/, int /*width*/, int /*height*/,
                      const unsigned char* bytes, int size, void* /*user_data*/) {
  if (image->bufferView < 0 && bytes != nullptr && size > 0) {
    image->image.assign(bytes, bytes + size);
  }
  image->as_is = true;
  return true;
}

bool IsBinaryGltf(std::span<const std::uint8_t> bytes) {
  return bytes.size() >= 4 && std::memcmp(bytes.data(), "glTF", 4) == 0;
}

std::uint32_t ReadU32(std::span<const std::uint8_t> bytes, std::size_t offset) {
  std::uint32_t v = 0;
  std::memcpy(&v, bytes.data() + offset, 4);
  return v;
}

// The JSON text of a .gltf, or of a .glb's first chunk (GLB header: magic, version, length; chunk
// header: length, type).
StatusOr<std::string_view> JsonText(std::span<const std::uint8_t> file, bool binary) {
  if (!binary) return std::string_view(reinterpret_cast<const char*>(file.data()), file.size());
  if (file.size() < 20 || !IsBinaryGltf(file)) {
    return Status::BadInput("not a binary glTF file (no GLB header)");
  }
  if (ReadU32(file, 4) == 1) {
    return Status::BadInput(
        "glTF 1.0 is not supported (binary glTF version 1); convert to glTF 2.0");
  }
  const std::uint32_t json_length = ReadU32(file, 12);
  if (json_length > file.size() - 20) {
    return Status::BadInput("truncated binary glTF (its JSON chunk needs {} bytes, {} remain)",
                            json_length, file.size() - 20);
  }
  return std::string_view(reinterpret_cast<const char*>(file.data()) + 20, json_length);
}

// asset.version must be 2.x; glTF 1.0 is a different format that tinygltf half-parses.
Status CheckVersion(const nlohmann::json& doc) {
  const auto asset = doc.find("asset");
  if (asset == doc.end() || !asset->is_object() || !asset->contains("version") ||
      !(*asset)["version"].is_string()) {
    return Status::BadInput("asset.version is missing (not a glTF 2.0 file)");
  }
  const std::string version = (*asset)["version"];
  const std::string major = version.substr(0, version.find('.'));
  if (major == "2") return Status::Ok();
  if (major == "1") {
    return Status::BadInput("glTF 1.0 is not supported (asset.version {}); convert to glTF 2.0",
                            version);
  }
  return Status::BadInput("unsupported glTF version (asset.version '{}')", version);
}

// Depth of the deepest JSON value, found without recursion.
std::size_t JsonDepth(const nlohmann::json& doc) {
  std::size_t deepest = 0;
  std::vector<std::pair<const nlohmann::json*, std::size_t>> pending = {{&doc, 1}};
  while (!pending.empty()) {
    const auto [value, depth] = pending.back();
    pending.pop_back();
    deepest = std::max(deepest, depth);
    if (value->is_structured()) {
      for (const nlohmann::json& child : *value) pending.emplace_back(&child, depth + 1);
    }
  }
  return deepest;
}

// An external buffer: the file the side-file rule resolved its URI to, and its declared length.
struct ExternalBuffer {
  std::filesystem::path file;
  std::uint64_t declared = 0;
};

// External buffers are resolved here first, by the side-file rule: a buffer outside the allowed
// folders is an error (the mesh cannot be built without it), as is one that does not exist
// (tinygltf would also search the working directory, and its message does not say which buffer
// is missing). Their files and declared byteLengths go to `buffers`, in order: tinygltf reads
// them in that order, and BufferReader reads those files and only that much.
Status CheckExternalBuffers(const nlohmann::json& doc, const SideFileRule& rule,
                            std::vector<ExternalBuffer>& external) {
  const auto buffers = doc.find("buffers");
  if (buffers == doc.end() || !buffers->is_array()) return Status::Ok();
  for (std::size_t i = 0; i < buffers->size(); ++i) {
    const nlohmann::json& buffer = (*buffers)[i];
    if (!buffer.is_object() || !buffer.contains("uri") || !buffer["uri"].is_string()) continue;
    const std::string uri = buffer["uri"];
    if (tinygltf::IsDataURI(uri)) continue;
    StatusOr<std::filesystem::path> file =
        rule.Resolve(uri, SideFileSyntax::kUri, rule.model_folder());
    if (!file.ok()) {
      return Status::BadInput("buffer {} '{}' {}: not read", i, uri, file.status().message());
    }
    std::error_code ec;
    if (!std::filesystem::is_regular_file(*file, ec)) {
      return Status::BadInput("buffer {} '{}' not found", i, uri);
    }
    const auto length = buffer.find("byteLength");
    external.push_back({*file, length != buffer.end() && length->is_number_unsigned()
                                   ? length->get<std::uint64_t>()
                                   : 0});
  }
  return Status::Ok();
}

// A sparse count is read by tinygltf into an int: 2^40 would silently become 0. Each must be a
// whole number no larger than its accessor's count (nor an int), checked before anything is
// sized by it.
Status CheckSparseCounts(const nlohmann::json& doc) {
  constexpr auto kMaxSparseCount = static_cast<std::uint64_t>(std::numeric_limits<int>::max());
  const auto accessors = doc.find("accessors");
  if (accessors == doc.end() || !accessors->is_array()) return Status::Ok();
  for (std::size_t i = 0; i < accessors->size(); ++i) {
    const nlohmann::json& accessor = (*accessors)[i];
    if (!accessor.is_object() || !accessor.contains("sparse")) continue;
    const nlohmann::json& sparse = accessor["sparse"];
    // A sparse object without a count is left to tinygltf, which says what is missing.
    if (!sparse.is_object() || !sparse.contains("count")) continue;
    const nlohmann::json& count = sparse["count"];
    const auto elements = accessor.find("count");
    const std::uint64_t accessor_count =
        elements != accessor.end() && elements->is_number_unsigned()
            ? elements->get<std::uint64_t>()
            : 0;
    if (!count.is_number_unsigned()) {
      return Status::BadInput("accessor {} has sparse count {}, not a count", i, count.dump());
    }
    if (count.get<std::uint64_t>() > std::min(accessor_count, kMaxSparseCount)) {
      return Status::BadInput("accessor {} has sparse count {} for {} elements", i,
                              count.get<std::uint64_t>(), accessor_count);
    }
  }
  return Status::Ok();
}

// tinygltf's file reader for external buffers. Its own reads a whole file and only then compares
// the size with byteLength, so a short glTF naming a huge file would read all of it; this reads
// the declared bytes and no more, and refuses a file that is not regular or shorter than declared.
struct BufferReader {
  std::vector<ExternalBuffer> buffers;  // in the order tinygltf reads them
  std::size_t next = 0;
  std::vector<std::filesystem::path>* read = nullptr;  // the files read, for Mesh::side_files

  // Every external buffer was resolved and found before tinygltf runs: its own check opens the
  // file, which waits forever on a FIFO, and it would search the working directory too.
  static bool Exists(const std::string& /*path*/, void* /*user_data*/) { return true; }

  static bool Read(std::vector<unsigned char>* out, std::string* err, const std::string& path,
                   void* user_data) {
    auto* self = static_cast<BufferReader*>(user_data);
    if (self->next >= self->buffers.size()) {
      if (err) *err += "not a buffer this file declares";
      return false;
    }
    const ExternalBuffer& buffer = self->buffers[self->next++];
    StatusOr<std::vector<std::uint8_t>> bytes =
        ReadFilePrefix(buffer.file, buffer.declared, kInputFileLimit);
    if (!bytes.ok()) {
      std::string_view why = bytes.status().message();  // tinygltf names the file itself
      const std::string prefix = buffer.file.string() + ": ";
      if (why.starts_with(prefix)) why.remove_prefix(prefix.size());
      if (why.starts_with(path + ": ")) why.remove_prefix(path.size() + 2);
      if (err) *err += why;
      return false;
    }
    if (self->read != nullptr) self->read->push_back(buffer.file);
    *out = std::move(bytes).value();
    return true;
  }
};

// tinygltf passes an image's buffer view to the image loader without checking it against its
// buffer (an out-of-range access that aborts builds with _GLIBCXX_ASSERTIONS), so image views are
// checked here against the declared buffer sizes, which tinygltf does enforce on load.
Status CheckImageViews(const nlohmann::json& doc) {
  const auto images = doc.find("images");
  if (images == doc.end() || !images->is_array()) return Status::Ok();
  // Reads a non-negative integer member into `out` (left unchanged if absent and not required).
  auto number = [](const nlohmann::json* object, const char* key, std::uint64_t& out,
                   bool required) {
    if (object == nullptr || !object->is_object()) return false;
    if (!object->contains(key)) return !required;
    const nlohmann::json& v = (*object)[key];
    if (!v.is_number_unsigned()) return false;
    out = v.get<std::uint64_t>();
    return true;
  };
  auto element = [&](const char* array, std::uint64_t index) -> const nlohmann::json* {
    const auto it = doc.find(array);
    return it != doc.end() && it->is_array() && index < it->size() ? &(*it)[index] : nullptr;
  };
  for (std::size_t i = 0; i < images->size(); ++i) {
    const nlohmann::json& image = (*images)[i];
    if (!image.is_object() || !image.contains("bufferView")) continue;
    std::uint64_t view_index = 0, buffer_index = 0, offset = 0, length = 0, size = 0;
    const nlohmann::json* view = number(&image, "bufferView", view_index, true)
                                     ? element("bufferViews", view_index)
                                     : nullptr;
    const bool view_ok = number(view, "buffer", buffer_index, true) &&
                         number(view, "byteOffset", offset, false) &&
                         number(view, "byteLength", length, true);
    const nlohmann::json* buffer = view_ok ? element("buffers", buffer_index) : nullptr;
    if (!number(buffer, "byteLength", size, true) || offset > size || length > size - offset) {
      return Status::BadInput("image {} refers to a buffer view outside its buffer", i);
    }
  }
  return Status::Ok();
}

// tinygltf 2.7 (built without its own Draco support) rejects index accessors without a buffer
// view, which is how KHR_draco_mesh_compression primitives declare theirs. Their faces come from
// the Draco data, so those primitives lose "indices". Returns whether anything changed.
bool DropDracoIndices(nlohmann::json& doc) {
  bool changed = false;
  const auto meshes = doc.find("meshes");
  if (meshes == doc.end() || !meshes->is_array()) return false;
  for (nlohmann::json& mesh : *meshes) {
    if (!mesh.is_object() || !mesh.contains("primitives") || !mesh["primitives"].is_array()) {
      continue;
    }
    for (nlohmann::json& prim : mesh["primitives"]) {
      if (prim.is_object() && prim.contains("extensions") && prim["extensions"].is_object() &&
          prim["extensions"].contains("KHR_draco_mesh_compression")) {
        changed = prim.erase("indices") > 0 || changed;
      }
    }
  }
  return changed;
}

// Looks at the JSON before tinygltf does (JsonDepth, CheckVersion, CheckExternalBuffers,
// CheckSparseCounts, CheckImageViews, DropDracoIndices) and returns the JSON to load instead, if
// it had to change. JSON that does not parse is left to tinygltf, whose message says where.
StatusOr<std::optional<std::string>> Preflight(std::string_view text, const SideFileRule& rule,
                                               std::vector<ExternalBuffer>& buffers) {
  nlohmann::json doc = nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (doc.is_discarded() || !doc.is_object()) return std::optional<std::string>();
  if (JsonDepth(doc) > kMaxJsonDepth) {
    return Status::BadInput("JSON nested deeper than {} levels", kMaxJsonDepth);
  }
  SVOKIT_RETURN_IF_ERROR(CheckVersion(doc));
  SVOKIT_RETURN_IF_ERROR(CheckExternalBuffers(doc, rule, buffers));
  SVOKIT_RETURN_IF_ERROR(CheckSparseCounts(doc));
  SVOKIT_RETURN_IF_ERROR(CheckImageViews(doc));
  if (!DropDracoIndices(doc)) return std::optional<std::string>();
  return std::optional<std::string>(doc.dump());
}

// `file` with its JSON replaced by `json` (for a .glb: a new JSON chunk, padded with spaces to
// keep the following chunks 4-byte aligned as the spec requires).
std::vector<std::uint8_t> ReplaceJson(std::span<const std::uint8_t> file, bool binary,
                                      std::string json) {
  if (!binary) return {json.begin(), json.end()};
  const std::size_t old_end = 20 + std::size_t{ReadU32(file, 12)};
  json.resize((json.size() + 3) / 4 * 4, ' ');
  std::vector<std::uint8_t> out;
  out.reserve(20 + json.size() + (file.size() - old_end));
  out.insert(out.end(), file.begin(), file.begin() + 20);
  out.insert(out.end(), json.begin(), json.end());
  out.insert(out.end(), file.begin() + static_cast<std::ptrdiff_t>(old_end), file.end());
  const auto total = static_cast<std::uint32_t>(out.size());
  const auto json_length = static_cast<std::uint32_t>(json.size());
  std::memcpy(out.data() + 8, &total, 4);
  std::memcpy(out.data() + 12, &json_length, 4);
  return out;
}

// Parses a .gltf or .glb; external buffers are the files `rule` allows. tinygltf's non-fatal
// findings go to mesh.warnings, the buffers read to mesh.side_files.
StatusOr<tinygltf::Model> LoadModel(std::vector<std::uint8_t> file, bool binary,
                                    const SideFileRule& rule, Mesh& mesh) {
  const std::filesystem::path& base_dir = rule.model_folder();
  std::vector<std::string>& warnings = mesh.warnings;
  if (file.empty()) return Status::BadInput("empty file");
  StatusOr<std::string_view> json = JsonText(file, binary);
  if (!json.ok()) return json.status();
  BufferReader buffer_reader;
  buffer_reader.read = &mesh.side_files;
  StatusOr<std::optional<std::string>> changed = Preflight(*json, rule, buffer_reader.buffers);
  if (!changed.ok()) return changed.status();
  if (*changed) file = ReplaceJson(file, binary, std::move(**changed));
  if (file.size() > std::numeric_limits<std::uint32_t>::max()) {
    return Status::BadInput("file larger than 4 GiB, the glTF limit");
  }

  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(&KeepEncodedImage, nullptr);
  loader.SetFsCallbacks({.FileExists = &BufferReader::Exists,
                         .ExpandFilePath = &tinygltf::ExpandFilePath,
                         .ReadWholeFile = &BufferReader::Read,
                         .WriteWholeFile = nullptr,
                         .user_data = &buffer_reader});
  tinygltf::Model model;
  std::string err, warn;
  const auto size = static_cast<unsigned int>(file.size());
  bool loaded = false;
  try {
    loaded = binary ? loader.LoadBinaryFromMemory(&model, &err, &warn, file.data(), size,
                                                  base_dir.string())
                    : loader.LoadASCIIFromString(&model, &err, &warn,
                                                 reinterpret_cast<const char*>(file.data()), size,
                                                 base_dir.string());
  } catch (const std::exception& e) {  // tinygltf indexes with .at() in places
    loaded = false;
    err += e.what();
  }
  if (!loaded) {
    const std::string detail = OneLine(err + "\n" + warn);
    return Status::BadInput("{}", detail.empty() ? "cannot parse glTF" : detail);
  }
  for (const std::string* text : {&err, &warn}) {
    if (const std::string line = OneLine(*text); !line.empty()) warnings.push_back(line);
  }
  return model;
}

// ---------------------------------------------------------------------------------------------
// Accessors

enum class Semantic { kIndices, kPosition, kNormal, kTexcoord, kColor };

const char* SemanticName(Semantic s) {
  switch (s) {
    case Semantic::kIndices:
      return "indices";
    case Semantic::kPosition:
      return "POSITION";
    case Semantic::kNormal:
      return "NORMAL";
    case Semantic::kTexcoord:
      return "TEXCOORD_0";
    case Semantic::kColor:
      return "COLOR_0";
  }
  return "?";
}

const char* TypeName(int type) {
  switch (type) {
    case TINYGLTF_TYPE_SCALAR:
      return "SCALAR";
    case TINYGLTF_TYPE_VEC2:
      return "VEC2";
    case TINYGLTF_TYPE_VEC3:
      return "VEC3";
    case TINYGLTF_TYPE_VEC4:
      return "VEC4";
    case TINYGLTF_TYPE_MAT2:
      return "MAT2";
    case TINYGLTF_TYPE_MAT3:
      return "MAT3";
    case TINYGLTF_TYPE_MAT4:
      return "MAT4";
  }
  return "unknown";
}

const char* ComponentTypeName(int component_type) {
  switch (component_type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
      return "BYTE";
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
      return "UNSIGNED_BYTE";
    case TINYGLTF_COMPONENT_TYPE_SHORT:
      return "SHORT";
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
      return "UNSIGNED_SHORT";
    case TINYGLTF_COMPONENT_TYPE_INT:
      return "INT";
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
      return "UNSIGNED_INT";
    case TINYGLTF_COMPONENT_TYPE_FLOAT:
      return "FLOAT";
    case TINYGLTF_COMPONENT_TYPE_DOUBLE:
      return "DOUBLE";
  }
  return "unknown";
}

// The accessor types each semantic accepts, per the glTF 2.0 spec.
std::vector<int> AllowedTypes(Semantic s) {
  switch (s) {
    case Semantic::kIndices:
      return {TINYGLTF_TYPE_SCALAR};
    case Semantic::kPosition:
    case Semantic::kNormal:
      return {TINYGLTF_TYPE_VEC3};
    case Semantic::kTexcoord:
      return {TINYGLTF_TYPE_VEC2};
    case Semantic::kColor:
      return {TINYGLTF_TYPE_VEC3, TINYGLTF_TYPE_VEC4};
  }
  return {};
}

// Component types per the glTF 2.0 spec, widened by KHR_mesh_quantization (integer positions,
// normals and texture coordinates).
bool ComponentTypeAllowed(Semantic s, int type, bool normalized) {
  const bool is_float = type == TINYGLTF_COMPONENT_TYPE_FLOAT;
  const bool small_int =
      type == TINYGLTF_COMPONENT_TYPE_BYTE || type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE ||
      type == TINYGLTF_COMPONENT_TYPE_SHORT || type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT;
  switch (s) {
    case Semantic::kIndices:
      return !normalized && (type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE ||
                             type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT ||
                             type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT);
    case Semantic::kPosition:
    case Semantic::kTexcoord:
      return is_float || small_int;
    case Semantic::kNormal:
      return is_float || (normalized && (type == TINYGLTF_COMPONENT_TYPE_BYTE ||
                                         type == TINYGLTF_COMPONENT_TYPE_SHORT));
    case Semantic::kColor:
      return is_float || (normalized && (type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE ||
                                         type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT));
  }
  return false;
}

template <class T>
T LoadUnaligned(const std::uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

// One component as double; normalized integers map to [0, 1] or [-1, 1] per the glTF spec.
double ReadComponent(const std::uint8_t* p, int type, bool normalized) {
  switch (type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE: {
      const double v = LoadUnaligned<std::int8_t>(p);
      return normalized ? std::max(v / 127.0, -1.0) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: {
      const double v = LoadUnaligned<std::uint8_t>(p);
      return normalized ? v / 255.0 : v;
    }
    case TINYGLTF_COMPONENT_TYPE_SHORT: {
      const double v = LoadUnaligned<std::int16_t>(p);
      return normalized ? std::max(v / 32767.0, -1.0) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
      const double v = LoadUnaligned<std::uint16_t>(p);
      return normalized ? v / 65535.0 : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
      return LoadUnaligned<std::uint32_t>(p);
    case TINYGLTF_COMPONENT_TYPE_FLOAT:
      return LoadUnaligned<float>(p);
  }
  return 0;
}

// The bytes of buffer view `index`, after checking that the view lies inside its buffer.
StatusOr<std::span<const std::uint8_t>> ViewBytes(const tinygltf::Model& model, int index) {
  if (index < 0 || static_cast<std::size_t>(index) >= model.bufferViews.size()) {
    return Status::BadInput("buffer view {} does not exist ({} buffer views)", index,
                            model.bufferViews.size());
  }
  const tinygltf::BufferView& view = model.bufferViews[index];
  if (view.buffer < 0 || static_cast<std::size_t>(view.buffer) >= model.buffers.size()) {
    return Status::BadInput("buffer view {} refers to buffer {}, which does not exist", index,
                            view.buffer);
  }
  const std::vector<unsigned char>& data = model.buffers[view.buffer].data;
  if (view.byteOffset > data.size() || view.byteLength > data.size() - view.byteOffset) {
    return Status::BadInput(
        "buffer view {} (offset {}, length {}) extends past the end of buffer {} ({} bytes)", index,
        view.byteOffset, view.byteLength, view.buffer, data.size());
  }
  return std::span<const std::uint8_t>(data.data() + view.byteOffset, view.byteLength);
}

// Reads `count` elements of `components` components, the first `offset` bytes into `bytes` and
// each `stride` bytes after the previous, after checking that the last one ends inside `bytes`.
StatusOr<std::vector<double>> ReadElements(std::span<const std::uint8_t> bytes, std::size_t offset,
                                           std::size_t stride, std::size_t count,
                                           int component_type, int components, bool normalized) {
  const std::size_t component_size =
      static_cast<std::size_t>(tinygltf::GetComponentSizeInBytes(component_type));
  const std::size_t element_size = component_size * components;
  if (stride < element_size) {
    return Status::BadInput("byteStride {} is smaller than the element size {}", stride,
                            element_size);
  }
  // offset + (count - 1) * stride + element_size <= bytes.size(), without overflow.
  if (count > 0 && (offset > bytes.size() || element_size > bytes.size() - offset ||
                    count - 1 > (bytes.size() - offset - element_size) / stride)) {
    return Status::BadInput(
        "{} elements of {} bytes (stride {}, offset {}) exceed the {} bytes of its buffer view",
        count, element_size, stride, offset, bytes.size());
  }
  std::vector<double> values(count * components);
  for (std::size_t i = 0; i < count; ++i) {
    const std::uint8_t* element = bytes.data() + offset + i * stride;
    for (int k = 0; k < components; ++k) {
      values[i * components + k] =
          ReadComponent(element + k * component_size, component_type, normalized);
    }
  }
  return values;
}

struct AccessorData {
  std::size_t count = 0;
  int components = 0;
  std::vector<double> values;  ///< count × components
};

// Applies a sparse accessor's substitutions to `data`; `context` names the accessor in errors.
Status ApplySparse(const tinygltf::Model& model, const tinygltf::Accessor& acc,
                   const std::string& context, AccessorData& data) {
  const auto& sparse = acc.sparse;
  if (sparse.count < 0 || static_cast<std::size_t>(sparse.count) > data.count) {
    return Status::BadInput("{} has sparse count {} for {} elements", context, sparse.count,
                            data.count);
  }
  const int index_type = sparse.indices.componentType;
  if (!ComponentTypeAllowed(Semantic::kIndices, index_type, false)) {
    return Status::BadInput("{} has sparse indices of component type {}", context,
                            ComponentTypeName(index_type));
  }
  if (sparse.indices.byteOffset < 0 || sparse.values.byteOffset < 0) {
    return Status::BadInput("{} has a negative sparse byteOffset", context);
  }
  const auto count = static_cast<std::size_t>(sparse.count);
  StatusOr<std::span<const std::uint8_t>> index_bytes = ViewBytes(model, sparse.indices.bufferView);
  if (!index_bytes.ok()) return index_bytes.status().WithContext(context + " sparse indices");
  StatusOr<std::vector<double>> indices =
      ReadElements(*index_bytes, static_cast<std::size_t>(sparse.indices.byteOffset),
                   static_cast<std::size_t>(tinygltf::GetComponentSizeInBytes(index_type)), count,
                   index_type, 1, false);
  if (!indices.ok()) return indices.status().WithContext(context + " sparse indices");
  StatusOr<std::span<const std::uint8_t>> value_bytes = ViewBytes(model, sparse.values.bufferView);
  if (!value_bytes.ok()) return value_bytes.status().WithContext(context + " sparse values");
  const std::size_t element_size =
      static_cast<std::size_t>(tinygltf::GetComponentSizeInBytes(acc.componentType)) *
      data.components;
  StatusOr<std::vector<double>> values =
      ReadElements(*value_bytes, static_cast<std::size_t>(sparse.values.byteOffset), element_size,
                   count, acc.componentType, data.components, acc.normalized);
  if (!values.ok()) return values.status().WithContext(context + " sparse values");
  for (std::size_t i = 0; i < count; ++i) {
    const double target = (*indices)[i];
    if (target >= static_cast<double>(data.count)) {
      return Status::BadInput("{} has sparse index {} out of range ({} elements)", context, target,
                              data.count);
    }
    std::copy_n(values->begin() + static_cast<std::ptrdiff_t>(i * data.components), data.components,
                data.values.begin() + static_cast<std::ptrdiff_t>(target) * data.components);
  }
  return Status::Ok();
}

// Every accessor read goes through here: checks the accessor's type and component type for the
// semantic it is used as, its buffer view, stride and byte range, then converts to double.
StatusOr<AccessorData> ReadAccessor(const tinygltf::Model& model, int index, Semantic semantic) {
  const char* what = SemanticName(semantic);
  const std::string context = fmt::format("accessor {} ({})", index, what);
  if (index < 0 || static_cast<std::size_t>(index) >= model.accessors.size()) {
    return Status::BadInput("{} does not exist ({} accessors)", context, model.accessors.size());
  }
  const tinygltf::Accessor& acc = model.accessors[index];
  const std::vector<int> types = AllowedTypes(semantic);
  if (std::find(types.begin(), types.end(), acc.type) == types.end()) {
    std::string expected;
    for (int t : types) expected += (expected.empty() ? "" : " or ") + std::string(TypeName(t));
    return Status::BadInput("{} has type {}, expected {}", context, TypeName(acc.type), expected);
  }
  if (!ComponentTypeAllowed(semantic, acc.componentType, acc.normalized)) {
    return Status::BadInput("{} has component type {}{}, which glTF does not allow for {}", context,
                            acc.normalized ? "normalized " : "",
                            ComponentTypeName(acc.componentType), what);
  }
  AccessorData data;
  data.count = acc.count;
  data.components = tinygltf::GetNumComponentsInType(static_cast<std::uint32_t>(acc.type));
  if (acc.bufferView < 0) {
    // Spec: without a buffer view the elements are zeros (usually overridden by sparse values).
    if (acc.count > kMaxZeroFilledElements) {
      return Status::BadInput("{} has no buffer view but claims {} elements", context, acc.count);
    }
    data.values.assign(acc.count * data.components, 0.0);
  } else {
    StatusOr<std::span<const std::uint8_t>> bytes = ViewBytes(model, acc.bufferView);
    if (!bytes.ok()) return bytes.status().WithContext(context);
    const std::size_t element_size =
        static_cast<std::size_t>(tinygltf::GetComponentSizeInBytes(acc.componentType)) *
        data.components;
    const std::size_t view_stride = model.bufferViews[acc.bufferView].byteStride;
    StatusOr<std::vector<double>> values =
        ReadElements(*bytes, acc.byteOffset, view_stride != 0 ? view_stride : element_size,
                     acc.count, acc.componentType, data.components, acc.normalized);
    if (!values.ok()) return values.status().WithContext(context);
    data.values = std::move(values).value();
  }
  if (acc.sparse.isSparse) SVOKIT_RETURN_IF_ERROR(ApplySparse(model, acc, context, data));
  return data;
}

// ---------------------------------------------------------------------------------------------
// Primitives as indexed draco::Meshes

// Adds a float attribute with one value per point (identity mapping), as glTF vertices are.
void AddFloatAttribute(draco::Mesh& mesh, draco::GeometryAttribute::Type type,
                       const AccessorData& data) {
  draco::GeometryAttribute layout;
  layout.Init(type, nullptr, static_cast<std::uint8_t>(data.components), draco::DT_FLOAT32,
              /*normalized=*/false, static_cast<std::int64_t>(sizeof(float) * data.components), 0);
  draco::PointAttribute* att = mesh.attribute(mesh.AddAttribute(layout, true, mesh.num_points()));
  std::array<float, 4> value{};
  for (std::size_t i = 0; i < data.count; ++i) {
    for (int k = 0; k < data.components; ++k) {
      value[k] = static_cast<float>(data.values[i * data.components + k]);
    }
    att->SetAttributeValue(draco::AttributeValueIndex(static_cast<std::uint32_t>(i)), value.data());
  }
}

// Triangles of a list, strip or fan, with the strip's alternating winding undone (glTF
// spec 3.7.2.1).
std::vector<draco::Mesh::Face> Triangulate(const std::vector<std::uint32_t>& v, int mode) {
  std::vector<draco::Mesh::Face> faces;
  auto add = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
    faces.push_back({draco::PointIndex(a), draco::PointIndex(b), draco::PointIndex(c)});
  };
  const std::size_t n = v.size();
  if (mode == TINYGLTF_MODE_TRIANGLES) {
    for (std::size_t i = 0; i + 2 < n; i += 3) add(v[i], v[i + 1], v[i + 2]);
  } else if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
    for (std::size_t i = 0; i + 2 < n; ++i) {
      if (i % 2 == 0) {
        add(v[i], v[i + 1], v[i + 2]);
      } else {
        add(v[i], v[i + 2], v[i + 1]);
      }
    }
  } else if (mode == TINYGLTF_MODE_TRIANGLE_FAN) {
    for (std::size_t i = 0; i + 2 < n; ++i) add(v[i + 1], v[i + 2], v[0]);
  }
  return faces;
}

// The glTF attributes svokit imports and the Draco attribute types that carry them.
struct AttributeSlot {
  const char* name;
  Semantic semantic;
  draco::GeometryAttribute::Type draco_type;
};
constexpr std::array<AttributeSlot, 4> kAttributes = {{
    {"POSITION", Semantic::kPosition, draco::GeometryAttribute::POSITION},
    {"NORMAL", Semantic::kNormal, draco::GeometryAttribute::NORMAL},
    {"TEXCOORD_0", Semantic::kTexcoord, draco::GeometryAttribute::TEX_COORD},
    {"COLOR_0", Semantic::kColor, draco::GeometryAttribute::COLOR},
}};

// Gathers an uncompressed primitive's accessors into a draco::Mesh.
StatusOr<std::unique_ptr<draco::Mesh>> GatherPrimitive(const tinygltf::Model& model,
                                                       const tinygltf::Primitive& prim,
                                                       std::vector<std::string>& warnings) {
  if (!prim.attributes.count("POSITION")) return Status::BadInput("has no POSITION attribute");
  auto out = std::make_unique<draco::Mesh>();
  std::size_t vertex_count = 0;
  for (const AttributeSlot& slot : kAttributes) {
    const auto it = prim.attributes.find(slot.name);
    if (it == prim.attributes.end()) continue;
    StatusOr<AccessorData> data = ReadAccessor(model, it->second, slot.semantic);
    if (!data.ok()) return data.status();
    if (slot.semantic == Semantic::kPosition) {
      if (data->count > std::numeric_limits<std::uint32_t>::max()) {
        return Status::BadInput("has more than 2^32 vertices");
      }
      vertex_count = data->count;
      out->set_num_points(static_cast<std::uint32_t>(vertex_count));
    } else if (data->count != vertex_count) {
      return Status::BadInput("accessor {} ({}) has {} elements, but POSITION has {}", it->second,
                              slot.name, data->count, vertex_count);
    }
    AddFloatAttribute(*out, slot.draco_type, *data);
  }

  std::vector<std::uint32_t> corners;
  if (prim.indices >= 0) {
    StatusOr<AccessorData> indices = ReadAccessor(model, prim.indices, Semantic::kIndices);
    if (!indices.ok()) return indices.status();
    corners.reserve(indices->count);
    for (std::size_t i = 0; i < indices->count; ++i) {
      const double index = indices->values[i];
      if (index >= static_cast<double>(vertex_count)) {
        return Status::BadInput(
            "index {} (element {} of accessor {}) is out of range ({} vertices)", index, i,
            prim.indices, vertex_count);
      }
      corners.push_back(static_cast<std::uint32_t>(index));
    }
  } else {
    corners.resize(vertex_count);
    for (std::size_t i = 0; i < vertex_count; ++i) corners[i] = static_cast<std::uint32_t>(i);
  }
  if (prim.mode == TINYGLTF_MODE_TRIANGLES && corners.size() % 3 != 0) {
    warnings.push_back(fmt::format("triangle list with {} indices; the last {} ignored",
                                   corners.size(), corners.size() % 3));
  }
  const std::vector<draco::Mesh::Face> faces = Triangulate(corners, prim.mode);
  out->SetNumFaces(faces.size());
  for (std::size_t f = 0; f < faces.size(); ++f) {
    out->SetFace(draco::FaceIndex(static_cast<std::uint32_t>(f)), faces[f]);
  }
  return out;
}

// A non-negative integer member of a JSON object from an extension, or -1.
int IndexMember(const tinygltf::Value& object, const char* key) {
  if (!object.IsObject() || !object.Has(key)) return -1;
  const tinygltf::Value& v = object.Get(key);
  if (!v.IsNumber()) return -1;
  const double d = v.GetNumberAsDouble();
  if (!(d >= 0 && d <= std::numeric_limits<int>::max()) || d != std::floor(d)) return -1;
  return static_cast<int>(d);
}

// Decodes a KHR_draco_mesh_compression primitive. Its "attributes" map glTF semantics to Draco
// unique ids; only those attributes are kept, retyped to the semantic, so AppendDracoMesh finds
// them.
StatusOr<std::unique_ptr<draco::Mesh>> DecodeDracoPrimitive(const tinygltf::Model& model,
                                                            const tinygltf::Primitive& prim,
                                                            const tinygltf::Value& ext,
                                                            std::vector<std::string>& warnings) {
  const int view = IndexMember(ext, "bufferView");
  if (view < 0 || !ext.Get("attributes").IsObject()) {
    return Status::BadInput("KHR_draco_mesh_compression needs a bufferView and attributes");
  }
  const tinygltf::Value& ids = ext.Get("attributes");
  StatusOr<std::span<const std::uint8_t>> bytes = ViewBytes(model, view);
  if (!bytes.ok()) return bytes.status();
  draco::DecoderBuffer buffer;
  buffer.Init(reinterpret_cast<const char*>(bytes->data()), bytes->size());
  draco::Decoder decoder;
  draco::StatusOr<std::unique_ptr<draco::Mesh>> decoded = decoder.DecodeMeshFromBuffer(&buffer);
  if (!decoded.ok() || !decoded.value()) {
    return Status::BadInput("cannot decode its Draco data ({})",
                            OneLine(decoded.status().error_msg_string()));
  }
  const draco::Mesh& in = *decoded.value();

  auto out = std::make_unique<draco::Mesh>();
  out->set_num_points(in.num_points());
  for (const AttributeSlot& slot : kAttributes) {
    if (!ids.Has(slot.name)) {
      if (slot.semantic == Semantic::kPosition) {
        return Status::BadInput("KHR_draco_mesh_compression has no POSITION attribute");
      }
      if (prim.attributes.count(slot.name)) {
        warnings.push_back(fmt::format("{} is not in the Draco data and is ignored", slot.name));
      }
      continue;
    }
    const int id = IndexMember(ids, slot.name);
    const draco::PointAttribute* src =
        id < 0 ? nullptr : in.GetAttributeByUniqueId(static_cast<std::uint32_t>(id));
    if (!src) {
      return Status::BadInput("KHR_draco_mesh_compression maps {} to a missing Draco attribute",
                              slot.name);
    }
    auto copy = std::make_unique<draco::PointAttribute>();
    copy->CopyFrom(*src);
    copy->set_attribute_type(slot.draco_type);
    out->AddAttribute(std::move(copy));
  }
  out->SetNumFaces(in.num_faces());
  for (draco::FaceIndex f(0); f < in.num_faces(); ++f) out->SetFace(f, in.face(f));
  return out;
}

// ---------------------------------------------------------------------------------------------
// Transforms

using Mat4 = std::array<double, 16>;  // column-major, as glTF stores matrices
constexpr Mat4 kIdentity = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};

Mat4 Multiply(const Mat4& a, const Mat4& b) {
  Mat4 m{};
  for (int col = 0; col < 4; ++col) {
    for (int row = 0; row < 4; ++row) {
      for (int k = 0; k < 4; ++k) m[col * 4 + row] += a[k * 4 + row] * b[col * 4 + k];
    }
  }
  return m;
}

// The node's local matrix: `matrix`, or translation × rotation × scale.
StatusOr<Mat4> LocalMatrix(const tinygltf::Node& node, int index) {
  auto check_size = [&](const std::vector<double>& v, std::size_t n, const char* what) {
    return v.empty() || v.size() == n
               ? Status::Ok()
               : Status::BadInput("node {} has a {} with {} values, expected {}", index, what,
                                  v.size(), n);
  };
  SVOKIT_RETURN_IF_ERROR(check_size(node.matrix, 16, "matrix"));
  SVOKIT_RETURN_IF_ERROR(check_size(node.translation, 3, "translation"));
  SVOKIT_RETURN_IF_ERROR(check_size(node.rotation, 4, "rotation"));
  SVOKIT_RETURN_IF_ERROR(check_size(node.scale, 3, "scale"));
  Mat4 m = kIdentity;
  if (!node.matrix.empty()) {
    std::copy(node.matrix.begin(), node.matrix.end(), m.begin());
    return m;
  }
  double x = 0, y = 0, z = 0, w = 1;
  if (!node.rotation.empty()) {
    // Exporters write rounded unit quaternions; normalizing keeps the rotation orthonormal.
    const double len =
        std::sqrt(node.rotation[0] * node.rotation[0] + node.rotation[1] * node.rotation[1] +
                  node.rotation[2] * node.rotation[2] + node.rotation[3] * node.rotation[3]);
    if (len > 0) {
      x = node.rotation[0] / len, y = node.rotation[1] / len, z = node.rotation[2] / len;
      w = node.rotation[3] / len;
    }
  }
  const std::array<double, 9> r = {
      1 - 2 * (y * y + z * z), 2 * (x * y + z * w), 2 * (x * z - y * w), 2 * (x * y - z * w),
      1 - 2 * (x * x + z * z), 2 * (y * z + x * w), 2 * (x * z + y * w), 2 * (y * z - x * w),
      1 - 2 * (x * x + y * y)};  // column-major 3×3
  const std::array<double, 3> s =
      node.scale.empty() ? std::array<double, 3>{1, 1, 1}
                         : std::array<double, 3>{node.scale[0], node.scale[1], node.scale[2]};
  for (int col = 0; col < 3; ++col) {
    for (int row = 0; row < 3; ++row) m[col * 4 + row] = r[col * 3 + row] * s[col];
  }
  if (!node.translation.empty()) {
    m[12] = node.translation[0], m[13] = node.translation[1], m[14] = node.translation[2];
  }
  return m;
}

// Moves what AppendDracoMesh just added (vertices from `first_vertex`, triangles from
// `first_triangle`) into world space: positions by `m`, normals by its cofactor matrix (the inverse
// transpose up to a positive factor once the determinant's sign is applied), and mirrored
// transforms flip the winding so triangles keep facing outward.
void TransformAppended(Mesh& mesh, std::size_t first_vertex, std::size_t first_triangle,
                       const Mat4& m) {
  const Vec3d c0{m[0], m[1], m[2]}, c1{m[4], m[5], m[6]}, c2{m[8], m[9], m[10]};
  const Vec3d t{m[12], m[13], m[14]};
  for (std::size_t i = first_vertex; i < mesh.positions.size(); ++i) {
    const Vec3d p = mesh.positions[i];
    mesh.positions[i] = c0 * p.x + c1 * p.y + c2 * p.z + t;
  }
  const double det = Dot(c0, Cross(c1, c2));
  const double sign = det < 0 ? -1.0 : 1.0;
  const Vec3d n0 = Cross(c1, c2) * sign, n1 = Cross(c2, c0) * sign, n2 = Cross(c0, c1) * sign;
  for (std::size_t c = 3 * first_triangle; c < mesh.normals.size(); ++c) {
    const Vec3f& n = mesh.normals[c];
    const Vec3d v = n0 * n.x + n1 * n.y + n2 * n.z;
    const double len = Length(v);
    const Vec3d unit = len > 0 ? v / len : Vec3d{};
    mesh.normals[c] = {static_cast<float>(unit.x), static_cast<float>(unit.y),
                       static_cast<float>(unit.z)};
  }
  if (det >= 0) return;
  for (std::size_t tri = first_triangle; tri < mesh.triangles.size(); ++tri) {
    std::swap(mesh.triangles[tri][1], mesh.triangles[tri][2]);
    if (mesh.has_normals()) std::swap(mesh.normals[3 * tri + 1], mesh.normals[3 * tri + 2]);
    if (mesh.has_uvs()) std::swap(mesh.uvs[3 * tri + 1], mesh.uvs[3 * tri + 2]);
    if (mesh.has_colors()) std::swap(mesh.colors[3 * tri + 1], mesh.colors[3 * tri + 2]);
  }
}

// ---------------------------------------------------------------------------------------------
// Materials and textures

// A file extension for embedded image bytes: OIIO picks its decoder by the texture's name.
std::string ImageExtension(const std::string& mime, std::span<const std::uint8_t> bytes) {
  if (mime == "image/png") return ".png";
  if (mime == "image/jpeg") return ".jpg";
  if (mime == "image/webp") return ".webp";
  if (mime == "image/bmp") return ".bmp";
  if (mime == "image/gif") return ".gif";
  if (bytes.size() >= 4 && std::memcmp(bytes.data(), "\x89PNG", 4) == 0) return ".png";
  if (bytes.size() >= 2 && bytes[0] == 0xFF && bytes[1] == 0xD8) return ".jpg";
  return "";
}

// ---------------------------------------------------------------------------------------------
// The scene

// A 2-D affine map of texture coordinates, row-major [a b c; d e f]: u' = a·u + b·v + c.
struct UvTransform {
  std::array<double, 6> m = {1, 0, 0, 0, 1, 0};
};

class GltfImporter {
 public:
  GltfImporter(const tinygltf::Model& model, const SideFileRule& rule, Mesh& mesh)
      : model_(model), rule_(rule), mesh_(mesh), material_slots_(model.materials.size()) {}

  Status Run() {
    SVOKIT_RETURN_IF_ERROR(CheckRequiredExtensions());
    StatusOr<std::vector<std::size_t>> order = NodeOrder();
    if (!order.ok()) return order.status();
    StatusOr<std::vector<int>> roots = RootNodes();
    if (!roots.ok()) return roots.status();
    SVOKIT_RETURN_IF_ERROR(CheckInstancing(*roots, *order));
    for (int root : *roots) SVOKIT_RETURN_IF_ERROR(AppendNodeTree(root));
    return Status::Ok();
  }

 private:
  Status CheckRequiredExtensions() {
    for (const std::string& ext : model_.extensionsRequired) {
      if (ext == "KHR_draco_mesh_compression" || ext == "KHR_mesh_quantization" ||
          ext == "KHR_texture_transform") {
        continue;
      }
      // Extensions that only change appearance cannot make the geometry wrong.
      bool appearance = false;
      for (const char* prefix :
           {"KHR_materials_", "KHR_texture_", "EXT_texture_", "KHR_technique_", "KHR_lights_"}) {
        appearance = appearance || ext.starts_with(prefix);
      }
      if (!appearance) return Status::BadInput("requires the unsupported extension {}", ext);
      mesh_.warnings.push_back(
          fmt::format("required extension {} is not supported; appearance may differ", ext));
    }
    return Status::Ok();
  }

  // All nodes, every parent before its children (reverse post-order of an iterative depth-first
  // search, so a deep hierarchy cannot overflow the stack). A child still on the search path is its
  // own ancestor.
  StatusOr<std::vector<std::size_t>> NodeOrder() const {
    const std::size_t n = model_.nodes.size();
    enum : std::uint8_t { kNew, kOnPath, kDone };
    std::vector<std::uint8_t> state(n, kNew);
    std::vector<std::size_t> post_order;
    for (std::size_t start = 0; start < n; ++start) {
      if (state[start] != kNew) continue;
      std::vector<std::pair<std::size_t, std::size_t>> path = {{start, 0}};  // node, next child
      state[start] = kOnPath;
      while (!path.empty()) {
        auto& [node, next] = path.back();
        const std::vector<int>& children = model_.nodes[node].children;
        if (next == children.size()) {
          state[node] = kDone;
          post_order.push_back(node);
          path.pop_back();
          continue;
        }
        const int child = children[next++];
        if (child < 0 || static_cast<std::size_t>(child) >= n) {
          return Status::BadInput("node {} has child {}, but there are only {} nodes", node, child,
                                  n);
        }
        if (state[child] == kOnPath) {
          return Status::BadInput("node {} is its own ancestor (cyclic node hierarchy)", child);
        }
        if (state[child] == kNew) {
          state[child] = kOnPath;
          path.emplace_back(child, 0);
        }
      }
    }
    for (std::size_t i = 0; i < n; ++i) {
      const int m = model_.nodes[i].mesh;
      if (m < -1 || m >= static_cast<int>(model_.meshes.size())) {
        return Status::BadInput("node {} refers to mesh {}, but there are only {} meshes", i, m,
                                model_.meshes.size());
      }
    }
    return std::vector<std::size_t>(post_order.rbegin(), post_order.rend());
  }

  // Counts the instances of every node (its paths from the roots) before anything is emitted, so
  // an exponentially instancing graph fails at once instead of after filling memory.
  Status CheckInstancing(const std::vector<int>& roots, const std::vector<std::size_t>& order) {
    std::vector<double> instances(model_.nodes.size(), 0.0);  // doubles: counts can be huge
    std::vector<double> mesh_instances(model_.meshes.size(), 0.0);
    for (int root : roots) instances[root] += 1;
    double total = 0;
    for (std::size_t node : order) {
      total += instances[node];
      for (int child : model_.nodes[node].children) instances[child] += instances[node];
      if (model_.nodes[node].mesh >= 0) mesh_instances[model_.nodes[node].mesh] += instances[node];
    }
    if (total > static_cast<double>(kMaxNodeInstances)) {
      return Status::BadInput("the node hierarchy expands to {:.3g} node instances (limit {})",
                              total, kMaxNodeInstances);
    }
    double repeated = 0;  // triangles emitted by second and later instances
    for (std::size_t m = 0; m < model_.meshes.size(); ++m) {
      if (mesh_instances[m] <= 1) continue;
      for (std::size_t p = 0; p < model_.meshes[m].primitives.size(); ++p) {
        StatusOr<const draco::Mesh*> prim = Primitive(static_cast<int>(m), static_cast<int>(p));
        if (!prim.ok()) {
          return prim.status().WithContext(fmt::format("mesh {} primitive {}", m, p));
        }
        if (*prim) repeated += (mesh_instances[m] - 1) * (*prim)->num_faces();
      }
    }
    if (repeated > static_cast<double>(kMaxInstancedTriangles)) {
      return Status::BadInput("node instancing repeats {:.3g} triangles (limit {})", repeated,
                              kMaxInstancedTriangles);
    }
    return Status::Ok();
  }

  // The default scene's nodes, else scene 0's, else every node that is nobody's child.
  StatusOr<std::vector<int>> RootNodes() const {
    const int scenes = static_cast<int>(model_.scenes.size());
    if (model_.defaultScene < -1 || model_.defaultScene >= scenes) {
      return Status::BadInput("the default scene {} does not exist ({} scenes)",
                              model_.defaultScene, scenes);
    }
    const int n = static_cast<int>(model_.nodes.size());
    if (scenes > 0) {
      const int scene = std::max(model_.defaultScene, 0);
      for (int node : model_.scenes[scene].nodes) {
        if (node < 0 || node >= n) {
          return Status::BadInput("scene {} refers to node {}, but there are only {} nodes", scene,
                                  node, n);
        }
      }
      return model_.scenes[scene].nodes;
    }
    std::vector<bool> is_child(n, false);
    for (const tinygltf::Node& node : model_.nodes) {
      for (int child : node.children) is_child[child] = true;  // ranges checked by CheckNodeGraph
    }
    std::vector<int> roots;
    for (int i = 0; i < n; ++i) {
      if (!is_child[i]) roots.push_back(i);
    }
    return roots;
  }

  // Appends every mesh instance below `root`; iterative, like NodeOrder.
  Status AppendNodeTree(int root) {
    std::vector<std::pair<int, Mat4>> pending = {{root, kIdentity}};  // node, parent's world
    while (!pending.empty()) {
      const auto [index, parent] = pending.back();
      pending.pop_back();
      const tinygltf::Node& node = model_.nodes[index];
      StatusOr<Mat4> local = LocalMatrix(node, index);
      if (!local.ok()) return local.status();
      const Mat4 world = Multiply(parent, *local);
      if (node.mesh >= 0) SVOKIT_RETURN_IF_ERROR(AppendMesh(node.mesh, world));
      // Reversed so children are emitted in file order.
      for (auto it = node.children.rbegin(); it != node.children.rend(); ++it) {
        pending.emplace_back(*it, world);
      }
    }
    return Status::Ok();
  }

  Status AppendMesh(int mesh_index, const Mat4& world) {
    const tinygltf::Mesh& gltf_mesh = model_.meshes[mesh_index];
    for (std::size_t p = 0; p < gltf_mesh.primitives.size(); ++p) {
      const std::string context = fmt::format("mesh {} primitive {}", mesh_index, p);
      StatusOr<const draco::Mesh*> prim = Primitive(mesh_index, static_cast<int>(p));
      if (!prim.ok()) return prim.status().WithContext(context);
      if (*prim == nullptr) continue;  // points or lines
      StatusOr<std::uint32_t> material = MaterialSlot(gltf_mesh.primitives[p].material);
      if (!material.ok()) return material.status().WithContext(context);
      const std::size_t first_vertex = mesh_.positions.size();
      const std::size_t first_triangle = mesh_.triangles.size();
      SVOKIT_RETURN_IF_ERROR(
          AppendDracoMesh(**prim, *material, /*flip_v=*/true, mesh_).WithContext(context));
      if (const auto t = uv_transforms_.find(*material);
          t != uv_transforms_.end() && mesh_.has_uvs()) {
        // The transform maps glTF's coordinates (v down); svokit's v was flipped on append.
        for (std::size_t c = 3 * first_triangle; c < mesh_.uvs.size(); ++c) {
          Vec2f& uv = mesh_.uvs[c];
          const std::array<double, 6>& m = t->second.m;
          const double u = uv.u, v = 1.0 - double{uv.v};
          uv = {static_cast<float>(m[0] * u + m[1] * v + m[2]),
                static_cast<float>(1.0 - (m[3] * u + m[4] * v + m[5]))};
        }
      }
      TransformAppended(mesh_, first_vertex, first_triangle, world);
    }
    return Status::Ok();
  }

  // The primitive as an indexed draco::Mesh, built once however often its mesh is instanced;
  // nullptr for point and line primitives, which are skipped.
  StatusOr<const draco::Mesh*> Primitive(int mesh_index, int prim_index) {
    const auto [it, inserted] = primitives_.try_emplace({mesh_index, prim_index});
    if (!inserted) return it->second.get();
    const tinygltf::Primitive& prim = model_.meshes[mesh_index].primitives[prim_index];
    switch (prim.mode) {
      case TINYGLTF_MODE_TRIANGLES:
      case TINYGLTF_MODE_TRIANGLE_STRIP:
      case TINYGLTF_MODE_TRIANGLE_FAN:
        break;
      case TINYGLTF_MODE_POINTS:
      case TINYGLTF_MODE_LINE:
      case TINYGLTF_MODE_LINE_LOOP:
      case TINYGLTF_MODE_LINE_STRIP:
        mesh_.warnings.push_back(fmt::format(
            "mesh {} primitive {}: {} skipped (only triangles are imported)", mesh_index,
            prim_index, prim.mode == TINYGLTF_MODE_POINTS ? "points" : "lines"));
        return nullptr;
      default:
        return Status::BadInput("has invalid mode {}", prim.mode);
    }
    std::vector<std::string> warnings;
    const auto draco_ext = prim.extensions.find("KHR_draco_mesh_compression");
    StatusOr<std::unique_ptr<draco::Mesh>> built =
        draco_ext != prim.extensions.end()
            ? DecodeDracoPrimitive(model_, prim, draco_ext->second, warnings)
            : GatherPrimitive(model_, prim, warnings);
    for (const std::string& w : warnings) {
      mesh_.warnings.push_back(fmt::format("mesh {} primitive {}: {}", mesh_index, prim_index, w));
    }
    if (!built.ok()) return built.status();
    it->second = std::move(built).value();
    return it->second.get();
  }

  // Svokit material index for glTF material `index` (-1: the shared white "default"), converted
  // on first use.
  StatusOr<std::uint32_t> MaterialSlot(int index) {
    if (index < -1 || index >= static_cast<int>(model_.materials.size())) {
      return Status::BadInput("refers to material {}, but there are only {} materials", index,
                              model_.materials.size());
    }
    std::optional<std::uint32_t>& slot = index < 0 ? default_material_ : material_slots_[index];
    if (!slot) {
      Material material;
      material.name = "default";
      if (index >= 0) material = ConvertMaterial(index);
      slot = static_cast<std::uint32_t>(mesh_.materials.size());
      if (index >= 0 && material.texture >= 0) {
        const tinygltf::TextureInfo& info =
            model_.materials[index].pbrMetallicRoughness.baseColorTexture;
        if (auto t = TextureTransform(info, material.name)) uv_transforms_[*slot] = *t;
      }
      mesh_.materials.push_back(std::move(material));
    }
    return *slot;
  }

  Material ConvertMaterial(int index) {
    const tinygltf::Material& m = model_.materials[index];
    Material material;
    material.name = m.name.empty() ? fmt::format("material_{}", index) : m.name;
    const std::vector<double>& factor = m.pbrMetallicRoughness.baseColorFactor;
    if (factor.size() == 4) {
      material.base_color = {static_cast<float>(factor[0]), static_cast<float>(factor[1]),
                             static_cast<float>(factor[2]), static_cast<float>(factor[3])};
    } else {
      mesh_.warnings.push_back(
          fmt::format("material '{}': baseColorFactor has {} values, expected 4; using white",
                      material.name, factor.size()));
    }
    if (m.alphaMode == "MASK") {
      material.alpha_mode = AlphaMode::kMask;
      material.alpha_cutoff = static_cast<float>(m.alphaCutoff);
    } else if (m.alphaMode == "BLEND") {
      material.alpha_mode = AlphaMode::kBlend;
    } else if (m.alphaMode != "OPAQUE") {
      mesh_.warnings.push_back(
          fmt::format("material '{}': alphaMode '{}' is not one of OPAQUE, "
                      "MASK, BLEND; the material is opaque",
                      material.name, m.alphaMode));
    }
    AttachBaseColorTexture(m.pbrMetallicRoughness.baseColorTexture, material);
    return material;
  }

  // KHR_texture_transform's map of the base colour texture's coordinates (glTF's, v down):
  // offset · rotation · scale, as the extension defines it; nullopt for the identity.
  std::optional<UvTransform> TextureTransform(const tinygltf::TextureInfo& info,
                                              const std::string& material) {
    const auto ext = info.extensions.find("KHR_texture_transform");
    if (ext == info.extensions.end()) return std::nullopt;
    const tinygltf::Value& v = ext->second;
    auto numbers = [&](const char* key, std::initializer_list<double> fallback) {
      std::vector<double> out(fallback);
      if (!v.Has(key)) return out;
      const tinygltf::Value& x = v.Get(key);
      if (x.IsNumber() && out.size() == 1) {
        out[0] = x.GetNumberAsDouble();
      } else if (x.IsArray() && x.ArrayLen() == out.size()) {
        for (std::size_t i = 0; i < out.size(); ++i) {
          const tinygltf::Value& e = x.Get(static_cast<int>(i));
          if (e.IsNumber()) out[i] = e.GetNumberAsDouble();
        }
      }
      for (double& d : out) {
        if (!std::isfinite(d)) {
          mesh_.warnings.push_back(fmt::format(
              "material '{}': KHR_texture_transform {} is not finite; ignored", material, key));
          out = fallback;
          break;
        }
      }
      return out;
    };
    if (v.Has("texCoord") && v.Get("texCoord").IsNumber() &&
        v.Get("texCoord").GetNumberAsDouble() != 0) {
      mesh_.warnings.push_back(fmt::format(
          "material '{}': KHR_texture_transform's texCoord is not 0, only TEXCOORD_0 is imported",
          material));
    }
    const std::vector<double> offset = numbers("offset", {0, 0});
    const double rotation = numbers("rotation", {0})[0];
    const std::vector<double> scale = numbers("scale", {1, 1});
    const double c = std::cos(rotation), s = std::sin(rotation);
    UvTransform t;
    t.m = {c * scale[0], s * scale[1], offset[0], -s * scale[0], c * scale[1], offset[1]};
    if (t.m == UvTransform{}.m) return std::nullopt;
    return t;
  }

  // Points `material` at the texture's image: embedded images (buffer view or data URI) become
  // textures here, once per image; external files go through AttachTextureFile. Anything unusable
  // leaves the material on its base colour with a warning.
  void AttachBaseColorTexture(const tinygltf::TextureInfo& info, Material& material) {
    if (info.index < 0) return;
    auto warn = [&](const std::string& what) {
      mesh_.warnings.push_back(
          fmt::format("material '{}': {}; using the base colour", material.name, what));
    };
    if (info.texCoord != 0) {
      return warn(fmt::format("base colour texture uses TEXCOORD_{}, only TEXCOORD_0 is imported",
                              info.texCoord));
    }
    if (static_cast<std::size_t>(info.index) >= model_.textures.size()) {
      return warn(fmt::format("texture {} does not exist", info.index));
    }
    const int source = model_.textures[info.index].source;
    if (source < 0 || static_cast<std::size_t>(source) >= model_.images.size()) {
      return warn(fmt::format("texture {} has no image svokit can read", info.index));
    }
    if (const auto it = image_textures_.find(source); it != image_textures_.end()) {
      material.texture = it->second;
      return;
    }
    const tinygltf::Image& image = model_.images[source];
    if (!image.uri.empty()) {
      AttachTextureFile(rule_, rule_.model_folder(), image.uri, SideFileSyntax::kUri, material,
                        mesh_);
    } else {
      std::span<const std::uint8_t> bytes(image.image);
      if (image.bufferView >= 0) {
        StatusOr<std::span<const std::uint8_t>> view = ViewBytes(model_, image.bufferView);
        if (!view.ok()) return warn(fmt::format("image {}: {}", source, view.status().message()));
        bytes = *view;
      }
      if (bytes.empty()) return warn(fmt::format("image {} is empty", source));
      std::string name = image.name.empty() ? fmt::format("image_{}", source) : image.name;
      const std::string ext = ImageExtension(image.mimeType, bytes);
      if (!name.ends_with(ext)) name += ext;
      // Bytes that are not an image svokit reads are never stored.
      if (StatusOr<ImageHeader> header = ReadImageHeader(name, bytes); !header.ok()) {
        return warn(header.status().message());
      }
      mesh_.textures.emplace_back(std::move(name),
                                  std::vector<std::uint8_t>(bytes.begin(), bytes.end()),
                                  /*srgb=*/true);
      material.texture = static_cast<std::int32_t>(mesh_.textures.size() - 1);
    }
    if (material.texture >= 0) image_textures_[source] = material.texture;
  }

  const tinygltf::Model& model_;
  const SideFileRule& rule_;
  Mesh& mesh_;
  std::map<std::pair<int, int>, std::unique_ptr<draco::Mesh>> primitives_;
  std::vector<std::optional<std::uint32_t>> material_slots_;  // per glTF material, once converted
  std::optional<std::uint32_t> default_material_;
  std::map<std::uint32_t, UvTransform> uv_transforms_;  // svokit material → its texture transform
  std::map<int, std::int32_t> image_textures_;          // glTF image → index into mesh_.textures
};

}  // namespace

StatusOr<Mesh> ImportGltf(const std::filesystem::path& path, const ImportOptions& options) {
  const std::string name = path.string();
  StatusOr<std::vector<std::uint8_t>> bytes = ReadFileBytes(path);
  if (!bytes.ok()) return bytes.status();
  // Third-party parsing of hostile input: anything thrown becomes an error about this file.
  try {
    Mesh mesh;
    const bool binary = LowerExtension(path) == "glb" || IsBinaryGltf(*bytes);
    const SideFileRule rule(path, options);
    StatusOr<tinygltf::Model> model = LoadModel(std::move(bytes).value(), binary, rule, mesh);
    if (!model.ok()) return model.status().WithContext(name);
    SVOKIT_RETURN_IF_ERROR(GltfImporter(*model, rule, mesh).Run().WithContext(name));
    return mesh;
  } catch (const std::bad_alloc&) {
    return Status::OutOfMemory("{}: out of memory while importing", name);
  } catch (const std::exception& e) {
    return Status::BadInput("{}: {}", name, OneLine(e.what()));
  }
}

}  // namespace svokit::detail
