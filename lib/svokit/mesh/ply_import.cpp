// Stanford PLY: ASCII and binary (both byte orders). The header declares elements and their typed
// properties; every element is read in file order and every property (lists included) is consumed
// exactly, so unknown content can never desynchronise the reader. Faces are collected first and
// triangulated once all vertices are known, because elements may come in any order.

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <optional>
#include <unordered_set>

#include "svokit/mesh/importers.hpp"
#include "svokit/mesh/mesh_builder.hpp"
#include "svokit/mesh/text_scanner.hpp"

namespace svokit::detail {

namespace {

enum class PlyType : std::uint8_t {
  kInt8,
  kUint8,
  kInt16,
  kUint16,
  kInt32,
  kUint32,
  kFloat32,
  kFloat64
};

struct PlyTypeName {
  std::string_view name;
  PlyType type;
};
constexpr PlyTypeName kPlyTypeNames[] = {
    {"char", PlyType::kInt8},      {"int8", PlyType::kInt8},       {"uchar", PlyType::kUint8},
    {"uint8", PlyType::kUint8},    {"short", PlyType::kInt16},     {"int16", PlyType::kInt16},
    {"ushort", PlyType::kUint16},  {"uint16", PlyType::kUint16},   {"int", PlyType::kInt32},
    {"int32", PlyType::kInt32},    {"uint", PlyType::kUint32},     {"uint32", PlyType::kUint32},
    {"float", PlyType::kFloat32},  {"float32", PlyType::kFloat32}, {"double", PlyType::kFloat64},
    {"float64", PlyType::kFloat64}};

std::optional<PlyType> ParsePlyType(std::string_view name) {
  for (const PlyTypeName& t : kPlyTypeNames) {
    if (t.name == name) return t.type;
  }
  return std::nullopt;
}

std::string_view TypeName(PlyType type) {
  for (const PlyTypeName& t : kPlyTypeNames) {
    if (t.type == type) return t.name;
  }
  return "?";
}

constexpr std::size_t SizeOf(PlyType type) {
  switch (type) {
    case PlyType::kInt8:
    case PlyType::kUint8:
      return 1;
    case PlyType::kInt16:
    case PlyType::kUint16:
      return 2;
    case PlyType::kInt32:
    case PlyType::kUint32:
    case PlyType::kFloat32:
      return 4;
    case PlyType::kFloat64:
      return 8;
  }
  return 8;
}

constexpr bool IsInteger(PlyType type) {
  return type < PlyType::kFloat32;
}

bool FitsType(PlyType type, std::int64_t v) {
  switch (type) {
    case PlyType::kInt8:
      return v >= INT8_MIN && v <= INT8_MAX;
    case PlyType::kUint8:
      return v >= 0 && v <= UINT8_MAX;
    case PlyType::kInt16:
      return v >= INT16_MIN && v <= INT16_MAX;
    case PlyType::kUint16:
      return v >= 0 && v <= UINT16_MAX;
    case PlyType::kInt32:
      return v >= INT32_MIN && v <= INT32_MAX;
    case PlyType::kUint32:
      return v >= 0 && v <= UINT32_MAX;
    default:
      return true;
  }
}

// Integer colour channels are fractions of the type's range; 32-bit integer colours are in practice
// 0..255 values written with a wide type, so they are scaled like 8-bit ones.
double ColorScale(PlyType type) {
  switch (type) {
    case PlyType::kInt16:
    case PlyType::kUint16:
      return 1.0 / 65535.0;
    case PlyType::kFloat32:
    case PlyType::kFloat64:
      return 1.0;
    default:
      return 1.0 / 255.0;
  }
}

// What a property means to svokit; everything else is read and dropped.
enum Role : std::uint8_t {
  kIgnore,
  kX,
  kY,
  kZ,
  kNx,
  kNy,
  kNz,
  kU,
  kV,
  kRed,
  kGreen,
  kBlue,
  kAlpha,
  kIndices,
  kTexcoord,
  kTexnumber,
  kRoleCount
};

Role ColorRole(std::string_view n) {
  if (n.starts_with("diffuse_")) n.remove_prefix(8);  // e.g. Point Cloud Library exports
  if (n == "red") return kRed;
  if (n == "green") return kGreen;
  if (n == "blue") return kBlue;
  if (n == "alpha") return kAlpha;
  return kIgnore;
}

Role VertexRole(std::string_view n) {
  if (n == "x") return kX;
  if (n == "y") return kY;
  if (n == "z") return kZ;
  if (n == "nx") return kNx;
  if (n == "ny") return kNy;
  if (n == "nz") return kNz;
  if (n == "u" || n == "s" || n == "texture_u" || n == "texture_s") return kU;
  if (n == "v" || n == "t" || n == "texture_v" || n == "texture_t") return kV;
  return ColorRole(n);
}

Role FaceRole(std::string_view n) {
  if (n == "vertex_indices" || n == "vertex_index") return kIndices;
  if (n == "texcoord") return kTexcoord;    // MeshLab: u v per corner
  if (n == "texnumber") return kTexnumber;  // MeshLab: index of the face's TextureFile
  return ColorRole(n);
}

// Stanford scans (e.g. Igea) store triangle strips instead of faces.
Role StripRole(std::string_view n) {
  return n == "vertex_indices" || n == "vertex_index" ? kIndices : kIgnore;
}

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::kFloat32;  // the item type for lists
  PlyType count_type = PlyType::kUint8;
  bool is_list = false;
  Role role = kIgnore;
  std::size_t line = 0;
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::vector<PlyProperty> properties;
  std::unordered_set<std::string> property_names;  // a header may declare very many properties
  std::array<bool, kRoleCount> has{};              // which roles a property fills
  std::array<double, kRoleCount> scale{};          // colour channel scale per role
  std::size_t line = 0;

