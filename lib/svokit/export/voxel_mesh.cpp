// Voxel meshes: the faces between a voxel and an empty neighbour, as quads, in OBJ (with a palette
// .mtl) or binary glTF (vertex colours). Faces are made a 128³ cube of voxels at a time in key
// order; with merging, coplanar faces of one colour within such a cube become rectangles (greedy
// meshing), so the output depends on the voxels alone.

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "svokit/core/file_io.hpp"
#include "svokit/core/morton.hpp"
#include "svokit/export/palette.hpp"
#include "svokit/export/voxel_writers.hpp"
#include "svokit/svo/sample_codec.hpp"

namespace svokit {

namespace {

// A face, or a rectangle of faces, on the plane `plane` across axis dir / 2, facing the negative
// (even dir) or positive (odd dir) side, covering [u0, u1) × [v0, v1) on axes (a + 1) % 3 and
// (a + 2) % 3; `color` its colour's output value.
struct Quad {
  std::uint8_t dir = 0;
  std::int64_t plane = 0, u0 = 0, v0 = 0, u1 = 0, v1 = 0;
  std::uint32_t color = 0;
};

constexpr std::uint32_t kChunkShift = 7;  // faces are merged within 128³ cubes of voxels

class FaceMaker {
 public:
  FaceMaker(const VoxelSet& voxels, std::vector<std::uint32_t> colors, bool merge)
      : voxels_(voxels), colors_(std::move(colors)), merge_(merge) {
    const auto& d = voxels.grid.dims();
    std::uint32_t longest = std::max({d[0], d[1], d[2]});
    while ((std::int64_t{1} << level_) < longest) ++level_;
    shift_ = std::min(kChunkShift, level_);
  }

  // Calls visit(quads) once per 128³ cube, in key order.
  template <typename Visit>
  void ForEachChunk(Visit&& visit) const {
    const auto& keys = voxels_.keys;
    std::vector<Quad> quads;
    for (std::size_t begin = 0; begin < keys.size();) {
      const std::uint64_t chunk = keys[begin] >> (3 * shift_);
      std::size_t end = begin;
      while (end < keys.size() && keys[end] >> (3 * shift_) == chunk) ++end;
      quads.clear();
      Faces(begin, end, quads);
      if (merge_) Merge(chunk, quads);
      visit(std::span<const Quad>(quads));
      begin = end;
    }
  }

 private:
  bool Filled(std::int64_t x, std::int64_t y, std::int64_t z) const {
    const std::int64_t side = std::int64_t{1} << level_;
    if (x < 0 || y < 0 || z < 0 || x >= side || y >= side || z >= side) return false;
    return std::binary_search(
        voxels_.keys.begin(), voxels_.keys.end(),
        MortonEncode(static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(y),
                     static_cast<std::uint32_t>(z)));
  }

  void Faces(std::size_t begin, std::size_t end, std::vector<Quad>& out) const {
    for (std::size_t i = begin; i < end; ++i) {
      const MortonCoord m = MortonDecode(voxels_.keys[i]);
      const std::array<std::int64_t, 3> c{m.x, m.y, m.z};
      for (std::uint8_t dir = 0; dir < 6; ++dir) {
        const int a = dir / 2;
        const std::int64_t step = dir % 2 ? 1 : -1;
        std::array<std::int64_t, 3> n = c;
        n[a] += step;
        if (Filled(n[0], n[1], n[2])) continue;
        const std::int64_t u = c[(a + 1) % 3], v = c[(a + 2) % 3];
        out.push_back({dir, c[a] + (dir % 2), u, v, u + 1, v + 1, colors_[i]});
      }
    }
  }

