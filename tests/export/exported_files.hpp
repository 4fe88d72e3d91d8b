#pragma once
// Exports of an octree read back by small parsers written here from the formats' specs, sharing
// no code with the writers: binvox and MagicaVoxel .vox, for the surface and the solid tests.

#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "svokit/export/export.hpp"
#include "tests/test_util.hpp"

namespace svokit::test {

using Coord = std::array<std::int64_t, 3>;

/// `svo` exported to `path` (its format by the extension), at `level` or the voxels'.
inline Status Export(const Svo& svo, const std::filesystem::path& path,
                     std::optional<std::uint32_t> level = std::nullopt) {
  ExportOptions options;
  options.level = level;
  return ExportSvo(svo, path, options);
}

struct Binvox {
  std::int64_t dim = 0;
  Vec3d translate;
  double scale = 0;
  std::set<Coord> voxels;
};

// http://www.patrickmin.com/binvox/binvox.html: text header, then (value, count) byte pairs over
// the dim³ cube with y running fastest, then z, then x.
inline Binvox ReadBinvox(const std::filesystem::path& path) {
  const std::string bytes = ReadText(path);
  std::istringstream in(bytes);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "#binvox 1");
  Binvox b;
  while (std::getline(in, line) && line != "data") {
    std::istringstream words(line);
    std::string key;
    words >> key;
    if (key == "dim") {
      std::int64_t d1 = 0, d2 = 0, d3 = 0;
      words >> d1 >> d2 >> d3;
      EXPECT_TRUE(d1 == d2 && d2 == d3) << line;
      b.dim = d1;
    } else if (key == "translate") {
      words >> b.translate.x >> b.translate.y >> b.translate.z;
    } else if (key == "scale") {
      words >> b.scale;
    }
  }
  EXPECT_EQ(line, "data");
  std::size_t pos = static_cast<std::size_t>(in.tellg());
  const std::int64_t total = b.dim * b.dim * b.dim;
  std::int64_t index = 0;
  for (; pos + 1 < bytes.size(); pos += 2) {
    const auto value = static_cast<std::uint8_t>(bytes[pos]);
    const auto count = static_cast<std::uint8_t>(bytes[pos + 1]);
    EXPECT_TRUE(value <= 1 && count > 0) << "pair at byte " << pos;
    for (int k = 0; k < count && value == 1; ++k) {
      const std::int64_t i = index + k;
      b.voxels.insert({i / (b.dim * b.dim), i % b.dim, i / b.dim % b.dim});  // x, y, z
    }
    index += count;
  }
  EXPECT_EQ(pos, bytes.size());
  EXPECT_EQ(index, total);
  return b;
}

// MagicaVoxel .vox (github.com/ephtracy/voxel-model): chunks inside MAIN; models SIZE + XYZI;
// scene graph nTRN → nGRP → nTRN → nSHP; a model voxel v lands at _t + v − floor(size / 2).
struct VoxFile {
  std::vector<std::array<std::int32_t, 3>> sizes;  ///< per model
  std::map<Coord, std::uint8_t> voxels;            ///< world voxel → palette index
  std::array<std::uint32_t, 257> palette{};        ///< palette index → RGBA

  std::uint32_t ColorAt(const Coord& voxel) const { return palette[voxels.at(voxel)]; }
  std::set<std::uint32_t> UsedIndices() const {
    std::set<std::uint32_t> used;
    for (const auto& [voxel, index] : voxels) used.insert(index);
    return used;
  }
};

/// Faces between a voxel of `filled` and a cell that is not in it: a closed surface's area.
inline std::uint64_t BoundaryFaces(const std::set<Coord>& filled) {
  std::uint64_t faces = 0;
  for (const Coord& c : filled) {
    for (int a = 0; a < 3; ++a) {
      for (const int step : {-1, 1}) {
        Coord n = c;
        n[a] += step;
        faces += filled.count(n) ? 0 : 1;
      }
    }
  }
  return faces;
}