  bool Has(std::initializer_list<Role> roles) const {
    return std::all_of(roles.begin(), roles.end(), [&](Role r) { return has[r]; });
  }
};

// Where a reader is, for error messages.
struct PlyCursor {
  const PlyElement& element;
  std::uint64_t index;
  const PlyProperty* property;  // null between properties
};

std::uint8_t ByteSwap(std::uint8_t v) {
  return v;
}
std::uint16_t ByteSwap(std::uint16_t v) {
  return __builtin_bswap16(v);
}
std::uint32_t ByteSwap(std::uint32_t v) {
  return __builtin_bswap32(v);
}
std::uint64_t ByteSwap(std::uint64_t v) {
  return __builtin_bswap64(v);
}

// Binary element data. Reads return false at the end of the data; every one is bounds-checked.
class BinaryReader {
 public:
  BinaryReader(std::span<const std::uint8_t> data, bool big_endian, std::string path)
      : data_(data), big_endian_(big_endian), path_(std::move(path)) {}

  bool BeginInstance() { return true; }
  bool EndInstance() { return true; }
  bool Integer(PlyType type, std::int64_t& v) {
    if (remaining() < SizeOf(type)) return false;
    switch (type) {
      case PlyType::kInt8:
        v = Load<std::int8_t, std::uint8_t>();
        break;
      case PlyType::kUint8:
        v = Load<std::uint8_t, std::uint8_t>();
        break;
      case PlyType::kInt16:
        v = Load<std::int16_t, std::uint16_t>();
        break;
      case PlyType::kUint16:
        v = Load<std::uint16_t, std::uint16_t>();
        break;
      case PlyType::kInt32:
        v = Load<std::int32_t, std::uint32_t>();
        break;
      case PlyType::kUint32:
        v = Load<std::uint32_t, std::uint32_t>();
        break;
      default:
        return false;  // callers only ask for integers of integer-typed properties
    }
    return true;
  }
  bool Real(PlyType type, double& v) {
    if (IsInteger(type)) {
      std::int64_t i = 0;
      if (!Integer(type, i)) return false;
      v = static_cast<double>(i);
      return true;
    }
    if (remaining() < SizeOf(type)) return false;
    v = type == PlyType::kFloat32 ? Load<float, std::uint32_t>() : Load<double, std::uint64_t>();
    return true;
  }
  /// Whether `n` items of `type` remain, so a list length read from the file is safe to loop over.
  bool CanHold(PlyType type, std::uint64_t n) const { return n <= remaining() / SizeOf(type); }
  bool Skip(PlyType type, std::uint64_t n) {
    if (!CanHold(type, n)) return false;
    pos_ += n * SizeOf(type);
    return true;
  }
  std::size_t remaining() const { return data_.size() - pos_; }

  template <class... Args>
  Status Error(fmt::format_string<Args...> f, Args&&... args) const {
    return Status::BadInput("{}: {}", path_, fmt::format(f, std::forward<Args>(args)...));
  }
  Status Failure(const PlyCursor& at) const {
    if (at.property) {
      return Error("truncated: element '{}' {} of {} (property '{}')", at.element.name, at.index,
                   at.element.count, at.property->name);
    }
    return Error("truncated: element '{}' {} of {}", at.element.name, at.index, at.element.count);
  }

