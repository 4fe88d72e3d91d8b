// Geomview OFF and its variants [ST][C][N]OFF: a keyword, vertex and face counts, one vertex per
// line (x y z [nx ny nz] [r g b [a]] [s t]) and one face per line (n i0 .. in-1 [colour]).
// '#' starts a comment anywhere. Colours are sRGB display values: integers 0..255 or floats 0..1.

#include <algorithm>
#include <array>

#include "svokit/mesh/importers.hpp"
#include "svokit/mesh/mesh_builder.hpp"
#include "svokit/mesh/text_scanner.hpp"

namespace svokit::detail {

namespace {

// Up to x y z + nx ny nz + r g b a + s t.
constexpr int kMaxVertexValues = 12;

// A number of a vertex or face line; colours need to know whether it was written as an integer.
struct OffNumber {
  double value = 0;
  bool integer = false;
};

class OffImporter {
 public:
  OffImporter(std::string_view text, std::string name)
      : text_(text), name_(std::move(name)), scan_(text, name_) {}

  StatusOr<Mesh> Import() {
    SVOKIT_RETURN_IF_ERROR(ParseHeader());
    mesh_.positions.reserve(vertex_count_);
    if (normals_) attributes_.normals.reserve(vertex_count_);
    if (colors_) attributes_.colors.reserve(vertex_count_);
    if (uvs_) attributes_.uvs.reserve(vertex_count_);
    for (std::uint64_t i = 0; i < vertex_count_; ++i) {
      if (!scan_.NextContentLine()) {
        return scan_.Error("truncated: the file ends after {} of {} vertices", i, vertex_count_);
      }
      SVOKIT_RETURN_IF_ERROR(ReadVertex(i));
    }
    PolygonAppender out(mesh_, attributes_);
    out.Reserve(face_count_);
    for (std::uint64_t f = 0; f < face_count_; ++f) {
      if (!scan_.NextContentLine()) {
        return scan_.Error("truncated: the file ends after {} of {} faces", f, face_count_);
      }
      SVOKIT_RETURN_IF_ERROR(ReadFace(f, out));
    }
    if (ignored_face_colors_ > 0) {
      mesh_.warnings.push_back(fmt::format(
          "{} per-face colours ignored (the vertices have colours)", ignored_face_colors_));
    }
    if (ignored_colormap_indices_ > 0) {
      mesh_.warnings.push_back(fmt::format("{} per-face colour-map indices ignored (no colour map)",
                                           ignored_colormap_indices_));
    }
    if (scan_.NextContentLine()) {
      mesh_.warnings.push_back(
          fmt::format("content after the last face ignored (from line {})", scan_.line_number()));
    }
    return std::move(mesh_);
  }

 private:
  // The next token of the current line; a '#' ends the line.
  std::string_view Token() {
    std::string_view tok = scan_.Token();
    const std::size_t hash = tok.find('#');
    if (hash != std::string_view::npos) {
      tok = tok.substr(0, hash);
      scan_.Rest();
    }
    return tok;
  }

