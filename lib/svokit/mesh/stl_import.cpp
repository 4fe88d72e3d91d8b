// STL, binary and ASCII. STL stores each facet's three corners separately; identical positions are
// welded (exactly, bitwise) so the mesh comes out indexed and its topology can be analysed.
// Facet normals are ignored: exporters often write them wrong or as zero, and the normal implied by
// the vertex order is exact.

#include <algorithm>
#include <bit>
#include <cctype>
#include <cstring>

#include "svokit/core/bytes.hpp"
#include "svokit/mesh/importers.hpp"
#include "svokit/mesh/mesh_builder.hpp"
#include "svokit/mesh/text_scanner.hpp"

namespace svokit::detail {

namespace {

constexpr std::uint64_t kBinaryHeaderBytes = 84;  // 80-byte comment + u32 triangle count
constexpr std::uint64_t kBinaryFacetBytes = 50;   // normal, 3 corners (12 floats) + u16 attribute

// Maps positions to vertex indices with open addressing: one probe array of indices into the
// positions themselves, so the table costs 4 bytes a slot and never copies a key.
class PositionWelder {
 public:
  PositionWelder(std::vector<Vec3d>& positions, std::size_t expected_vertices)
      : positions_(positions) {
    std::size_t capacity = 1024;
    while (capacity < 2 * expected_vertices) capacity *= 2;
    slots_.assign(capacity, kEmpty);
    positions_.reserve(expected_vertices);
  }

  /// The index of `p` (finite), adding it if new; false when 2^32 - 1 vertices are exceeded.
  bool Insert(Vec3d p, std::uint32_t& index) {
    // -0.0 and +0.0 are the same point, but not the same bits.
    for (int a = 0; a < 3; ++a) p[a] = p[a] == 0.0 ? 0.0 : p[a];
    const std::size_t mask = slots_.size() - 1;
    for (std::size_t s = Hash(p) & mask;; s = (s + 1) & mask) {
      const std::uint32_t slot = slots_[s];
      if (slot == kEmpty) break;
      if (positions_[slot] == p) {
        index = slot;
        return true;
      }
    }
    if (positions_.size() >= kEmpty) return false;
    index = static_cast<std::uint32_t>(positions_.size());
    positions_.push_back(p);
    // Keep the load factor at most 1/2 so probe sequences stay short.
    if (2 * positions_.size() > slots_.size()) {
      Rehash(2 * slots_.size());
    } else {
      Place(index);
    }
    return true;
  }

 private:
  static constexpr std::uint32_t kEmpty = UINT32_MAX;

  static std::uint64_t Mix(std::uint64_t h) {  // splitmix64 finaliser
    h ^= h >> 30;
    h *= 0xbf58476d1ce4e5b9ULL;
    h ^= h >> 27;
    h *= 0x94d049bb133111ebULL;
    return h ^ (h >> 31);
  }
  static std::size_t Hash(const Vec3d& p) {
    std::uint64_t h = Mix(std::bit_cast<std::uint64_t>(p.x));
    h = Mix(h ^ std::bit_cast<std::uint64_t>(p.y));
    return static_cast<std::size_t>(Mix(h ^ std::bit_cast<std::uint64_t>(p.z)));
  }
  void Place(std::uint32_t index) {
    const std::size_t mask = slots_.size() - 1;
    std::size_t s = Hash(positions_[index]) & mask;
    while (slots_[s] != kEmpty) s = (s + 1) & mask;
    slots_[s] = index;
  }
  void Rehash(std::size_t capacity) {
    slots_.assign(capacity, kEmpty);
    for (std::uint32_t i = 0; i < positions_.size(); ++i) Place(i);
  }

  std::vector<Vec3d>& positions_;
  std::vector<std::uint32_t> slots_;
};

class StlImporter {
 public:
  StlImporter(std::span<const std::uint8_t> bytes, std::string name)
      : bytes_(bytes), name_(std::move(name)) {}

  StatusOr<Mesh> Import() {
    std::uint64_t declared = 0;
    if (bytes_.size() >= kBinaryHeaderBytes) {
      ByteReader header(bytes_.subspan(80, 4), name_);
      std::uint32_t count = 0;
      SVOKIT_RETURN_IF_ERROR(header.Get(count));
      declared = count;
      // The size test comes first: many binary STLs start their header with "solid" too.
      if (bytes_.size() == kBinaryHeaderBytes + kBinaryFacetBytes * declared) {
        return ImportBinary(declared);
      }
    }
    // ASCII STL is plain text: a NUL byte means a (broken) binary file whatever its first word.
    const std::string_view text = AsText(bytes_);
    if (StartsWithSolid(text) && text.find('\0') == std::string_view::npos) {
      return ImportAscii(text);
    }
    if (bytes_.size() < kBinaryHeaderBytes) {
      return Status::BadInput(
          "{}: truncated or malformed binary STL: the file has {} bytes, less than the {}-byte "
          "header, and is not ASCII STL",
          name_, bytes_.size(), kBinaryHeaderBytes);
    }
    return Status::BadInput(
        "{}: truncated or malformed binary STL: header declares {} triangles ({} bytes) but the "
        "file has {} bytes",
        name_, declared, kBinaryHeaderBytes + kBinaryFacetBytes * declared, bytes_.size());
  }

 private:
  static bool IsSpace(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; }
  static bool EqualsNoCase(std::string_view a, std::string_view b) {
    return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
             return std::tolower(static_cast<unsigned char>(x)) ==
                    std::tolower(static_cast<unsigned char>(y));
           });
  }
  static bool StartsWithSolid(std::string_view text) {
    std::size_t i = 0;
    while (i < text.size() && IsSpace(text[i])) ++i;
    return EqualsNoCase(text.substr(i, 5), "solid");
  }