 private:
  template <class T, class Bits>
  T Load() {
    Bits bits;
    std::memcpy(&bits, data_.data() + pos_, sizeof bits);
    pos_ += sizeof bits;
    if (big_endian_) bits = ByteSwap(bits);
    return std::bit_cast<T>(bits);
  }

  std::span<const std::uint8_t> data_;
  std::size_t pos_ = 0;
  bool big_endian_;
  std::string path_;
};

// ASCII element data: one element per line, values separated by white space. A failed read records
// why, and Failure() turns that into the message.
class AsciiReader {
 public:
  explicit AsciiReader(TextScanner& scan) : scan_(scan) {}

  bool BeginInstance() {
    while (scan_.NextLine()) {
      if (!scan_.AtLineEnd()) return true;
    }
    return Fail(kEnd, {});
  }
  bool EndInstance() { return scan_.AtLineEnd() || Fail(kExtra, scan_.PeekToken()); }
  bool Integer(PlyType type, std::int64_t& v) {
    const std::string_view tok = scan_.Token();
    if (tok.empty()) return Fail(kMissing, tok);
    if (!TextScanner::ParseNumber(tok, v)) return Fail(kMalformed, tok);
    if (!FitsType(type, v)) return Fail(kRange, tok);
    return true;
  }
  bool Real(PlyType type, double& v) {
    if (IsInteger(type)) {
      std::int64_t i = 0;
      if (!Integer(type, i)) return false;
      v = static_cast<double>(i);
      return true;
    }
    const std::string_view tok = scan_.Token();
    if (tok.empty()) return Fail(kMissing, tok);
    if (!TextScanner::ParseNumber(tok, v)) return Fail(kMalformed, tok);
    return true;
  }
  // A list longer than its line fails at the first missing value, so the loop is bounded.
  bool CanHold(PlyType, std::uint64_t) const { return true; }
  bool Skip(PlyType type, std::uint64_t n) {
    double ignored = 0;
    for (std::uint64_t k = 0; k < n; ++k) {
      if (!Real(type, ignored)) return false;
    }
    return true;
  }
  std::size_t remaining() const { return 0; }

  template <class... Args>
  Status Error(fmt::format_string<Args...> f, Args&&... args) const {
    return scan_.Error(f, std::forward<Args>(args)...);
  }
  Status Failure(const PlyCursor& at) const {
    const std::string where =
        fmt::format("element '{}' {} of {}", at.element.name, at.index, at.element.count);
    const std::string prop = at.property ? at.property->name : std::string("?");
    const std::string_view type = at.property ? TypeName(at.property->type) : std::string_view("?");
    switch (failure_) {
      case kEnd:
        return Error("truncated: {} is missing (the file ends)", where);
      case kMissing:
        return Error("{}: the line ends before property '{}'", where, prop);
      case kMalformed:
        return Error("{}: property '{}' ({}): expected a number, found '{}'", where, prop, type,
                     TextScanner::Clip(token_));
      case kRange:
        return Error("{}: property '{}': {} does not fit its type {}", where, prop,
                     TextScanner::Clip(token_), type);
      case kExtra:
        return Error("{}: unexpected value '{}' after the last property", where,
                     TextScanner::Clip(token_));
    }
    return Error("{}: malformed", where);
  }

 private:
  enum FailureKind { kEnd, kMissing, kMalformed, kRange, kExtra };
  bool Fail(FailureKind kind, std::string_view token) {
    failure_ = kind;
    token_ = token;
    return false;
  }

  TextScanner& scan_;
  FailureKind failure_ = kEnd;
  std::string_view token_;
};

// Faces as read, before triangulation (vertices may come after faces in the file).
struct FaceSoup {
  std::vector<std::uint32_t> corners;    // all faces' vertex indices, concatenated
  std::vector<std::size_t> ends;         // end of face f in `corners`
  std::vector<Vec2f> corner_uvs;         // parallel to `corners` when faces carry texcoords
  std::vector<Rgba> colors;              // one per face when faces carry colours
  std::vector<std::uint32_t> materials;  // one per face when texnumber selects a TextureFile
};

// Triangle strips as read: vertex indices of all strips, kRestart where a strip restarts.
struct StripSoup {
  static constexpr std::uint32_t kRestart = UINT32_MAX;
  std::vector<std::uint32_t> indices;
  std::vector<std::size_t> ends;  // end of strip element s in `indices`
};

enum class PlyFormat { kAscii, kBinaryLittleEndian, kBinaryBigEndian };

class PlyImporter {
 public:
  PlyImporter(const std::filesystem::path& path, std::span<const std::uint8_t> bytes,
              const ImportOptions& options)
      : rule_(path, options), name_(path.string()), bytes_(bytes), scan_(AsText(bytes), name_) {}

