#include "svokit/svo/page_borders.hpp"

#include <array>
#include <unordered_map>
#include <unordered_set>

#include "svokit/core/bytes.hpp"
#include "svokit/core/morton.hpp"
#include "svokit/svo/brick_math.hpp"
#include "svokit/svo/sample_filter.hpp"

namespace svokit {

namespace {

using brick_math::DecodePremultiplied;
using brick_math::Encode;
using brick_math::EncodedSample;
using brick_math::LoadSample;
using brick_math::StoreSample;

// A lattice point of one level (sample k of node n is (side − 1)·n + k), packed 21 bits an axis.
struct Point {
  std::int64_t x = 0, y = 0, z = 0;
};
std::uint64_t Pack(const Point& p) {
  return static_cast<std::uint64_t>(p.x) | static_cast<std::uint64_t>(p.y) << 21 |
         static_cast<std::uint64_t>(p.z) << 42;
}
Point Unpack(std::uint64_t v) {
  constexpr std::uint64_t kAxis = (std::uint64_t{1} << 21) - 1;
  return {static_cast<std::int64_t>(v & kAxis), static_cast<std::int64_t>(v >> 21 & kAxis),
          static_cast<std::int64_t>(v >> 42 & kAxis)};
}

// Where a page's points are, per level: its cube spans lattice points cell·edge .. (cell + 1)·edge.
struct PageFrame {
  std::uint32_t side = 0, page_level = 0, depth = 0;
  std::int64_t cell[3] = {};