  // Greedy meshing per plane: rows of equal colour grown into rectangles, in v then u order.
  void Merge(std::uint64_t chunk, std::vector<Quad>& quads) const {
    const MortonCoord origin = MortonDecode(chunk);
    const std::int64_t side = std::int64_t{1} << shift_;
    const std::array<std::int64_t, 3> lo{origin.x * side, origin.y * side, origin.z * side};
    std::sort(quads.begin(), quads.end(), [](const Quad& a, const Quad& b) {
      return std::tie(a.dir, a.plane, a.v0, a.u0) < std::tie(b.dir, b.plane, b.v0, b.u0);
    });
    std::vector<Quad> merged;
    std::vector<std::int64_t> cell(static_cast<std::size_t>(side * side), -1);  // colour or −1
    for (std::size_t begin = 0; begin < quads.size();) {
      std::size_t end = begin;
      while (end < quads.size() && quads[end].dir == quads[begin].dir &&
             quads[end].plane == quads[begin].plane) {
        ++end;
      }
      const int a = quads[begin].dir / 2;
      const std::int64_t ulo = lo[(a + 1) % 3], vlo = lo[(a + 2) % 3];
      auto at = [&](std::int64_t u, std::int64_t v) -> std::int64_t& {
        return cell[static_cast<std::size_t>((u - ulo) + side * (v - vlo))];
      };
      for (std::size_t q = begin; q < end; ++q) at(quads[q].u0, quads[q].v0) = quads[q].color;
      for (std::size_t q = begin; q < end; ++q) {
        const std::int64_t u = quads[q].u0, v = quads[q].v0, color = at(u, v);
        if (color < 0) continue;  // already in a rectangle
        std::int64_t u1 = u + 1, v1 = v + 1;
        while (u1 < ulo + side && at(u1, v) == color) ++u1;
        auto row_matches = [&](std::int64_t row) {
          for (std::int64_t x = u; x < u1; ++x) {
            if (at(x, row) != color) return false;
          }
          return true;
        };
        while (v1 < vlo + side && row_matches(v1)) ++v1;
        for (std::int64_t y = v; y < v1; ++y) {
          for (std::int64_t x = u; x < u1; ++x) at(x, y) = -1;
        }
        merged.push_back({quads[q].dir, quads[q].plane, u, v, u1, v1, quads[q].color});
      }
      begin = end;
    }
    quads = std::move(merged);
  }