  StatusOr<Mesh> Import() {
    SVOKIT_RETURN_IF_ERROR(ParseHeader());
    SVOKIT_RETURN_IF_ERROR(AssignRoles());
    SVOKIT_RETURN_IF_ERROR(CheckSizes());
    if (format_ == PlyFormat::kAscii) {
      AsciiReader in(scan_);
      SVOKIT_RETURN_IF_ERROR(ReadBody(in));
      std::size_t trailing = 0;
      while (scan_.NextLine()) trailing += !scan_.AtLineEnd();
      if (trailing > 0) {
        mesh_.warnings.push_back(fmt::format("{} lines after the last element ignored", trailing));
      }
    } else {
      BinaryReader in(bytes_.subspan(data_offset_), format_ == PlyFormat::kBinaryBigEndian, name_);
      SVOKIT_RETURN_IF_ERROR(ReadBody(in));
      if (in.remaining() > 0) {
        mesh_.warnings.push_back(
            fmt::format("{} bytes after the last element ignored", in.remaining()));
      }
    }
    SVOKIT_RETURN_IF_ERROR(BuildTriangles());
    return std::move(mesh_);
  }

 private:
  Status ParseHeader() {
    if (!scan_.NextLine() || scan_.Token() != "ply" || !scan_.AtLineEnd()) {
      return scan_.Error("not a PLY file (the first line must be 'ply')");
    }
    bool have_format = false;
    while (scan_.NextLine()) {
      const char* line_start = scan_.line().data();
      const std::string_view key = scan_.Token();
      if (key.empty() || key == "obj_info") continue;
      if (key == "comment") {
        // MeshLab names its texture images in comments.
        if (scan_.Token() == "TextureFile") {
          const std::string_view file = scan_.Rest();
          if (!file.empty()) texture_files_.emplace_back(file);
        }
      } else if (key == "format") {
        if (have_format) return scan_.Error("second 'format' line");
        SVOKIT_RETURN_IF_ERROR(ParseFormat());
        have_format = true;
      } else if (key == "element") {
        if (!have_format) return scan_.Error("'element' before the 'format' line");
        SVOKIT_RETURN_IF_ERROR(ParseElement());
      } else if (key == "property") {
        if (elements_.empty()) return scan_.Error("'property' before the first 'element'");
        SVOKIT_RETURN_IF_ERROR(ParseProperty(elements_.back()));
      } else if (key == "end_header") {
        if (!scan_.AtLineEnd()) return scan_.Error("unexpected text after 'end_header'");
        if (!have_format) return scan_.Error("the header has no 'format' line");
        const std::size_t newline = AsText(bytes_).find('\n', line_start - AsText(bytes_).data());
        data_offset_ = newline == std::string_view::npos ? bytes_.size() : newline + 1;
        return Status::Ok();
      } else if (elements_.empty()) {
        // Old exporters (e.g. Blender 2.4) wrote comment text without 'comment'. Before the first
        // element such a line cannot change the data layout, so it is only worth a warning.
        mesh_.warnings.push_back(fmt::format("PLY header line {}: unknown keyword '{}' ignored",
                                             scan_.line_number(), TextScanner::Clip(key)));
      } else {
        return scan_.Error("unknown PLY header keyword '{}'", TextScanner::Clip(key));
      }
    }
    return scan_.Error("the PLY header has no 'end_header' line");
  }

  Status ParseFormat() {
    const std::string_view format = scan_.Token();
    if (format == "ascii") {
      format_ = PlyFormat::kAscii;
    } else if (format == "binary_little_endian") {
      format_ = PlyFormat::kBinaryLittleEndian;
    } else if (format == "binary_big_endian") {
      format_ = PlyFormat::kBinaryBigEndian;
    } else {
      return scan_.Error(
          "unknown PLY format '{}' (expected ascii, binary_little_endian or binary_big_endian)",
          TextScanner::Clip(format));
    }
    const std::string_view version = scan_.Token();
    if (version != "1.0" && version != "1") {
      return scan_.Error("unsupported PLY version '{}' (expected 1.0)", TextScanner::Clip(version));
    }
    if (!scan_.AtLineEnd()) return scan_.Error("unexpected text after the PLY version");
    return Status::Ok();
  }