  Status ParseHeader() {
    if (!scan_.NextContentLine()) return scan_.Error("no OFF keyword (the file has no content)");
    const std::string_view keyword = Token();
    std::string_view k = keyword;
    uvs_ = k.starts_with("ST");
    if (uvs_) k.remove_prefix(2);
    colors_ = k.starts_with("C");
    if (colors_) k.remove_prefix(1);
    normals_ = k.starts_with("N");
    if (normals_) k.remove_prefix(1);
    if (k.starts_with("4")) return scan_.Error("4D vertices ('{}') are not supported", keyword);
    if (k.starts_with("n")) {
      return scan_.Error("n-dimensional OFF ('{}') is not supported", keyword);
    }
    if (k != "OFF") {
      return scan_.Error(
          "not an OFF file: expected a keyword such as OFF, COFF, NOFF or STOFF, "
          "found '{}'",
          TextScanner::Clip(keyword));
    }
    std::string_view tok = Token();
    if (tok == "BINARY") return scan_.Error("binary OFF is not supported");
    // Some writers (e.g. several CGAL data files) put the counts on the keyword's line.
    if (tok.empty()) {
      if (!scan_.NextContentLine()) return scan_.Error("truncated: no vertex and face counts");
      tok = Token();
    }
    std::uint64_t counts[3] = {0, 0, 0};
    int n = 0;
    for (; !tok.empty(); tok = Token(), ++n) {
      if (n == 3) return scan_.Error("unexpected '{}' after the counts", TextScanner::Clip(tok));
      if (!TextScanner::ParseNumber(tok, counts[n])) {
        return scan_.Error("expected the vertex, face and edge counts, found '{}'",
                           TextScanner::Clip(tok));
      }
    }
    if (n < 2) return scan_.Error("expected the vertex and face counts (and edge count)");
    vertex_count_ = counts[0];
    face_count_ = counts[1];
    if (face_count_ == 0) return scan_.Error("the OFF file declares 0 faces");
    if (vertex_count_ > UINT32_MAX) {
      return scan_.Error("{} vertices; at most 2^32 - 1 are supported", vertex_count_);
    }
    // A vertex line has at least "x y z\n", a face line at least "3 a b c\n": two bytes a number.
    const std::uint64_t remaining = text_.size();
    const std::uint64_t vertex_bytes =
        2 * (3 + (normals_ ? 3 : 0) + (colors_ ? 3 : 0) + (uvs_ ? 2 : 0));
    if (!CountFits(vertex_count_, vertex_bytes, remaining) ||
        !CountFits(face_count_, 8, remaining - vertex_count_ * vertex_bytes)) {
      return scan_.Error(
          "truncated: the header declares {} vertices and {} faces, but the file has only {} bytes",
          vertex_count_, face_count_, remaining);
    }
    return Status::Ok();
  }

  // Reads the rest of the line's numbers into values (at most values.size()); n = how many.
  template <std::size_t N>
  Status ReadNumbers(std::array<OffNumber, N>& values, std::size_t& n, const char* what,
                     std::uint64_t index) {
    n = 0;
    for (std::string_view tok = Token(); !tok.empty(); tok = Token()) {
      if (n == N) return scan_.Error("{} {}: too many values", what, index);
      OffNumber& number = values[n++];
      if (!TextScanner::ParseNumber(tok, number.value)) {
        return scan_.Error("{} {}: expected a number, found '{}'", what, index,
                           TextScanner::Clip(tok));
      }
      number.integer = tok.find_first_not_of("+-0123456789") == std::string_view::npos;
    }
    return Status::Ok();
  }

  // 3 or 4 components: all integers means 0..255, otherwise 0..1.
  Status ReadColor(const OffNumber* c, std::size_t n, const char* what, std::uint64_t index,
                   Rgba& color) {
    const bool bytes = std::all_of(c, c + n, [](const OffNumber& x) { return x.integer; });
    double v[4] = {0, 0, 0, bytes ? 255.0 : 1.0};
    for (std::size_t k = 0; k < n; ++k) {
      v[k] = c[k].value;
      if (bytes && (v[k] < 0 || v[k] > 255)) {
        return scan_.Error("{} {}: colour component {} is outside 0..255", what, index, v[k]);
      }
    }
    const double scale = bytes ? 1.0 / 255.0 : 1.0;
    color = DisplayColor(v[0] * scale, v[1] * scale, v[2] * scale, v[3] * scale);
    return Status::Ok();
  }