/// Little-endian values read one after another from a file's bytes.
class Bytes {
 public:
  explicit Bytes(std::string bytes) : bytes_(std::move(bytes)) {}
  template <class T>
  T Get() {
    T v{};
    if (pos_ + sizeof(T) > bytes_.size()) throw std::runtime_error("vox: truncated");
    std::memcpy(&v, bytes_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return v;
  }
  std::string Text(std::size_t n) {
    if (pos_ + n > bytes_.size()) throw std::runtime_error("vox: truncated");
    std::string s = bytes_.substr(pos_, n);
    pos_ += n;
    return s;
  }
  std::string String() { return Text(static_cast<std::size_t>(Get<std::int32_t>())); }
  std::map<std::string, std::string> Dict() {
    std::map<std::string, std::string> d;
    for (std::int32_t n = Get<std::int32_t>(); n > 0; --n) {
      std::string key = String();
      d[key] = String();
    }
    return d;
  }
  std::size_t pos() const { return pos_; }
  std::size_t size() const { return bytes_.size(); }

 private:
  std::string bytes_;
  std::size_t pos_ = 0;
};

inline VoxFile ReadVox(const std::filesystem::path& path) {
  Bytes in(ReadText(path));
  EXPECT_EQ(in.Text(4), "VOX ");
  EXPECT_EQ(in.Get<std::int32_t>(), 150);
  EXPECT_EQ(in.Text(4), "MAIN");
  EXPECT_EQ(in.Get<std::int32_t>(), 0);
  const auto children = static_cast<std::size_t>(in.Get<std::int32_t>());
  EXPECT_EQ(children, in.size() - in.pos());
  struct Model {
    std::array<std::int32_t, 3> size;
    std::vector<std::array<std::uint8_t, 4>> xyzi;
  };
  std::vector<Model> models;
  struct Transform {
    std::int32_t child;
    Coord t;
  };
  std::map<std::int32_t, Transform> transforms;
  std::map<std::int32_t, std::vector<std::int32_t>> groups;
  std::map<std::int32_t, std::int32_t> shapes;
  VoxFile file;
  while (in.pos() < in.size()) {
    const std::string id = in.Text(4);
    const auto content = static_cast<std::size_t>(in.Get<std::int32_t>());
    EXPECT_EQ(in.Get<std::int32_t>(), 0) << id;
    const std::size_t end = in.pos() + content;
    if (id == "SIZE") {
      Model m;
      for (std::int32_t& s : m.size) s = in.Get<std::int32_t>();
      models.push_back(m);
    } else if (id == "XYZI") {
      for (std::int32_t n = in.Get<std::int32_t>(); n > 0; --n) {
        models.back().xyzi.push_back(in.Get<std::array<std::uint8_t, 4>>());
      }
    } else if (id == "nTRN") {
      const auto node = in.Get<std::int32_t>();
      in.Dict();
      Transform t{in.Get<std::int32_t>(), {0, 0, 0}};
      in.Get<std::int32_t>();  // reserved
      in.Get<std::int32_t>();  // layer
      EXPECT_EQ(in.Get<std::int32_t>(), 1);
      const auto frame = in.Dict();
      if (frame.count("_t")) {
        std::istringstream(frame.at("_t")) >> t.t[0] >> t.t[1] >> t.t[2];
      }
      transforms[node] = t;
    } else if (id == "nGRP") {
      const auto node = in.Get<std::int32_t>();
      in.Dict();
      for (std::int32_t n = in.Get<std::int32_t>(); n > 0; --n) {
        groups[node].push_back(in.Get<std::int32_t>());
      }
    } else if (id == "nSHP") {
      const auto node = in.Get<std::int32_t>();
      in.Dict();
      EXPECT_EQ(in.Get<std::int32_t>(), 1);
      shapes[node] = in.Get<std::int32_t>();
      in.Dict();
    } else if (id == "RGBA") {
      for (std::size_t k = 1; k <= 256; ++k) file.palette[k] = in.Get<std::uint32_t>();
    } else {
      in.Text(content);  // LAYR, MATL, …: not needed here
    }
    EXPECT_EQ(in.pos(), end) << id;
  }

  for (const Model& m : models) file.sizes.push_back(m.size);
  std::function<void(std::int32_t, Coord)> visit = [&](std::int32_t node, Coord offset) {
    if (transforms.count(node)) {
      const Transform& t = transforms.at(node);
      visit(t.child, {offset[0] + t.t[0], offset[1] + t.t[1], offset[2] + t.t[2]});
    } else if (groups.count(node)) {
      for (std::int32_t child : groups.at(node)) visit(child, offset);
    } else {
      const Model& m = models.at(static_cast<std::size_t>(shapes.at(node)));
      for (const auto& v : m.xyzi) {
        Coord world{};
        for (int a = 0; a < 3; ++a) {
          EXPECT_LT(v[a], m.size[a]) << "voxel outside its model";
          world[a] = offset[a] + v[a] - m.size[a] / 2;
        }
        EXPECT_NE(v[3], 0);
        EXPECT_TRUE(file.voxels.emplace(world, v[3]).second) << "voxel twice";
      }
    }
  };
  visit(0, {0, 0, 0});
  return file;
}

/// `vox` with its voxels in svokit's frame: a .vox is z-up, svokit's grid y-up, so a voxel at
/// (x, y, z) of a grid of `dims` is written at (x, dims.z − 1 − z, y) (formats: docs/tools).
inline VoxFile InSvokitFrame(VoxFile vox, const std::array<std::uint32_t, 3>& dims) {
  std::map<Coord, std::uint8_t> voxels;
  for (const auto& [c, index] : vox.voxels) {
    voxels[{c[0], c[2], static_cast<std::int64_t>(dims[2]) - 1 - c[1]}] = index;
  }
  vox.voxels = std::move(voxels);
  return vox;
}

}  // namespace svokit::test