  Status ParseElement() {
    PlyElement element;
    element.name = std::string(scan_.Token());
    element.line = scan_.line_number();
    if (element.name.empty()) return scan_.Error("'element' without a name");
    SVOKIT_RETURN_IF_ERROR(scan_.Number(element.count, "an element count"));
    if (!scan_.AtLineEnd()) return scan_.Error("unexpected text after the element count");
    if (!element_names_.insert(element.name).second) {
      return scan_.Error("element '{}' is declared twice", element.name);
    }
    elements_.push_back(std::move(element));
    return Status::Ok();
  }

  Status ParseType(PlyType& type) {
    const std::string_view name = scan_.Token();
    const std::optional<PlyType> parsed = ParsePlyType(name);
    if (!parsed) {
      return scan_.Error("unknown PLY property type '{}'",
                         name.empty() ? std::string("(none)") : TextScanner::Clip(name));
    }
    type = *parsed;
    return Status::Ok();
  }

  Status ParseProperty(PlyElement& element) {
    PlyProperty p;
    p.line = scan_.line_number();
    if (scan_.PeekToken() == "list") {
      scan_.Token();
      p.is_list = true;
      SVOKIT_RETURN_IF_ERROR(ParseType(p.count_type));
      if (!IsInteger(p.count_type)) {
        return scan_.Error("list length type '{}' is not an integer type", TypeName(p.count_type));
      }
    }
    SVOKIT_RETURN_IF_ERROR(ParseType(p.type));
    p.name = std::string(scan_.Token());
    if (p.name.empty()) return scan_.Error("property without a name");
    if (!scan_.AtLineEnd()) return scan_.Error("unexpected text after property '{}'", p.name);
    if (!element.property_names.insert(p.name).second) {
      return scan_.Error("element '{}' declares property '{}' twice", element.name, p.name);
    }
    element.properties.push_back(std::move(p));
    return Status::Ok();
  }

  template <class... Args>
  Status LineError(std::size_t line, fmt::format_string<Args...> f, Args&&... args) const {
    return Status::BadInput("{}:{}: {}", name_, line, fmt::format(f, std::forward<Args>(args)...));
  }

  // Finds the vertex and face elements and decides what each of their properties feeds.
  Status AssignRoles() {
    for (PlyElement& e : elements_) {
      const bool is_vertex = e.name == "vertex", is_face = e.name == "face",
                 is_strips = e.name == "tristrips";
      if (e.count > 0 && e.properties.empty()) {
        return LineError(e.line, "element '{}' has no properties", e.name);
      }
      if (is_vertex) vertex_ = &e;
      if (is_face) face_ = &e;
      if (is_strips) strips_ = &e;
      if (!is_vertex && !is_face && !is_strips) continue;
      for (PlyProperty& p : e.properties) {
        const Role role = is_vertex ? VertexRole(p.name)
                          : is_face ? FaceRole(p.name)
                                    : StripRole(p.name);
        if (role == kIgnore || e.has[role]) continue;  // unknown, or an alias already seen
        const bool wants_list = role == kIndices || role == kTexcoord;
        if (p.is_list != wants_list) {
          return LineError(p.line, "property '{}' of element '{}' must be {}", p.name, e.name,
                           wants_list ? "a list" : "a scalar, not a list");
        }
        if (role == kIndices && !IsInteger(p.type)) {
          return LineError(p.line, "vertex index type '{}' is not an integer type",
                           TypeName(p.type));
        }
        p.role = role;
        e.has[role] = true;
        e.scale[role] = ColorScale(p.type);
      }
    }
    if (!vertex_) return Status::BadInput("{}: the PLY file has no 'vertex' element", name_);
    if (!vertex_->Has({kX, kY, kZ})) {
      return LineError(vertex_->line, "element 'vertex' lacks one of the properties x, y, z");
    }
    if (vertex_->count > UINT32_MAX) {
      return LineError(vertex_->line, "{} vertices; at most 2^32 - 1 are supported",
                       vertex_->count);
    }
    if (!face_ && !strips_) {
      return Status::BadInput(
          "{}: the PLY file has no 'face' or 'tristrips' element (a point cloud?); svokit needs "
          "triangles",
          name_);
    }
    for (const PlyElement* e : {face_, strips_}) {
      if (e && !e->has[kIndices]) {
        return LineError(e->line, "element '{}' has no 'vertex_indices' list", e->name);
      }
    }
    if ((face_ ? face_->count : 0) + (strips_ ? strips_->count : 0) == 0) {
      return LineError((face_ ? face_ : strips_)->line, "the PLY file declares 0 faces");
    }
    const PlyElement& v = *vertex_;
    auto incomplete = [&](std::initializer_list<Role> roles, const char* what) {
      const bool any = std::any_of(roles.begin(), roles.end(), [&](Role r) { return v.has[r]; });
      if (any && !v.Has(roles)) {
        mesh_.warnings.push_back(fmt::format("incomplete vertex {} ignored", what));
      }
    };
    incomplete({kNx, kNy, kNz}, "normals (need nx, ny, nz)");
    incomplete({kU, kV}, "texture coordinates (need u and v, or s and t)");
    incomplete({kRed, kGreen, kBlue}, "colours (need red, green, blue)");
    return Status::Ok();
  }

