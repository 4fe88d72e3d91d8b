// The brick filter's reference ("filter 2"), from its definition (filter_reference.hpp) and the
// sample codecs alone. Every product that is then added goes through a volatile, so no compiler
// setting can fuse it into an FMA: the sums are exactly the IEEE ones the definition spells out.

#include "tests/svo/filter_reference.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <sstream>
#include <string>
#include <unordered_map>
#include <vector>

#include "svokit/core/grid_transform.hpp"
#include "svokit/core/half.hpp"
#include "svokit/core/octahedral.hpp"
#include "svokit/svo/sample_codec.hpp"

namespace svokit::test {
namespace {

// a·b rounded once, never fused with what it is added to.
float Mul(float a, float b) {
  volatile float p = a * b;
  return p;
}
double Mul(double a, double b) {
  volatile double p = a * b;
  return p;
}

constexpr int kAxisBits = 21;
constexpr std::int64_t kAxisLimit = std::int64_t{1} << kAxisBits;

bool Packable(const Vec3i& p) {
  return p.x >= 0 && p.y >= 0 && p.z >= 0 && p.x < kAxisLimit && p.y < kAxisLimit &&
         p.z < kAxisLimit;
}
std::uint64_t Pack(const Vec3i& p) {
  return static_cast<std::uint64_t>(p.x) | static_cast<std::uint64_t>(p.y) << kAxisBits |
         static_cast<std::uint64_t>(p.z) << (2 * kAxisBits);
}

// Position (half voxels) of brick sample k of node `c` of `level`: c·S + k·S/(s − 1) voxels,
// S = 2^(depth − level).
Vec3i SamplePosition(std::uint32_t depth, std::uint32_t side, std::uint32_t level,
                     const MortonCoord& c, std::uint32_t kx, std::uint32_t ky, std::uint32_t kz) {
  const std::int64_t size2 = std::int64_t{2} << (depth - level);  // node size in half voxels
  const std::int64_t step = size2 / (side - 1);
  return {c.x * size2 + kx * step, c.y * size2 + ky * step, c.z * size2 + kz * step};
}

std::string Hex(std::uint64_t v) {
  std::ostringstream out;
  out << "0x" << std::hex << v;
  return out.str();
}

FilterSample StoredSample(const Svo& svo, std::uint32_t level, std::uint64_t node,
                          std::uint32_t sample) {
  const SvoLevel& lv = svo.levels[level];
  const std::size_t at = node * svo.brick_samples() + sample;
  FilterSample s;
  s.opacity = lv.opacity[at];
  if (svo.has_color) s.color = lv.color[at];
  if (svo.has_normal) s.normal = lv.normal[at];
  return s;
}

std::string NodeText(std::uint32_t level, std::uint64_t key, std::uint32_t sample,
                     std::uint32_t side) {
  const MortonCoord c = MortonDecode(key);
  std::ostringstream out;
  out << "level " << level << " node " << Hex(key) << " (" << c.x << ", " << c.y << ", " << c.z
      << ") sample " << sample << " (" << sample % side << ", " << sample / side % side << ", "
      << sample / (side * side) << ")";
  return out.str();
}

std::string PositionText(const Vec3i& p) {  // half voxels, shown in voxels
  std::ostringstream out;
  out << "voxel position (" << static_cast<double>(p.x) / 2 << ", " << static_cast<double>(p.y) / 2
      << ", " << static_cast<double>(p.z) / 2 << ")";
  return out.str();
}

}  // namespace

std::string ToString(const FilterSample& s) {
  std::ostringstream out;
  out << "o=" << int{s.opacity} << " c=" << Hex(s.color) << " n=" << Hex(s.normal);
  return out.str();
}

FilterVoxels FilterVoxelsOf(const VoxelSet& voxels, std::uint32_t side) {
  FilterVoxels in;
  in.depth = OctreeDepth(voxels.grid);
  in.side = side;
  in.has_color = voxels.has_colors();
  in.has_normal = voxels.has_normals();
  in.keys.assign(voxels.keys.begin(), voxels.keys.end());
  for (std::size_t i = 0; i < voxels.size(); ++i) {
    if (in.has_color) in.colors.push_back(static_cast<Rgba>(voxels.color(i)));
    if (in.has_normal) in.normals.push_back(static_cast<Vec3f>(voxels.normals[i]));
  }
  return in;
}

FilterReference::FilterReference(const FilterVoxels& in)
    : depth_(in.depth),
      side_(in.side),
      has_color_(in.has_color),
      has_normal_(in.has_normal),
      voxel_keys_(in.keys),
      colors_(in.colors),
      normals_(in.normals) {
  for (std::size_t i = 0; i < voxel_keys_.size(); ++i) voxel_index_.emplace(voxel_keys_[i], i);
  // Nodes of level L: the voxel keys >> 3(D − L), deduplicated.
  keys_.resize(depth_ + 1);
  for (std::uint32_t level = 0; level <= depth_; ++level) {
    std::vector<std::uint64_t>& keys = keys_[level];
    for (const std::uint64_t key : voxel_keys_) keys.push_back(key >> (3 * (depth_ - level)));
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  }
  // Level by level from the voxels up: each lattice point of an existing brick, once.
  samples_.resize(depth_ + 1);
  for (std::uint32_t level = depth_ + 1; level-- > 0;) {
    for (const std::uint64_t key : keys_[level]) {
      const MortonCoord c = MortonDecode(key);
      for (std::uint32_t kz = 0; kz < side_; ++kz) {
        for (std::uint32_t ky = 0; ky < side_; ++ky) {
          for (std::uint32_t kx = 0; kx < side_; ++kx) {
            const Vec3i p = Position(level, c, kx, ky, kz);
            const std::uint64_t packed = Pack(p);
            if (samples_[level].count(packed)) continue;
            FilterSample s;
            if (level == depth_) {
              s = VoxelLevelSample(p);
            } else if (level + 1 == depth_) {
              s = AboveVoxelsSample({p.x / 2, p.y / 2, p.z / 2});  // integer voxels here
            } else {
              s = TentSample(level, p);
            }
            samples_[level].emplace(packed, s);
          }
        }
      }
    }
  }
}

Vec3i FilterReference::Position(std::uint32_t level, const MortonCoord& node, std::uint32_t kx,
                                std::uint32_t ky, std::uint32_t kz) const {
  return SamplePosition(depth_, side_, level, node, kx, ky, kz);
}

FilterSample FilterReference::Sample(std::uint32_t level, std::uint64_t key,
                                     std::uint32_t sample) const {
  const Vec3i p = Position(level, MortonDecode(key), sample % side_, sample / side_ % side_,
                           sample / (side_ * side_));
  const FilterSample* s = Find(level, p);
  return s ? *s : FilterSample{};
}

const FilterSample* FilterReference::Find(std::uint32_t level, const Vec3i& position) const {
  if (level > depth_ || !Packable(position)) return nullptr;
  const auto it = samples_[level].find(Pack(position));
  return it == samples_[level].end() ? nullptr : &it->second;
}

std::int64_t FilterReference::VoxelAt(std::int64_t x, std::int64_t y, std::int64_t z) const {
  const std::int64_t n = std::int64_t{1} << depth_;
  if (x < 0 || y < 0 || z < 0 || x >= n || y >= n || z >= n) return -1;
  const auto it = voxel_index_.find(MortonEncode(
      static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(y), static_cast<std::uint32_t>(z)));
  return it == voxel_index_.end() ? -1 : static_cast<std::int64_t>(it->second);
}

FilterSample FilterReference::Encode(const Channels& v) const {
  FilterSample s;
  s.opacity = EncodeUnorm8(v[0]);
  if (s.opacity == 0) return {};
  const float inv = 1.f / v[0];
  if (has_color_) {
    s.color = EncodeColor(Rgba{v[1] * inv, v[2] * inv, v[3] * inv, v[4] * inv});
  }
  if (has_normal_) {
    const float xx = Mul(v[5], v[5]), yy = Mul(v[6], v[6]), zz = Mul(v[7], v[7]);
    const float xy = xx + yy;
    const float len = std::sqrt(xy + zz);
    s.normal =
        len > 1e-12f ? EncodeNormal(Vec3f{v[5] / len, v[6] / len, v[7] / len}) : std::uint16_t{0};
  }
  return s;
}

// Level D: the m voxel cells whose closed cube holds the point, summed in z, y, x order over the
// present ones, times 1/m.
FilterSample FilterReference::VoxelLevelSample(const Vec3i& half) const {
  std::array<std::vector<std::int64_t>, 3> cells;
  for (int a = 0; a < 3; ++a) {
    const std::int64_t h = half[a];
    if (h % 2 != 0) {
      cells[a] = {(h - 1) / 2};  // a voxel's centre plane: that voxel alone
    } else {
      cells[a] = {h / 2 - 1, h / 2};  // a voxel boundary: the voxels on both sides
    }
  }
  const std::size_t m = cells[0].size() * cells[1].size() * cells[2].size();
  Channels sum{};  // +0
  for (const std::int64_t z : cells[2]) {
    for (const std::int64_t y : cells[1]) {
      for (const std::int64_t x : cells[0]) {
        const std::int64_t i = VoxelAt(x, y, z);
        if (i < 0) continue;
        const auto v = static_cast<std::size_t>(i);
        sum[0] = sum[0] + 1.f;
        if (has_color_) {
          const Rgba& c = colors_[v];
          sum[1] = sum[1] + c.r;
          sum[2] = sum[2] + c.g;
          sum[3] = sum[3] + c.b;
          sum[4] = sum[4] + c.a;
        }
        if (has_normal_) {
          const Vec3f& n = normals_[v];
          sum[5] = sum[5] + n.x;
          sum[6] = sum[6] + n.y;
          sum[7] = sum[7] + n.z;
        }
      }
    }
  }
  const float inv_m = 1.f / static_cast<float>(m);
  Channels mean;
  for (std::size_t ch = 0; ch < mean.size(); ++ch) mean[ch] = sum[ch] * inv_m;
  return Encode(mean);
}

// Level D − 1 at integer voxel point p: separable binary64 sums over the cells around p.
FilterSample FilterReference::AboveVoxelsSample(const Vec3i& p) const {
  const bool three = side_ == 3;
  static constexpr double kBox[2] = {1, 1};
  static constexpr double kCubic[4] = {1, 3, 3, 1};
  const double* w = three ? kBox : kCubic;
  const int taps = three ? 2 : 4;
  const std::int64_t first = three ? -1 : -2;  // cells p − 1, p or p − 2 … p + 1
  const double scale = three ? 0x1p-3 : 0x1p-9;
  // q per cell and channel: a, c·a, n·a (a = 1 for a voxel, 0 for an absent cell).
  const auto q = [&](std::int64_t x, std::int64_t y, std::int64_t z, std::size_t ch) -> double {
    const std::int64_t i = VoxelAt(x, y, z);
    if (i < 0) return 0.0;
    const auto v = static_cast<std::size_t>(i);
    switch (ch) {
      case 0:
        return 1.0;
      case 1:
        return has_color_ ? static_cast<double>(colors_[v].r) : 0.0;
      case 2:
        return has_color_ ? static_cast<double>(colors_[v].g) : 0.0;
      case 3:
        return has_color_ ? static_cast<double>(colors_[v].b) : 0.0;
      case 4:
        return has_color_ ? static_cast<double>(colors_[v].a) : 0.0;
      case 5:
        return has_normal_ ? static_cast<double>(normals_[v].x) : 0.0;
      case 6:
        return has_normal_ ? static_cast<double>(normals_[v].y) : 0.0;
      default:
        return has_normal_ ? static_cast<double>(normals_[v].z) : 0.0;
    }
  };
  Channels result;
  for (std::size_t ch = 0; ch < result.size(); ++ch) {
    double s = 0.0;  // S = Σₖ wₖ·Y(zₖ)
    for (int k = 0; k < taps; ++k) {
      const std::int64_t z = p.z + first + k;
      double y_sum = 0.0;  // Y(z) = Σⱼ wⱼ·X(yⱼ, z)
      for (int j = 0; j < taps; ++j) {
        const std::int64_t y = p.y + first + j;
        double x_sum = 0.0;  // X(y, z) = Σᵢ wᵢ·q(xᵢ, y, z)
        for (int i = 0; i < taps; ++i) x_sum = x_sum + Mul(w[i], q(p.x + first + i, y, z, ch));
        y_sum = y_sum + Mul(w[j], x_sum);
      }
      s = s + Mul(w[k], y_sum);
    }
    result[ch] = static_cast<float>(s * scale);
  }
  return Encode(result);
}

// Level L < D − 1: the [¼ ½ ¼] tent over level L + 1's stored samples at ± the finer spacing.
FilterSample FilterReference::TentSample(std::uint32_t level, const Vec3i& half) const {
  static constexpr float kTent[3] = {0.25f, 0.5f, 0.25f};
  // Finer spacing 2^(D−L−1)/(s − 1) voxels, in half voxels.
  const std::int64_t h = (std::int64_t{2} << (depth_ - level - 1)) / (side_ - 1);
  // tap[z][y][x]: the finer sample at half + (x − 1, y − 1, z − 1)·h, decoded, premultiplied.
  std::array<std::array<std::array<Channels, 3>, 3>, 3> tap{};
  for (int dz = 0; dz < 3; ++dz) {
    for (int dy = 0; dy < 3; ++dy) {
      for (int dx = 0; dx < 3; ++dx) {
        Channels& t = tap[dz][dy][dx];
        t.fill(0.f);
        const FilterSample* f =
            Find(level + 1, {half.x + (dx - 1) * h, half.y + (dy - 1) * h, half.z + (dz - 1) * h});
        if (!f || f->opacity == 0) continue;
        const float o = DecodeUnorm8(f->opacity);
        t[0] = o;
        if (has_color_) {
          const Rgba c = DecodeColor(f->color);
          t[1] = Mul(c.r, o);
          t[2] = Mul(c.g, o);
          t[3] = Mul(c.b, o);
          t[4] = Mul(c.a, o);
        }
        if (has_normal_) {
          const Vec3f n = DecodeNormal(f->normal);
          t[5] = Mul(n.x, o);
          t[6] = Mul(n.y, o);
          t[7] = Mul(n.z, o);
        }
      }
    }
  }
  Channels result;
  for (std::size_t ch = 0; ch < result.size(); ++ch) {
    float fy[3];
    for (int z = 0; z < 3; ++z) {
      float fx[3];
      for (int y = 0; y < 3; ++y) {
        fx[y] = 0.f;
        for (int x = 0; x < 3; ++x) fx[y] = fx[y] + Mul(kTent[x], tap[z][y][x][ch]);
      }
      fy[z] = 0.f;
      for (int y = 0; y < 3; ++y) fy[z] = fy[z] + Mul(kTent[y], fx[y]);
    }
    float o = 0.f;
    for (int z = 0; z < 3; ++z) o = o + Mul(kTent[z], fy[z]);
    result[ch] = o;
  }
  return Encode(result);
}

std::string CompareWithReference(const Svo& svo, const FilterReference& ref, int max_reports) {
  std::ostringstream head;
  if (svo.depth != ref.depth() || svo.brick_side != ref.side() ||
      svo.levels.size() != ref.depth() + 1) {
    head << "shape: octree depth " << svo.depth << ", side " << svo.brick_side << ", "
         << svo.levels.size() << " levels; reference depth " << ref.depth() << ", side "
         << ref.side() << "\n";
    return head.str();
  }
  if (ref.has_color() && !svo.has_color) head << "the octree has no colour plane\n";
  if (ref.has_normal() && !svo.has_normal) head << "the octree has no normal plane\n";
  if (!ref.has_color() && svo.has_color) head << "the octree has a colour plane, unexpected\n";
  if (!ref.has_normal() && svo.has_normal) head << "the octree has a normal plane, unexpected\n";
  if (!head.str().empty()) return head.str();

  std::ostringstream details;
  int reports = 0;
  const std::uint32_t per_node = svo.brick_samples();
  for (std::uint32_t level = 0; level <= svo.depth; ++level) {
    const std::vector<std::uint64_t> keys = svo.LevelKeys(level);
    if (keys != ref.Keys(level)) {
      head << "level " << level << ": other nodes (octree " << keys.size() << ", reference "
           << ref.Keys(level).size() << ")\n";
      continue;
    }
    const SvoLevel& lv = svo.levels[level];
    const std::size_t samples = keys.size() * per_node;
    if (lv.opacity.size() != samples || (svo.has_color && lv.color.size() != samples) ||
        (svo.has_normal && lv.normal.size() != samples)) {
      head << "level " << level << ": planes of " << lv.opacity.size() << ", " << lv.color.size()
           << ", " << lv.normal.size() << " samples for " << samples << "\n";
      continue;
    }
    std::uint64_t differ = 0;
    for (std::size_t i = 0; i < keys.size(); ++i) {
      for (std::uint32_t s = 0; s < per_node; ++s) {
        const FilterSample got = StoredSample(svo, level, i, s);
        const FilterSample want = ref.Sample(level, keys[i], s);
        if (got == want) continue;
        ++differ;
        if (reports < max_reports) {
          ++reports;
          const Vec3i p = ref.Position(level, MortonDecode(keys[i]), s % ref.side(),
                                       s / ref.side() % ref.side(), s / (ref.side() * ref.side()));
          details << NodeText(level, keys[i], s, ref.side()) << " at " << PositionText(p)
                  << ": octree " << ToString(got) << ", reference " << ToString(want) << "\n";
        }
      }
    }
    if (differ) {
      head << "level " << level << ": " << differ << " of " << samples << " samples differ\n";
    }
  }
  if (head.str().empty()) return "";
  return head.str() + "first differences:\n" + details.str();
}

std::string SharedBorderConflicts(const Svo& svo, int max_reports) {
  std::ostringstream head, details;
  const std::uint32_t side = svo.brick_side, per_node = svo.brick_samples();
  if (side != 2 && side != 3) return "";
  int reports = 0;
  struct Holder {
    FilterSample sample;
    std::uint64_t key;
    std::uint32_t index;
  };
  for (std::uint32_t level = 0; level <= svo.depth && level < svo.levels.size(); ++level) {
    const std::vector<std::uint64_t> keys = svo.LevelKeys(level);
    std::unordered_map<std::uint64_t, Holder> first;
    std::uint64_t conflicts = 0;
    for (std::size_t i = 0; i < keys.size(); ++i) {
      const MortonCoord c = MortonDecode(keys[i]);
      for (std::uint32_t s = 0; s < per_node; ++s) {
        const Vec3i p =
            SamplePosition(svo.depth, side, level, c, s % side, s / side % side, s / (side * side));
        const FilterSample got = StoredSample(svo, level, i, s);
        const auto [it, inserted] = first.emplace(Pack(p), Holder{got, keys[i], s});
        if (inserted || it->second.sample == got) continue;
        ++conflicts;
        if (reports < max_reports) {
          ++reports;
          details << PositionText(p) << ": " << NodeText(level, keys[i], s, side) << " stores "
                  << ToString(got) << ", "
                  << NodeText(level, it->second.key, it->second.index, side) << " stores "
                  << ToString(it->second.sample) << "\n";
        }
      }
    }
    if (conflicts) {
      head << "level " << level << ": " << conflicts << " shared samples stored differently\n";
    }
  }
  if (head.str().empty()) return "";
  return head.str() + "first conflicts:\n" + details.str();
}

}  // namespace svokit::test