  PageFrame(const SvoChunk& page, const SvoShape& shape)
      : side(shape.brick_side), page_level(page.root_level), depth(shape.depth) {
    const MortonCoord c = MortonDecode(page.root_key);
    cell[0] = c.x;
    cell[1] = c.y;
    cell[2] = c.z;
  }
  std::int64_t Edge(std::uint32_t level) const {
    return static_cast<std::int64_t>(side - 1) << (level - page_level);
  }
  // On one of the page's faces, or one lattice step inside them (and on none).
  bool OnFace(std::uint32_t level, const Point& p) const {
    const std::int64_t e = Edge(level), q[3] = {p.x, p.y, p.z};
    for (int a = 0; a < 3; ++a) {
      const std::int64_t r = q[a] - cell[a] * e;
      if (r == 0 || r == e) return true;
    }
    return false;
  }
  bool InLayer(std::uint32_t level, const Point& p) const {
    if (OnFace(level, p)) return false;
    const std::int64_t e = Edge(level), q[3] = {p.x, p.y, p.z};
    for (int a = 0; a < 3; ++a) {
      const std::int64_t r = q[a] - cell[a] * e;
      if (r == 1 || r == e - 1) return true;
    }
    return false;
  }
  // Whether the samples of the page's face points at the page level may read point p of `level`
  // (through the levels between): within the page's cube grown by what the tents between reach,
  // half the page level's lattice step less one step of `level` (side 3; a whole one for side 2).
  bool Reaches(std::uint32_t level, const Point& p) const {
    const std::int64_t e = Edge(level), grow = (side == 3 ? e / 2 : e) - 1, q[3] = {p.x, p.y, p.z};
    for (int a = 0; a < 3; ++a) {
      if (q[a] < cell[a] * e - grow || q[a] > (cell[a] + 1) * e + grow) return false;
    }
    return true;
  }
};

// Calls fn(point, stored index) for every sample the nodes of `level` of the page store.
template <class Fn>
void ForEachStoredPoint(const SvoChunk& page, std::uint32_t side, std::uint32_t level,
                        std::span<const std::uint64_t> keys, const Fn& fn) {
  const SampleLayout& layout = page.layouts[level - page.root_level];
  const layout_detail::SideTable& t = layout_detail::TableFor(side);
  const std::int64_t step = side - 1;
  for (std::size_t i = 0; i < keys.size(); ++i) {
    const MortonCoord c = MortonDecode(keys[i]);
    std::uint64_t next = layout.first[i] + t.home_count;
    for (unsigned s = 0; s < side * side * side; ++s) {
      std::uint64_t at;
      if (t.is_home[s]) {
        at = layout.first[i] + t.index[s];
      } else if (layout.orphans[i] >> t.index[s] & 1u) {
        at = next++;
      } else {
        continue;
      }
      fn(Point{step * c.x + s % side, step * c.y + s / side % side, step * c.z + s / (side * side)},
         at);
    }
  }
}

void PutValues(ByteWriter& out, const LevelSamples& v) {
  out.PutArray(std::span<const std::uint8_t>(v.opacity));
  out.PutArray(std::span<const std::uint32_t>(v.color));
  out.PutArray(std::span<const std::uint16_t>(v.normal));
}

void Append(LevelSamples& to, const LevelSamples& from, std::uint64_t at) {
  to.opacity.push_back(from.opacity[at]);
  if (!from.color.empty()) to.color.push_back(from.color[at]);
  if (!from.normal.empty()) to.normal.push_back(from.normal[at]);
}

// One level of a shell: the face points its nodes hold (with their samples at the level above the
// voxels, which the page has right) and its samples one step inside its faces.
struct ShellLevel {
  std::vector<std::uint64_t> face, layer;
  LevelSamples face_values, layer_values;
};

Status GetValues(ByteReader& in, std::size_t n, const SvoShape& shape, LevelSamples& v) {
  SVOKIT_RETURN_IF_ERROR(in.GetArray(v.opacity, n));
  SVOKIT_RETURN_IF_ERROR(in.GetArray(v.color, shape.has_color ? n : 0));
  return in.GetArray(v.normal, shape.has_normal ? n : 0);
}

// What a solid's page adds to its shell: its full leaves (per level below the page's root, their
// keys), and its surface voxels within two of its faces with their attributes (a face sample of
// the level above the voxels reads two voxels across).
struct ShellInterior {
  std::vector<std::vector<std::uint64_t>> leaves;
  std::vector<std::uint64_t> voxels;
  std::vector<HalfRgba> colors;  // per voxel (empty with a shared colour)
  std::vector<OctNormal> normals;
};
struct Shell {
  std::vector<ShellLevel> levels;
  ShellInterior interior;
};

StatusOr<Shell> DecodeShell(std::span<const std::uint8_t> bytes, const SvoShape& shape,
                            std::uint32_t page_level, const std::string& name) {
  Shell shell;
  std::vector<ShellLevel>& levels = shell.levels;
  levels.resize(shape.depth - page_level);
  if (bytes.empty()) return shell;
  ByteReader in(bytes, name);
  for (std::uint32_t l = page_level; l < shape.depth; ++l) {
    ShellLevel& level = levels[l - page_level];
    std::uint64_t faces = 0, layers = 0;
    SVOKIT_RETURN_IF_ERROR(in.Get(faces));
    SVOKIT_RETURN_IF_ERROR(in.GetArray(level.face, faces));
    if (l + 1 == shape.depth) {
      SVOKIT_RETURN_IF_ERROR(GetValues(in, level.face.size(), shape, level.face_values));
    }
    SVOKIT_RETURN_IF_ERROR(in.Get(layers));
    SVOKIT_RETURN_IF_ERROR(in.GetArray(level.layer, layers));
    SVOKIT_RETURN_IF_ERROR(GetValues(in, level.layer.size(), shape, level.layer_values));
  }
  if (shape.solid) {
    ShellInterior& interior = shell.interior;
    interior.leaves.resize(shape.depth + 1);
    for (std::uint32_t l = page_level + 1; l <= shape.depth; ++l) {
      std::uint64_t n = 0;
      SVOKIT_RETURN_IF_ERROR(in.Get(n));
      SVOKIT_RETURN_IF_ERROR(in.GetArray(interior.leaves[l], n));
    }
    std::uint64_t n = 0;
    SVOKIT_RETURN_IF_ERROR(in.Get(n));
    SVOKIT_RETURN_IF_ERROR(in.GetArray(interior.voxels, n));
    SVOKIT_RETURN_IF_ERROR(
        in.GetArray(interior.colors, shape.has_color && shape.shared_color.empty() ? n : 0));
    SVOKIT_RETURN_IF_ERROR(in.GetArray(interior.normals, shape.has_normal ? n : 0));
  }
  if (!in.at_end()) return Status::BadInput("{} has bytes after its last level", name);
  return shell;
}

// Whether a cell lies inside a solid's full leaves, around one page: the full leaves of the 27
// pages' shells, and the pages that are full leaves of the top levels themselves.
class InteriorAround {
 public:
  InteriorAround(const PageFrame& frame, std::uint32_t full_pages)
      : frame_(frame), pages_(full_pages) {
    leaves_.resize(frame.depth + 1);
  }
  void Add(const ShellInterior& interior) {
    for (std::size_t l = 0; l < interior.leaves.size(); ++l) {
      leaves_[l].insert(interior.leaves[l].begin(), interior.leaves[l].end());
    }
  }
  // Cell (x, y, z) of `level` (≥ the page level).
  bool Full(std::uint32_t level, std::int64_t x, std::int64_t y, std::int64_t z) const {
    const std::int64_t c[3] = {x, y, z};
    const std::int64_t limit = std::int64_t{1} << level;
    const int shift = static_cast<int>(level - frame_.page_level);
    int slot[3];
    for (int a = 0; a < 3; ++a) {
      if (c[a] < 0 || c[a] >= limit) return false;
      slot[a] = static_cast<int>((c[a] >> shift) - frame_.cell[a]);
      if (slot[a] < -1 || slot[a] > 1) return false;
    }
    if (pages_ >> NeighbourSlot(slot[0], slot[1], slot[2]) & 1u) return true;
    for (std::uint32_t l = level; l > frame_.page_level; --l) {
      const int up = static_cast<int>(level - l);
      if (leaves_[l].contains(MortonEncode(static_cast<std::uint32_t>(x >> up),
                                           static_cast<std::uint32_t>(y >> up),
                                           static_cast<std::uint32_t>(z >> up)))) {
        return true;
      }
    }
    return false;
  }