  // Smallest number of bytes one element can take: fixed-size properties plus list lengths for
  // binary, one digit and a separator per value for ASCII.
  std::uint64_t MinElementBytes(const PlyElement& e) const {
    std::uint64_t bytes = 0;
    for (const PlyProperty& p : e.properties) {
      bytes += format_ == PlyFormat::kAscii ? 2 : SizeOf(p.is_list ? p.count_type : p.type);
    }
    return bytes;
  }

  // Rejects declared counts the file cannot possibly hold, before anything is reserved.
  Status CheckSizes() {
    const std::uint64_t available = bytes_.size() - data_offset_;
    std::uint64_t needed = 0;
    for (const PlyElement& e : elements_) {
      const std::uint64_t per_element = MinElementBytes(e);
      if (!CountFits(e.count, per_element, available - needed)) {
        return Status::BadInput(
            "{}: truncated: the header declares {} '{}' elements of at least {} bytes each, but "
            "only {} bytes follow the header",
            name_, e.count, e.name, per_element, available);
      }
      needed += e.count * per_element;
    }
    mesh_.positions.reserve(vertex_->count);
    if (!face_) return Status::Ok();
    // Faces with fewer than 3 corners are errors, so a valid face needs room for 3 indices.
    std::uint64_t face_bytes = MinElementBytes(*face_);
    for (const PlyProperty& p : face_->properties) {
      if (p.role == kIndices) face_bytes += 3 * (format_ == PlyFormat::kAscii ? 2 : SizeOf(p.type));
    }
    const std::uint64_t face_capacity =
        std::min<std::uint64_t>(face_->count, available / face_bytes);
    soup_.ends.reserve(face_capacity);
    soup_.corners.reserve(3 * face_capacity);
    return Status::Ok();
  }

  template <class Reader>
  Status ReadBody(Reader& in) {
    for (const PlyElement& e : elements_) SVOKIT_RETURN_IF_ERROR(ReadElement(in, e));
    return Status::Ok();
  }