  Status ReadVertex(std::uint64_t i) {
    std::array<OffNumber, kMaxVertexValues> v;
    std::size_t n = 0;
    SVOKIT_RETURN_IF_ERROR(ReadNumbers(v, n, "vertex", i));
    const std::size_t fixed = 3 + (normals_ ? 3 : 0) + (uvs_ ? 2 : 0);
    const std::size_t color_values = n >= fixed ? n - fixed : 0;
    if (n < fixed || (colors_ ? color_values != 3 && color_values != 4 : color_values != 0)) {
      return scan_.Error("vertex {}: {} numbers do not match the {} layout (x y z{}{}{})", i, n,
                         colors_ || normals_ || uvs_ ? "declared" : "OFF",
                         normals_ ? " nx ny nz" : "", colors_ ? " r g b [a]" : "",
                         uvs_ ? " s t" : "");
    }
    mesh_.positions.push_back({v[0].value, v[1].value, v[2].value});
    std::size_t next = 3;
    if (normals_) {
      attributes_.normals.push_back(
          {NarrowToFloat(v[3].value), NarrowToFloat(v[4].value), NarrowToFloat(v[5].value)});
      next = 6;
    }
    if (colors_) {
      Rgba c;
      SVOKIT_RETURN_IF_ERROR(ReadColor(&v[next], color_values, "vertex", i, c));
      attributes_.colors.push_back(c);
      next += color_values;
    }
    if (uvs_) {
      attributes_.uvs.push_back({NarrowToFloat(v[next].value), NarrowToFloat(v[next + 1].value)});
    }
    return Status::Ok();
  }

  Status ReadFace(std::uint64_t f, PolygonAppender& out) {
    std::string_view tok = Token();
    std::int64_t n = 0;
    if (!TextScanner::ParseNumber(tok, n)) {
      return scan_.Error("face {}: expected the number of corners, found '{}'", f,
                         TextScanner::Clip(tok));
    }
    if (n < 3) return scan_.Error("face {} has {} corners; at least 3 are needed", f, n);
    corners_.clear();
    for (std::int64_t k = 0; k < n; ++k) {
      tok = Token();
      std::int64_t v = 0;
      if (tok.empty()) {
        return scan_.Error("face {}: the line ends after {} of {} vertex indices", f, k, n);
      }
      if (!TextScanner::ParseNumber(tok, v)) {
        return scan_.Error("face {}: expected a vertex index, found '{}'", f,
                           TextScanner::Clip(tok));
      }
      if (v < 0 || static_cast<std::uint64_t>(v) >= vertex_count_) {
        return scan_.Error("face {}: vertex index {} is out of range (the file has {} vertices)", f,
                           v, vertex_count_);
      }
      corners_.push_back(static_cast<std::uint32_t>(v));
    }
    // Optional colour: nothing, a colour-map index, or 3 or 4 components.
    std::array<OffNumber, 4> c;
    std::size_t nc = 0;
    SVOKIT_RETURN_IF_ERROR(ReadNumbers(c, nc, "face", f));
    Rgba color;
    bool use_color = false;
    if (nc == 3 || nc == 4) {
      if (colors_) {
        ++ignored_face_colors_;  // per-vertex colours carry more detail and win
      } else {
        SVOKIT_RETURN_IF_ERROR(ReadColor(c.data(), nc, "face", f, color));
        use_color = true;
      }
    } else if (nc == 1) {
      ++ignored_colormap_indices_;
    } else if (nc != 0) {
      return scan_.Error("face {}: {} values after the vertex indices (a colour has 3 or 4)", f,
                         nc);
    }
    out.Append(corners_, {}, use_color ? &color : nullptr);
    return Status::Ok();
  }

  std::string_view text_;
  std::string name_;
  TextScanner scan_;
  bool uvs_ = false, colors_ = false, normals_ = false;
  std::uint64_t vertex_count_ = 0, face_count_ = 0;
  VertexAttributes attributes_;
  Mesh mesh_;
  std::size_t ignored_face_colors_ = 0;
  std::size_t ignored_colormap_indices_ = 0;
  std::vector<std::uint32_t> corners_;  // scratch, reused across faces
};

}  // namespace

StatusOr<Mesh> ImportOff(const std::filesystem::path& path) {
  StatusOr<std::vector<std::uint8_t>> bytes = ReadMeshFile(path);
  if (!bytes.ok()) return bytes.status();
  OffImporter importer(AsText(*bytes), path.string());
  return importer.Import();
}

}  // namespace svokit::detail