  const VoxelSet& voxels_;
  std::vector<std::uint32_t> colors_;
  bool merge_;
  std::uint32_t level_ = 0, shift_ = 0;
};

// The quad's corners in grid units, counter-clockwise seen from the side it faces.
std::array<std::array<std::int64_t, 3>, 4> Corners(const Quad& q) {
  const int a = q.dir / 2, ua = (a + 1) % 3, va = (a + 2) % 3;
  std::array<std::array<std::int64_t, 2>, 4> uv{
      {{q.u0, q.v0}, {q.u1, q.v0}, {q.u1, q.v1}, {q.u0, q.v1}}};
  if (q.dir % 2 == 0) std::swap(uv[1], uv[3]);  // u × v is +axis: reversed for the negative side
  std::array<std::array<std::int64_t, 3>, 4> out{};
  for (int k = 0; k < 4; ++k) {
    out[k][a] = q.plane;
    out[k][ua] = uv[k][0];
    out[k][va] = uv[k][1];
  }
  return out;
}

Vec3d World(const GridTransform& grid, const std::array<std::int64_t, 3>& c) {
  const double h = grid.voxel_size();
  const Vec3d o = grid.origin();
  return {o.x + static_cast<double>(c[0]) * h, o.y + static_cast<double>(c[1]) * h,
          o.z + static_cast<double>(c[2]) * h};
}

Status WriteObj(const VoxelSet& voxels, bool merge, const std::filesystem::path& path,
                VoxelMeshStats& stats) {
  // Colours as a palette of materials, as .vox indexes them: a side file NAME.mtl.
  std::vector<std::uint32_t> rgb(voxels.size(), 0xccccccu);
  if (voxels.has_colors()) {
    for (std::size_t i = 0; i < voxels.size(); ++i)
      rgb[i] = EncodeColor(voxels.color(i)) & 0xffffffu;
  }
  const Palette palette = MedianCut(rgb);
  std::filesystem::path mtl_path = path;
  mtl_path.replace_extension(".mtl");
  AtomicFileWriter mtl(mtl_path);
  SVOKIT_RETURN_IF_ERROR(mtl.Open());
  // Kd in linear RGB, as svokit's OBJ importer and Blender's read it.
  std::string text = "# svokit voxel mesh palette: linear RGB\n";
  for (std::size_t k = 0; k < palette.colors.size(); ++k) {
    const Rgba c = DecodeColor(palette.colors[k] | 0xff000000u);
    text += fmt::format("newmtl p{}\nKd {:.6g} {:.6g} {:.6g}\n", k + 1, c.r, c.g, c.b);
  }
  SVOKIT_RETURN_IF_ERROR(mtl.Write(text.data(), text.size()));

  std::vector<std::uint32_t> colors(palette.index.begin(), palette.index.end());
  const FaceMaker maker(voxels, std::move(colors), merge);
  AtomicFileWriter out(path);
  SVOKIT_RETURN_IF_ERROR(out.Open());
  text = fmt::format(
      "# svokit voxel mesh: the faces of {} voxels of {:.9g}\nmtllib {}\n"
      "vn -1 0 0\nvn 1 0 0\nvn 0 -1 0\nvn 0 1 0\nvn 0 0 -1\nvn 0 0 1\n",
      voxels.size(), voxels.grid.voxel_size(), mtl_path.filename().string());
  std::uint64_t vertices = 0;
  std::uint32_t material = 0;
  Status status = out.Write(text.data(), text.size());
  maker.ForEachChunk([&](std::span<const Quad> quads) {
    if (!status.ok()) return;
    text.clear();
    for (const Quad& q : quads) {
      for (const auto& c : Corners(q)) {
        const Vec3d p = World(voxels.grid, c);
        text += fmt::format("v {:.9g} {:.9g} {:.9g}\n", p.x, p.y, p.z);
      }
    }
    for (std::size_t k = 0; k < quads.size(); ++k) {
      if (quads[k].color != material) {
        material = quads[k].color;
        text += fmt::format("usemtl p{}\n", material);
      }
      const std::uint64_t v = vertices + 4 * k + 1;
      const int n = quads[k].dir + 1;
      text += fmt::format("f {}//{} {}//{} {}//{} {}//{}\n", v, n, v + 1, n, v + 2, n, v + 3, n);
    }
    vertices += 4 * quads.size();
    stats.quads += quads.size();
    status = out.Write(text.data(), text.size());
  });
  SVOKIT_RETURN_IF_ERROR(status);
  SVOKIT_RETURN_IF_ERROR(mtl.Commit());
  return out.Commit();
}

// glTF 2.0 binary: positions, normals, linear RGBA8 vertex colours (when the voxels have colours)
// and 32-bit indices, four vertices and two triangles a quad.
Status WriteGlb(const VoxelSet& voxels, bool merge, const std::filesystem::path& path,
                VoxelMeshStats& stats) {
  const bool has_color = voxels.has_colors();
  std::vector<std::uint32_t> colors(voxels.size(), 0);
  if (has_color) {
    for (std::size_t i = 0; i < voxels.size(); ++i) {
      const Rgba c = voxels.color(i);
      colors[i] = EncodeUnorm8(c.r) | EncodeUnorm8(c.g) << 8 | EncodeUnorm8(c.b) << 16 |
                  std::uint32_t{EncodeUnorm8(c.a)} << 24;
    }
  }
  const FaceMaker maker(voxels, std::move(colors), merge);
  // First pass: the counts and bounds the header states.
  std::uint64_t quads = 0;
  std::array<double, 3> lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
  maker.ForEachChunk([&](std::span<const Quad> chunk) {
    quads += chunk.size();
    for (const Quad& q : chunk) {
      for (const auto& c : Corners(q)) {
        const Vec3d p = World(voxels.grid, c);
        const std::array<float, 3> f{static_cast<float>(p.x), static_cast<float>(p.y),
                                     static_cast<float>(p.z)};
        for (int k = 0; k < 3; ++k) {
          lo[k] = std::min<double>(lo[k], f[k]);
          hi[k] = std::max<double>(hi[k], f[k]);
        }
      }
    }
  });
  if (quads == 0) return Status::BadInput("{}: no voxels to mesh", path.string());
  const std::uint64_t vertices = 4 * quads;
  if (vertices > std::numeric_limits<std::uint32_t>::max()) {
    return Status::BadInput("{}: {} vertices pass glTF's 32-bit indices; export a coarser --level",
                            path.string(), vertices);
  }
  const std::uint64_t pos_bytes = 12 * vertices, color_bytes = has_color ? 4 * vertices : 0;
  const std::uint64_t index_bytes = 4 * 6 * quads;
  const std::uint64_t bin_bytes = 2 * pos_bytes + color_bytes + index_bytes;
  using Json = nlohmann::ordered_json;
  Json views = Json::array(), accessors = Json::array(), attributes;
  std::uint64_t offset = 0;
  auto view = [&](std::uint64_t bytes, std::uint32_t target) {
    views.push_back(
        {{"buffer", 0}, {"byteOffset", offset}, {"byteLength", bytes}, {"target", target}});
    offset += bytes;
    return views.size() - 1;
  };
  accessors.push_back({{"bufferView", view(pos_bytes, 34962)},
                       {"componentType", 5126},
                       {"count", vertices},
                       {"type", "VEC3"},
                       {"min", lo},
                       {"max", hi}});
  attributes["POSITION"] = 0;
  accessors.push_back({{"bufferView", view(pos_bytes, 34962)},
                       {"componentType", 5126},
                       {"count", vertices},
                       {"type", "VEC3"}});
  attributes["NORMAL"] = 1;
  if (has_color) {
    accessors.push_back({{"bufferView", view(color_bytes, 34962)},
                         {"componentType", 5121},
                         {"normalized", true},
                         {"count", vertices},
                         {"type", "VEC4"}});
    attributes["COLOR_0"] = 2;
  }
  accessors.push_back({{"bufferView", view(index_bytes, 34963)},
                       {"componentType", 5125},
                       {"count", 6 * quads},
                       {"type", "SCALAR"}});
  const Json gltf = {
      {"asset", {{"version", "2.0"}, {"generator", "svokit voxel mesh"}}},
      {"scene", 0},
      {"scenes", {{{"nodes", {0}}}}},
      {"nodes", {{{"mesh", 0}}}},
      {"materials",
       {{{"pbrMetallicRoughness",
          {{"baseColorFactor", {1, 1, 1, 1}}, {"metallicFactor", 0}, {"roughnessFactor", 1}}}}}},
      {"meshes",
       {{{"primitives",
          {{{"attributes", attributes},
            {"indices", accessors.size() - 1},
            {"material", 0},
            {"mode", 4}}}}}}},
      {"accessors", accessors},
      {"bufferViews", views},
      {"buffers", {{{"byteLength", bin_bytes}}}}};
  std::string json = gltf.dump();
  json.resize((json.size() + 3) / 4 * 4, ' ');
  const std::uint64_t total = 12 + 8 + json.size() + 8 + bin_bytes;
  if (total > std::numeric_limits<std::uint32_t>::max()) {
    return Status::BadInput("{}: {} bytes pass a .glb's 4 GiB; export a coarser --level",
                            path.string(), total);
  }
  AtomicFileWriter out(path);
  SVOKIT_RETURN_IF_ERROR(out.Open());
  auto put32 = [&](std::uint32_t v) { return out.Write(&v, 4); };
  SVOKIT_RETURN_IF_ERROR(out.Write("glTF", 4));
  SVOKIT_RETURN_IF_ERROR(put32(2));
  SVOKIT_RETURN_IF_ERROR(put32(static_cast<std::uint32_t>(total)));
  SVOKIT_RETURN_IF_ERROR(put32(static_cast<std::uint32_t>(json.size())));
  SVOKIT_RETURN_IF_ERROR(out.Write("JSON", 4));
  SVOKIT_RETURN_IF_ERROR(out.Write(json.data(), json.size()));
  SVOKIT_RETURN_IF_ERROR(put32(static_cast<std::uint32_t>(bin_bytes)));
  SVOKIT_RETURN_IF_ERROR(out.Write("BIN\0", 4));
  // One pass per vertex attribute: the faces are made again rather than held.
  Status status;
  std::vector<std::uint8_t> bytes;
  auto put = [&](const void* data, std::size_t size) {
    const auto* b = static_cast<const std::uint8_t*>(data);
    bytes.insert(bytes.end(), b, b + size);
  };
  for (int pass = 0; pass < (has_color ? 3 : 2); ++pass) {
    maker.ForEachChunk([&](std::span<const Quad> chunk) {
      bytes.clear();
      for (const Quad& q : chunk) {
        std::array<float, 3> normal{};
        normal[q.dir / 2] = q.dir % 2 ? 1.f : -1.f;
        for (const auto& c : Corners(q)) {
          const Vec3d p = World(voxels.grid, c);
          const std::array<float, 3> position{static_cast<float>(p.x), static_cast<float>(p.y),
                                              static_cast<float>(p.z)};
          if (pass == 0) put(position.data(), 12);
          if (pass == 1) put(normal.data(), 12);
          if (pass == 2) put(&q.color, 4);  // R in the low byte, as glTF's VEC4 order
        }
      }
      if (status.ok()) status = out.Write(bytes);
    });
    SVOKIT_RETURN_IF_ERROR(status);
  }
  std::vector<std::uint32_t> indices;
  for (std::uint64_t q = 0; q < quads;) {
    indices.clear();
    for (; q < quads && indices.size() < (1u << 20); ++q) {
      const auto v = static_cast<std::uint32_t>(4 * q);
      for (std::uint32_t k : {v, v + 1, v + 2, v, v + 2, v + 3}) indices.push_back(k);
    }
    SVOKIT_RETURN_IF_ERROR(out.Write(indices.data(), 4 * indices.size()));
  }
  stats.quads = quads;
  return out.Commit();
}

}  // namespace

std::uint64_t NaiveFaceCount(const VoxelSet& voxels) {
  VoxelMeshStats stats;
  const FaceMaker maker(voxels, std::vector<std::uint32_t>(voxels.size(), 0), false);
  maker.ForEachChunk([&](std::span<const Quad> quads) { stats.quads += quads.size(); });
  return stats.quads;
}

StatusOr<VoxelMeshStats> WriteVoxelMesh(const VoxelSet& voxels, bool merge,
                                        const std::filesystem::path& path) {
  VoxelMeshStats stats;
  const std::string ext = LowerExtension(path);
  const Status s =
      ext == "obj" ? WriteObj(voxels, merge, path, stats) : WriteGlb(voxels, merge, path, stats);
  if (!s.ok()) return s;
  return stats;
}

}  // namespace svokit