 private:
  const PageFrame& frame_;
  std::uint32_t pages_;
  std::vector<std::unordered_set<std::uint64_t>> leaves_;
};

// The surface voxels near the faces of the pages around one page (their shells'), by key: what
// the face samples of the level above the voxels read.
class VoxelsAround {
 public:
  void Add(const ShellInterior& interior) {
    for (std::size_t i = 0; i < interior.voxels.size(); ++i) {
      at_.emplace(interior.voxels[i], Voxel{&interior, i});
    }
  }
  // Voxel (x, y, z) premultiplied (VoxelCell), or null where there is none.
  const PremultipliedSample* Cell(const SvoShape& shape, std::int64_t x, std::int64_t y,
                                  std::int64_t z, PremultipliedSample& out) const {
    const std::int64_t limit = std::int64_t{1} << shape.depth;
    if (x < 0 || y < 0 || z < 0 || x >= limit || y >= limit || z >= limit) return nullptr;
    const auto it =
        at_.find(MortonEncode(static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(y),
                              static_cast<std::uint32_t>(z)));
    if (it == at_.end()) return nullptr;
    const ShellInterior& from = *it->second.interior;
    VoxelSamplesSource source;
    if (shape.has_color) {
      source.colors = from.colors.empty() ? std::span<const HalfRgba>(shape.shared_color)
                                          : std::span<const HalfRgba>(from.colors);
    }
    if (shape.has_normal) source.normals = from.normals;
    out = brick_math::VoxelCell(source, it->second.index, shape.has_color, shape.has_normal);
    return &out;
  }