  // The binary file's size equals 84 + 50 * declared, so every read below is in bounds.
  StatusOr<Mesh> ImportBinary(std::uint64_t declared) {
    if (declared == 0) return Status::BadInput("{}: binary STL with 0 triangles", name_);
    PositionWelder welder(mesh_.positions, declared / 2 + 3);
    mesh_.triangles.reserve(declared);
    const std::uint8_t* facet = bytes_.data() + kBinaryHeaderBytes;
    for (std::uint64_t f = 0; f < declared; ++f, facet += kBinaryFacetBytes) {
      float xyz[9];
      std::memcpy(xyz, facet + 12, sizeof xyz);  // skip the facet normal
      Triangle t;
      for (int c = 0; c < 3; ++c) {
        const Vec3d p{xyz[3 * c], xyz[3 * c + 1], xyz[3 * c + 2]};
        if (!IsFinite(p)) {
          return Status::BadInput("{}: facet {} has a non-finite vertex coordinate ({}, {}, {})",
                                  name_, f, p.x, p.y, p.z);
        }
        if (!welder.Insert(p, t[c])) {
          return Status::BadInput("{}: more than 2^32 - 1 distinct vertices", name_);
        }
      }
      mesh_.triangles.push_back(t);
    }
    mesh_.material_ids.assign(mesh_.triangles.size(), 0);
    return std::move(mesh_);
  }

  StatusOr<Mesh> ImportAscii(std::string_view text) {
    TextScanner scan(text, name_);
    // Facets take at least ~100 bytes of text, and closed meshes have about half as many
    // vertices as facets.
    PositionWelder welder(mesh_.positions, text.size() / 200);
    std::size_t solids = 0;
    for (;;) {
      const std::string_view tok = NextToken(scan);
      if (tok.empty()) break;
      if (!EqualsNoCase(tok, "solid")) return Unexpected(scan, tok, "'solid'");
      scan.Rest();  // the solid's name
      ++solids;
      SVOKIT_RETURN_IF_ERROR(ParseSolid(scan, welder));
    }
    if (solids == 0) return scan.Error("no 'solid' in the ASCII STL file");
    if (mesh_.triangles.empty()) return scan.Error("the STL file has no facets");
    mesh_.material_ids.assign(mesh_.triangles.size(), 0);
    return std::move(mesh_);
  }

  Status ParseSolid(TextScanner& scan, PositionWelder& welder) {
    for (;;) {
      const std::string_view tok = NextToken(scan);
      if (EqualsNoCase(tok, "endsolid")) {
        scan.Rest();  // the name, which need not match the one after 'solid'
        return Status::Ok();
      }
      if (!EqualsNoCase(tok, "facet")) return Unexpected(scan, tok, "'facet' or 'endsolid'");
      const std::size_t f = mesh_.triangles.size();
      SVOKIT_RETURN_IF_ERROR(Expect(scan, "normal"));
      double ignored_normal[3];
      for (double& n : ignored_normal) SVOKIT_RETURN_IF_ERROR(Number(scan, n, f));
      SVOKIT_RETURN_IF_ERROR(Expect(scan, "outer"));
      SVOKIT_RETURN_IF_ERROR(Expect(scan, "loop"));
      Triangle t;
      for (int c = 0; c < 3; ++c) {
        SVOKIT_RETURN_IF_ERROR(Expect(scan, "vertex"));
        Vec3d p;
        for (int a = 0; a < 3; ++a) SVOKIT_RETURN_IF_ERROR(Number(scan, p[a], f));
        if (!IsFinite(p)) {
          return scan.Error("facet {} has a non-finite vertex coordinate ({}, {}, {})", f, p.x, p.y,
                            p.z);
        }
        if (!welder.Insert(p, t[c])) return scan.Error("more than 2^32 - 1 distinct vertices");
      }
      SVOKIT_RETURN_IF_ERROR(Expect(scan, "endloop"));
      SVOKIT_RETURN_IF_ERROR(Expect(scan, "endfacet"));
      mesh_.triangles.push_back(t);
    }
  }

  // The next token, across line breaks; empty at the end of the text.
  static std::string_view NextToken(TextScanner& scan) {
    for (;;) {
      const std::string_view tok = scan.Token();
      if (!tok.empty()) return tok;
      if (!scan.NextLine()) return {};
    }
  }
  static Status Unexpected(const TextScanner& scan, std::string_view tok, std::string_view want) {
    if (tok.empty()) return scan.Error("truncated: expected {}, found the end of the file", want);
    return scan.Error("expected {}, found '{}'", want, TextScanner::Clip(tok));
  }
  static Status Expect(TextScanner& scan, std::string_view keyword) {
    const std::string_view tok = NextToken(scan);
    if (EqualsNoCase(tok, keyword)) return Status::Ok();
    return Unexpected(scan, tok, fmt::format("'{}'", keyword));
  }
  static Status Number(TextScanner& scan, double& value, std::size_t facet) {
    const std::string_view tok = NextToken(scan);
    if (TextScanner::ParseNumber(tok, value)) return Status::Ok();
    if (tok.empty()) return Unexpected(scan, tok, "a number");
    return scan.Error("facet {}: expected a number, found '{}'", facet, TextScanner::Clip(tok));
  }

  std::span<const std::uint8_t> bytes_;
  std::string name_;
  Mesh mesh_;
};

}  // namespace

StatusOr<Mesh> ImportStl(const std::filesystem::path& path) {
  StatusOr<std::vector<std::uint8_t>> bytes = ReadMeshFile(path);
  if (!bytes.ok()) return bytes.status();
  StlImporter importer(*bytes, path.string());
  return importer.Import();
}

}  // namespace svokit::detail