  template <class Reader>
  Status ReadElement(Reader& in, const PlyElement& e) {
    const bool is_vertex = &e == vertex_, is_face = &e == face_, is_strips = &e == strips_;
    const bool normals = is_vertex && e.Has({kNx, kNy, kNz});
    const bool uvs = is_vertex && e.Has({kU, kV});
    const bool colors = e.Has({kRed, kGreen, kBlue});
    const bool face_uvs = is_face && e.has[kTexcoord];
    const bool face_colors = is_face && colors;
    if (normals) vertex_attributes_.normals.reserve(e.count);
    if (uvs) vertex_attributes_.uvs.reserve(e.count);
    if (is_vertex && colors) vertex_attributes_.colors.reserve(e.count);
    if (face_colors) soup_.colors.reserve(soup_.ends.capacity());

    std::array<double, kRoleCount> value{};
    for (std::uint64_t i = 0; i < e.count; ++i) {
      if (!in.BeginInstance()) return in.Failure({e, i, nullptr});
      const std::size_t first_corner = soup_.corners.size();
      const std::size_t first_uv = soup_.corner_uvs.size();
      for (const PlyProperty& p : e.properties) {
        if (!p.is_list) {
          // Scalars svokit does not use land in value[kIgnore].
          if (!in.Real(p.type, value[p.role])) return in.Failure({e, i, &p});
          continue;
        }
        std::int64_t n = 0;
        if (!in.Integer(p.count_type, n)) return in.Failure({e, i, &p});
        if (n < 0)
          return in.Error("element '{}' {}: list '{}' has length {}", e.name, i, p.name, n);
        const auto length = static_cast<std::uint64_t>(n);
        if (p.role == kIndices && is_strips) {
          SVOKIT_RETURN_IF_ERROR(ReadStrip(in, {e, i, &p}, length));
        } else if (p.role == kIndices) {
          SVOKIT_RETURN_IF_ERROR(ReadCorners(in, {e, i, &p}, length));
        } else if (p.role == kTexcoord) {
          SVOKIT_RETURN_IF_ERROR(ReadTexcoords(in, {e, i, &p}, length));
        } else if (!in.Skip(p.type, length)) {
          return in.Failure({e, i, &p});
        }
      }
      if (!in.EndInstance()) return in.Failure({e, i, nullptr});

      if (is_vertex) {
        mesh_.positions.push_back({value[kX], value[kY], value[kZ]});
        if (normals) {
          vertex_attributes_.normals.push_back(
              {NarrowToFloat(value[kNx]), NarrowToFloat(value[kNy]), NarrowToFloat(value[kNz])});
        }
        if (uvs) {
          vertex_attributes_.uvs.push_back({NarrowToFloat(value[kU]), NarrowToFloat(value[kV])});
        }
        if (colors) vertex_attributes_.colors.push_back(ColorOf(e, value));
      } else if (is_face) {
        const std::size_t corners = soup_.corners.size() - first_corner;
        if (face_uvs && soup_.corner_uvs.size() - first_uv != corners) {
          return in.Error("face {}: 'texcoord' has {} pairs for {} corners", i,
                          soup_.corner_uvs.size() - first_uv, corners);
        }
        soup_.ends.push_back(soup_.corners.size());
        if (face_colors) soup_.colors.push_back(ColorOf(e, value));
        if (e.has[kTexnumber] && texture_files_.size() > 1) {
          const double t = value[kTexnumber];
          if (!(t >= 0 && t < static_cast<double>(texture_files_.size()) && t == std::floor(t))) {
            return in.Error("face {}: texnumber {} does not name one of the {} TextureFiles", i, t,
                            texture_files_.size());
          }
          soup_.materials.push_back(static_cast<std::uint32_t>(t));
        }
      } else if (is_strips) {
        strips_soup_.ends.push_back(strips_soup_.indices.size());
      }
    }
    return Status::Ok();
  }

  template <class Reader>
  Status ReadCorners(Reader& in, const PlyCursor& at, std::uint64_t n) {
    if (n < 3) return in.Error("face {} has {} corners; at least 3 are needed", at.index, n);
    if (!in.CanHold(at.property->type, n)) return in.Failure(at);
    const std::int64_t vertex_count = static_cast<std::int64_t>(vertex_->count);
    for (std::uint64_t k = 0; k < n; ++k) {
      std::int64_t v = 0;
      if (!in.Integer(at.property->type, v)) return in.Failure(at);
      if (v < 0 || v >= vertex_count) {
        return in.Error("face {}: vertex index {} is out of range (the file has {} vertices)",
                        at.index, v, vertex_count);
      }
      soup_.corners.push_back(static_cast<std::uint32_t>(v));
    }
    return Status::Ok();
  }

  // A strip of any length; -1 restarts it.
  template <class Reader>
  Status ReadStrip(Reader& in, const PlyCursor& at, std::uint64_t n) {
    if (!in.CanHold(at.property->type, n)) return in.Failure(at);
    const std::int64_t vertex_count = static_cast<std::int64_t>(vertex_->count);
    for (std::uint64_t k = 0; k < n; ++k) {
      std::int64_t v = 0;
      if (!in.Integer(at.property->type, v)) return in.Failure(at);
      if (v == -1) {
        strips_soup_.indices.push_back(StripSoup::kRestart);
        continue;
      }
      if (v < 0 || v >= vertex_count) {
        return in.Error(
            "tristrips {}: vertex index {} is out of range (the file has {} vertices; -1 restarts "
            "a strip)",
            at.index, v, vertex_count);
      }
      strips_soup_.indices.push_back(static_cast<std::uint32_t>(v));
    }
    return Status::Ok();
  }