 private:
  struct Voxel {
    const ShellInterior* interior;
    std::size_t index;
  };
  std::unordered_map<std::uint64_t, Voxel> at_;
};

// A solid page's ShellInterior: its voxels within two voxels of its faces and its full leaves
// within one of their own size, all the face samples read of it (a tap lies within one step of a
// face, and with side 2 its reach spans two cells of its level on each side).
void PutInterior(ByteWriter& out, const SvoChunk& page, const SvoShape& shape,
                 const PageFrame& frame, const std::vector<std::vector<std::uint64_t>>& keys) {
  const std::int64_t edge = std::int64_t{1} << (shape.depth - page.root_level);
  // Whether the cube of `size` voxels at c (in its level's units) comes within 2·size of a face.
  const auto near_faces = [&](const MortonCoord& c, std::int64_t size) {
    const std::int64_t v[3] = {c.x, c.y, c.z};
    for (int a = 0; a < 3; ++a) {
      const std::int64_t r = v[a] * size - frame.cell[a] * edge;
      if (r < 2 * size || r + size > edge - 2 * size) return true;
    }
    return false;
  };
  for (std::uint32_t l = page.root_level + 1; l <= shape.depth; ++l) {
    std::vector<std::uint64_t> leaves;
    const std::size_t k = l - 1 - page.root_level;
    const std::int64_t size = std::int64_t{1} << (shape.depth - l);
    for (std::size_t i = 0; i < keys[k].size(); ++i) {
      for (unsigned c = 0; c < 8; ++c) {
        const std::uint64_t leaf = keys[k][i] << 3 | c;
        if ((page.tree.full[k][i] >> c & 1u) && near_faces(MortonDecode(leaf), size)) {
          leaves.push_back(leaf);
        }
      }
    }
    out.Put(static_cast<std::uint64_t>(leaves.size()));
    out.PutArray(std::span<const std::uint64_t>(leaves));
  }
  const std::vector<std::uint64_t> voxels = ChunkVoxelKeys(page);
  std::vector<std::uint64_t> near;
  std::vector<HalfRgba> colors;
  std::vector<OctNormal> normals;
  for (std::size_t i = 0; i < voxels.size(); ++i) {
    if (!near_faces(MortonDecode(voxels[i]), 1)) continue;
    near.push_back(voxels[i]);
    if (!page.colors.empty()) colors.push_back(page.colors[i]);
    if (shape.has_normal) normals.push_back(page.normals[i]);
  }
  out.Put(static_cast<std::uint64_t>(near.size()));
  out.PutArray(std::span<const std::uint64_t>(near));
  out.PutArray(std::span<const HalfRgba>(colors));
  out.PutArray(std::span<const OctNormal>(normals));
}

}  // namespace

std::vector<std::uint8_t> EncodePageShell(const SvoChunk& page, const SvoShape& shape) {
  const PageFrame frame(page, shape);
  ByteWriter out;
  if (shape.brick_side == 0 || page.layouts.empty()) return {};
  const auto keys = TreeLevelKeys(page.tree, page.root_key, shape.depth - 1);
  for (std::uint32_t l = page.root_level; l < shape.depth; ++l) {
    const std::size_t k = l - page.root_level;
    ShellLevel level;
    const LevelSamples& samples = page.samples[k];
    const bool values = l + 1 == shape.depth;
    ForEachStoredPoint(page, shape.brick_side, l, keys[k], [&](const Point& p, std::uint64_t at) {
      if (frame.OnFace(l, p)) {
        level.face.push_back(Pack(p));
        if (values) Append(level.face_values, samples, at);
      } else if (l > page.root_level && frame.InLayer(l, p)) {
        level.layer.push_back(Pack(p));
        Append(level.layer_values, samples, at);
      }
    });
    out.Put(static_cast<std::uint64_t>(level.face.size()));
    out.PutArray(std::span<const std::uint64_t>(level.face));
    if (values) PutValues(out, level.face_values);
    out.Put(static_cast<std::uint64_t>(level.layer.size()));
    out.PutArray(std::span<const std::uint64_t>(level.layer));
    PutValues(out, level.layer_values);
  }
  if (shape.solid) PutInterior(out, page, shape, frame, keys);
  return std::move(out.bytes());
}

Status PatchPageFaces(SvoChunk& page, const SvoShape& shape,
                      std::span<const std::span<const std::uint8_t>> shells,
                      const std::string& name, std::uint32_t full_pages) {
  const std::uint32_t side = shape.brick_side, depth = shape.depth, top = page.root_level;
  if (side == 0 || depth < top + 2) return Status::Ok();
  const PageFrame frame(page, shape);
  std::vector<Shell> around;
  for (const std::span<const std::uint8_t> bytes : shells) {
    if (bytes.empty()) continue;
    StatusOr<Shell> shell = DecodeShell(bytes, shape, top, name + ": a neighbour's shell");
    if (!shell.ok()) return shell.status();
    around.push_back(std::move(*shell));
  }
  const bool color = shape.has_color, normal = shape.has_normal, solid = shape.solid;
  InteriorAround interior(frame, full_pages);
  VoxelsAround voxels;
  for (const Shell& shell : around) {
    interior.Add(shell.interior);
    voxels.Add(shell.interior);
  }
  // The samples of one level the next level up reads: on faces (computed, or given at the level
  // above the voxels) and one step inside them (given).
  std::unordered_map<std::uint64_t, EncodedSample> known;
  const auto add_given = [&](std::uint32_t l, bool faces) {
    for (const Shell& shell : around) {
      const ShellLevel& level = shell.levels[l - top];
      if (faces) {
        for (std::size_t i = 0; i < level.face.size(); ++i) {
          known.emplace(level.face[i], LoadSample(level.face_values, i));
        }
      }
      for (std::size_t i = 0; i < level.layer.size(); ++i) {
        known.emplace(level.layer[i], LoadSample(level.layer_values, i));
      }
    }
  };
  const auto keys = TreeLevelKeys(page.tree, page.root_key, depth - 1);
  // Stores the computed samples of the page's own face points of level l.
  const auto store = [&](std::uint32_t l,
                         const std::unordered_map<std::uint64_t, EncodedSample>& computed) {
    Status missing;
    LevelSamples& samples = page.samples[l - top];
    ForEachStoredPoint(page, side, l, keys[l - top], [&](const Point& p, std::uint64_t at) {
      if (!frame.OnFace(l, p)) return;
      const auto it = computed.find(Pack(p));
      if (it == computed.end()) {
        missing = Status::BadInput("{}: its shell does not hold a point of its faces", name);
        return;
      }
      StoreSample(it->second, at, samples);
    });
    return missing;
  };
  if (solid) {
    // A solid's face samples above the voxels read the interior across the faces: computed here
    // from the voxels near the faces and the full leaves around, as FilterSamples computes them.
    std::unordered_map<std::uint64_t, EncodedSample> computed;
    const std::int64_t step = side == 3 ? 1 : 2;
    for (const Shell& shell : around) {
      for (const std::uint64_t packed : shell.levels[depth - 1 - top].face) {
        if (computed.contains(packed)) continue;
        const Point q = Unpack(packed);
        const std::int64_t p[3] = {step * q.x, step * q.y, step * q.z};  // a voxel corner
        PremultipliedSample cells[64];
        const auto cell = [&](int dx, int dy, int dz) {
          return voxels.Cell(shape, p[0] + dx, p[1] + dy, p[2] + dz,
                             cells[(dx + 2) + 4 * ((dy + 2) + 4 * (dz + 2))]);
        };
        const auto filled = [&](int dx, int dy, int dz) {
          const std::int64_t x = p[0] + dx, y = p[1] + dy, z = p[2] + dz;
          PremultipliedSample unused;
          return voxels.Cell(shape, x, y, z, unused) != nullptr || interior.Full(depth, x, y, z);
        };
        const PremultipliedSample sum = brick_math::AboveVoxels(side, cell);
        const float opacity = side == 3 ? brick_math::AboveVoxelsOpacity<3>(filled)
                                        : brick_math::AboveVoxelsOpacity<2>(filled);
        computed.emplace(packed, Encode(color, normal, sum, opacity));
      }
    }
    SVOKIT_RETURN_IF_ERROR(store(depth - 1, computed));
    known = std::move(computed);
    add_given(depth - 1, false);
  } else {
    add_given(depth - 1, true);
  }
  for (std::uint32_t l = depth - 1; l-- > top;) {
    std::unordered_map<std::uint64_t, EncodedSample> computed;
    for (const Shell& shell : around) {
      for (const std::uint64_t packed : shell.levels[l - top].face) {
        const Point q = Unpack(packed);
        if (!frame.Reaches(l, q) || computed.contains(packed)) continue;
        // The tent over the finer points 2q + d − 1, as the filter reads them: decoded, zero
        // where no node holds the point, and in a solid the interior's opacity there.
        std::array<PremultipliedSample, 27> taps, opacities;
        bool differs = false;
        for (int d = 0; d < 27; ++d) {
          const Point t{2 * q.x + d % 3 - 1, 2 * q.y + d / 3 % 3 - 1, 2 * q.z + d / 9 - 1};
          const auto it = known.find(Pack(t));
          taps[d] = opacities[d] = PremultipliedSample{};
          if (it != known.end() && it->second.opacity != 0) {
            const PremultipliedSample v = DecodePremultiplied(it->second, color, normal);
            taps[d] = solid ? brick_math::ColourWeighted(v, it->second, color) : v;
            opacities[d].opacity = v.opacity;
          } else if (solid && it == known.end()) {
            const std::int64_t at[3] = {t.x, t.y, t.z};
            const unsigned octants = brick_math::FullOctants(
                side, at, [&](std::int64_t x, std::int64_t y, std::int64_t z) {
                  return interior.Full(l + 1, x, y, z);
                });
            if (octants != 0) {
              opacities[d].opacity =
                  DecodeUnorm8(brick_math::FullOctantsOpacity(depth - (l + 1), octants));
            }
          }
          differs = differs || taps[d].opacity != opacities[d].opacity;
        }
        const auto tent = [](const std::array<PremultipliedSample, 27>& from) {
          return brick_math::Tent([&](int x, int y, int z) -> const PremultipliedSample& {
            return from[static_cast<std::size_t>(x + 3 * y + 9 * z)];
          });
        };
        const PremultipliedSample weighted = tent(taps);
        computed.emplace(packed, Encode(color, normal, weighted,
                                        differs ? tent(opacities).opacity : weighted.opacity));
      }
    }
    SVOKIT_RETURN_IF_ERROR(store(l, computed));
    known = std::move(computed);
    if (l > top) add_given(l, false);
  }
  return Status::Ok();
}

LevelSamples RootBrick(const SvoChunk& page, std::uint32_t side) {
  Neighbourhood alone;
  alone.fill(-1);
  alone[NeighbourSlot(0, 0, 0)] = 0;
  const LevelSamples& samples = page.samples.front();
  LevelSamples brick;
  for (unsigned s = 0; s < side * side * side; ++s) {
    Append(brick, samples, SampleIndex(page.layouts.front(), alone, s));
  }
  return brick;
}

void FilterTopSamples(SvoChunk& top, std::uint32_t side, std::uint32_t depth,
                      const LevelSamples& root_bricks) {
  const std::uint32_t pages = top.tree.last_level(), n = side * side * side;
  std::vector<SampleLayout> layouts;
  for (std::uint32_t l = 0; l <= pages; ++l) layouts.push_back(LayOutSamples(top.tree, l, side));
  LevelSamples last;
  const std::uint64_t size = layouts.back().size();
  last.opacity.resize(size);
  last.color.resize(root_bricks.color.empty() ? 0 : size);
  last.normal.resize(root_bricks.normal.empty() ? 0 : size);
  const layout_detail::SideTable& t = layout_detail::TableFor(side);
  ForEachNeighbourhood(top.tree, pages, [&](std::uint64_t i, const Neighbourhood& nb) {
    for (unsigned s = 0; s < n; ++s) {
      // Only the samples the page's root stores: a point shared with another page is written once.
      if (!t.is_home[s] && !(layouts.back().orphans[i] >> t.index[s] & 1u)) continue;
      StoreSample(LoadSample(root_bricks, i * n + s), SampleIndex(layouts.back(), nb, s), last);
    }
  });
  top.samples = FilterSamplesAbove(top.tree, layouts, side, depth, std::move(last));
  layouts.pop_back();
  top.layouts = std::move(layouts);
}

}  // namespace svokit