  // Triangle i of a strip is (v[i], v[i+1], v[i+2]) for even i and (v[i+1], v[i], v[i+2]) for
  // odd i, so the winding stays consistent; -1 starts a new strip (and a new parity), as in
  // VCG/MeshLab. Degenerate triangles, which strips use to turn or join, are dropped.
  void AppendStrips(PolygonAppender& out) const {
    const std::span<const std::uint32_t> all = strips_soup_.indices;
    std::size_t begin = 0;
    for (const std::size_t end : strips_soup_.ends) {
      std::size_t start = begin;
      for (std::size_t k = begin; k + 2 < end; ++k) {
        const std::uint32_t a = all[k], b = all[k + 1], c = all[k + 2];
        if (a == StripSoup::kRestart) {
          start = k + 1;
          continue;
        }
        if (b == StripSoup::kRestart || c == StripSoup::kRestart) continue;
        if (a == b || b == c || a == c) continue;
        const std::array<std::uint32_t, 3> tri =
            (k - start) % 2 == 0 ? std::array{a, b, c} : std::array{b, a, c};
        out.Append(tri);
      }
      begin = end;
    }
  }

  template <class Reader>
  Status ReadTexcoords(Reader& in, const PlyCursor& at, std::uint64_t n) {
    if (n % 2 != 0) {
      return in.Error("face {}: 'texcoord' has an odd number of values ({})", at.index, n);
    }
    if (!in.CanHold(at.property->type, n)) return in.Failure(at);
    for (std::uint64_t k = 0; k < n; k += 2) {
      double u = 0, v = 0;
      if (!in.Real(at.property->type, u) || !in.Real(at.property->type, v)) {
        return in.Failure(at);
      }
      soup_.corner_uvs.push_back({NarrowToFloat(u), NarrowToFloat(v)});
    }
    return Status::Ok();
  }

  static Rgba ColorOf(const PlyElement& e, const std::array<double, kRoleCount>& value) {
    return DisplayColor(value[kRed] * e.scale[kRed], value[kGreen] * e.scale[kGreen],
                        value[kBlue] * e.scale[kBlue],
                        e.has[kAlpha] ? value[kAlpha] * e.scale[kAlpha] : 1.0);
  }

  Status BuildTriangles() {
    for (const std::string& file : texture_files_) {
      Material& material = mesh_.materials.emplace_back();
      material.name = file;
      AttachTextureFile(rule_, rule_.model_folder(), file, SideFileSyntax::kPath, material, mesh_);
    }
    // Per-vertex colours carry more detail than per-face ones, so they win when both exist.
    const bool face_colors = !soup_.colors.empty() && vertex_attributes_.colors.empty();
    if (!soup_.colors.empty() && !face_colors) {
      mesh_.warnings.push_back("per-face colours ignored (the vertices have colours)");
    }
    PolygonAppender out(mesh_, vertex_attributes_);
    // Triangulating an n-gon always yields n - 2 triangles.
    out.Reserve(soup_.corners.size() - 2 * soup_.ends.size() + strips_soup_.indices.size());
    const std::span<const std::uint32_t> corners = soup_.corners;
    const std::span<const Vec2f> corner_uvs = soup_.corner_uvs;
    std::size_t begin = 0;
    for (std::size_t f = 0; f < soup_.ends.size(); ++f) {
      const std::size_t n = soup_.ends[f] - begin;
      out.Append(corners.subspan(begin, n),
                 corner_uvs.empty() ? std::span<const Vec2f>() : corner_uvs.subspan(begin, n),
                 face_colors ? &soup_.colors[f] : nullptr,
                 soup_.materials.empty() ? 0 : soup_.materials[f]);
      begin = soup_.ends[f];
    }
    AppendStrips(out);
    return Status::Ok();
  }

  SideFileRule rule_;
  std::string name_;
  std::span<const std::uint8_t> bytes_;
  TextScanner scan_;
  PlyFormat format_ = PlyFormat::kAscii;
  std::vector<PlyElement> elements_;
  std::unordered_set<std::string> element_names_;
  std::vector<std::string> texture_files_;
  std::size_t data_offset_ = 0;
  const PlyElement* vertex_ = nullptr;
  const PlyElement* face_ = nullptr;
  const PlyElement* strips_ = nullptr;
  StripSoup strips_soup_;
  VertexAttributes vertex_attributes_;
  FaceSoup soup_;
  Mesh mesh_;
};

}  // namespace

StatusOr<Mesh> ImportPly(const std::filesystem::path& path, const ImportOptions& options) {
  StatusOr<std::vector<std::uint8_t>> bytes = ReadMeshFile(path);
  if (!bytes.ok()) return bytes.status();
  PlyImporter importer(path, *bytes, options);
  return importer.Import();
}

}  // namespace svokit::detail
