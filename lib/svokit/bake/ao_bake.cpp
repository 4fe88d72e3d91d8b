#include "svokit/bake/ao_bake.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include <fmt/format.h>

#include "svokit/core/bytes.hpp"
#include "svokit/core/file_io.hpp"
#include "svokit/core/hash.hpp"
#include "svokit/core/morton.hpp"
#include "svokit/core/parallel.hpp"
#include "svokit/formats/provenance.hpp"
#include "svokit/svo/sample_codec.hpp"
#include "svokit/svo/svo_assembler.hpp"

namespace svokit {

namespace {

constexpr int kMaxTextureSide = 16384;

Vec3d Normalized(const Vec3d& v) {
  const double length = Length(v);
  return length > 0 ? v / length : Vec3d{0, 0, 0};
}

// The unit normal a voxel's brick holds: the centre sample's (side 3), or the opacity-weighted
// mean of the corners' (side 2).
Vec3d VoxelNormal(const SvoLevel& bricks, std::uint32_t side, std::uint64_t voxel) {
  const std::uint32_t samples = side * side * side;
  const std::uint64_t first = voxel * samples;
  if (side == 3) {
    const Vec3f n = DecodeNormal(bricks.normal[first + 13]);
    return {n.x, n.y, n.z};
  }
  Vec3d sum{0, 0, 0};
  for (std::uint32_t s = 0; s < samples; ++s) {
    const Vec3f n = DecodeNormal(bricks.normal[first + s]);
    sum = sum + Vec3d{n.x, n.y, n.z} * DecodeUnorm8(bricks.opacity[first + s]);
  }
  return Normalized(sum);
}

}  // namespace

std::uint8_t EncodeAo(float ao) {
  return static_cast<std::uint8_t>(std::lround(255.f * std::clamp(ao, 0.f, 1.f)));
}

AoErrors CompareAo(std::span<const float> a, std::span<const float> b) {
  std::vector<double> d(a.size());
  for (std::size_t i = 0; i < a.size(); ++i) d[i] = std::abs(double{a[i]} - double{b[i]});
  AoErrors e;
  if (d.empty()) return e;
  for (const double v : d) e.mean += v;
  e.mean /= static_cast<double>(d.size());
  std::sort(d.begin(), d.end());
  e.p95 = d[std::min(d.size() - 1, static_cast<std::size_t>(0.95 * static_cast<double>(d.size())))];
  e.max = d.back();
  return e;
}

double MeanAo(std::span<const float> ao) {
  double sum = 0;
  for (const float x : ao) sum += x;
  return ao.empty() ? 0 : sum / static_cast<double>(ao.size());
}

StatusOr<std::vector<AoPoint>> VoxelPoints(const SvoChunk& page, const SvoShape& shape,
                                           const GridTransform& grid) {
  if (!shape.has_normal || shape.brick_side == 0) {
    return Status::BadInput(
        "the octree's voxels have no normals to bake along (voxelize it with normals)");
  }
  // The voxel bricks' normals and opacity: colours are not derived.
  SvoShape normals_only = shape;
  normals_only.has_color = false;
  normals_only.shared_color.clear();
  SvoLevel bricks;
  ChunkVoxelBricks(page, normals_only, bricks);
  const std::vector<std::uint64_t> keys = ChunkVoxelKeys(page);
  std::vector<AoPoint> points(keys.size());
  ParallelChunks(keys.size(), 4096, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const MortonCoord c = MortonDecode(keys[i]);
      points[i] = {
          grid.VoxelCenter({static_cast<int>(c.x), static_cast<int>(c.y), static_cast<int>(c.z)}),
          VoxelNormal(bricks, shape.brick_side, i)};
    }
  });
  return points;
}

std::vector<std::vector<std::uint8_t>> NodeAo(const MaskTree& tree, AoSums last, AoSums* root) {
  const std::size_t levels = tree.masks.size() + 1;
  std::vector<std::vector<std::uint8_t>> ao(levels);
  auto mean = [](std::uint64_t sum, std::uint64_t count) {
    return static_cast<std::uint8_t>((2 * sum + count) / (2 * count));
  };
  AoSums sums = std::move(last);
  for (std::size_t k = levels; k-- > 0;) {
    if (k + 1 < levels) {
      // Each node's sums from its children's, in node order.
      const std::vector<std::uint8_t>& masks = tree.masks[k];
      AoSums up{std::vector<std::uint64_t>(masks.size()), std::vector<std::uint64_t>(masks.size())};
      std::uint64_t child = 0;
      for (std::size_t i = 0; i < masks.size(); ++i) {
        for (int c = std::popcount(masks[i]); c-- > 0; ++child) {
          up.sum[i] += sums.sum[child];
          up.count[i] += sums.count[child];
        }
      }
      sums = std::move(up);
    }
    ao[k].resize(sums.sum.size());
    for (std::size_t i = 0; i < sums.sum.size(); ++i) ao[k][i] = mean(sums.sum[i], sums.count[i]);
  }
  if (root != nullptr) *root = std::move(sums);
  return ao;
}

std::vector<AoPoint> VertexPoints(const Mesh& mesh) {
  std::vector<Vec3d> normals(mesh.positions.size(), Vec3d{0, 0, 0});
  for (const Triangle& t : mesh.triangles) {
    const Vec3d& a = mesh.positions[t[0]];
    const Vec3d n = Cross(mesh.positions[t[1]] - a, mesh.positions[t[2]] - a);
    for (const std::uint32_t v : t) normals[v] = normals[v] + n;
  }
  std::vector<AoPoint> points(mesh.positions.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Vec3d n = Normalized(normals[i]);
    points[i] = {mesh.positions[i], Length(n) > 0 ? n : Vec3d{0, 0, 1}};
  }
  return points;
}

std::vector<AoPoint> SurfacePoints(const Mesh& mesh, std::size_t count, std::uint64_t seed) {
  std::vector<double> cumulative(mesh.triangles.size());
  double total = 0;
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Triangle& tri = mesh.triangles[t];
    total += Length(Cross(mesh.positions[tri[1]] - mesh.positions[tri[0]],
                          mesh.positions[tri[2]] - mesh.positions[tri[0]]));
    cumulative[t] = total;
  }
  std::vector<AoPoint> points;
  if (total <= 0) return points;
  for (std::size_t k = 0; k < count; ++k) {
    const std::uint64_t h = HashIndex(seed, k);
    const double at =
        (static_cast<double>(k) + UnitInterval(h)) / static_cast<double>(count) * total;
    const std::size_t t = std::min<std::size_t>(
        static_cast<std::size_t>(std::upper_bound(cumulative.begin(), cumulative.end(), at) -
                                 cumulative.begin()),
        cumulative.size() - 1);
    double u = UnitInterval(SplitMix64(h)), v = UnitInterval(SplitMix64(h + 1));
    if (u + v > 1) {
      u = 1 - u;
      v = 1 - v;
    }
    const Triangle& tri = mesh.triangles[t];
    const Vec3d& a = mesh.positions[tri[0]];
    const Vec3d e1 = mesh.positions[tri[1]] - a, e2 = mesh.positions[tri[2]] - a;
    points.push_back({a + e1 * u + e2 * v, Normalized(Cross(e1, e2))});
  }
  return points;
}

StatusOr<TexelPoints> RasterizeUvs(const Mesh& mesh, int size) {
  if (!mesh.has_uvs()) {
    return Status::BadInput("the mesh has no texture coordinates to bake a texture over");
  }
  if (size < 1 || size > kMaxTextureSide) {
    return Status::BadInput("a texture of {} texels a side: must be 1..{}", size, kMaxTextureSide);
  }
  const std::vector<AoPoint> vertices = VertexPoints(mesh);
  const std::size_t side = static_cast<std::size_t>(size);
  // Triangle t in texel coordinates (texel centres at integers).
  struct UvTriangle {
    std::array<double, 3> x, y;
    double area;
    std::array<double, 3> Weights(long px, long py) const {
      const double cx = static_cast<double>(px), cy = static_cast<double>(py);
      std::array<double, 3> w;
      for (int c = 0; c < 3; ++c) {
        const int a = (c + 1) % 3, b = (c + 2) % 3;
        w[c] = ((x[b] - x[a]) * (cy - y[a]) - (cx - x[a]) * (y[b] - y[a])) / area;
      }
      return w;
    }
  };
  auto uv_triangle = [&](std::size_t t) {
    UvTriangle uv;
    for (int c = 0; c < 3; ++c) {
      const Vec2f corner = mesh.uvs[3 * t + static_cast<std::size_t>(c)];
      uv.x[c] = static_cast<double>(corner.u) * size - 0.5;
      uv.y[c] = (1 - static_cast<double>(corner.v)) * size - 0.5;
    }
    uv.area = (uv.x[1] - uv.x[0]) * (uv.y[2] - uv.y[0]) - (uv.x[2] - uv.x[0]) * (uv.y[1] - uv.y[0]);
    return uv;
  };
  // The triangle that owns each texel (the first to cover it), 4 bytes a texel.
  constexpr std::uint32_t kNone = 0xffffffffu;
  std::vector<std::uint32_t> owner(side * side, kNone);
  std::vector<std::uint8_t> twice(side * side, 0);
  // Strictly inside, by more than rounding: a texel centre on an edge two triangles share is not
  // an overlap.
  constexpr double kInside = 1e-9;
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const UvTriangle uv = uv_triangle(t);
    if (uv.area == 0 || !std::isfinite(uv.area)) continue;
    const auto lo = [&](const std::array<double, 3>& v) {
      return std::clamp(static_cast<long>(std::ceil(std::min({v[0], v[1], v[2]}))), 0L,
                        static_cast<long>(size));
    };
    const auto hi = [&](const std::array<double, 3>& v) {
      return std::clamp(static_cast<long>(std::floor(std::max({v[0], v[1], v[2]}))), -1L,
                        static_cast<long>(size) - 1);
    };
    for (long py = lo(uv.y); py <= hi(uv.y); ++py) {
      for (long px = lo(uv.x); px <= hi(uv.x); ++px) {
        const std::array<double, 3> w = uv.Weights(px, py);
        if (w[0] < 0 || w[1] < 0 || w[2] < 0) continue;
        const std::size_t texel =
            static_cast<std::size_t>(py) * side + static_cast<std::size_t>(px);
        if (owner[texel] == kNone) {
          owner[texel] = static_cast<std::uint32_t>(t);
        } else if (w[0] > kInside && w[1] > kInside && w[2] > kInside) {
          const std::array<double, 3> first = uv_triangle(owner[texel]).Weights(px, py);
          twice[texel] |= first[0] > kInside && first[1] > kInside && first[2] > kInside;
        }
      }
    }
  }
  TexelPoints out;
  out.size = size;
  out.overlapped = static_cast<std::size_t>(std::count(twice.begin(), twice.end(), 1));
  for (std::size_t texel = 0; texel < owner.size(); ++texel) {
    if (owner[texel] == kNone) continue;
    const Triangle& tri = mesh.triangles[owner[texel]];
    const std::array<double, 3> w =
        uv_triangle(owner[texel])
            .Weights(static_cast<long>(texel % side), static_cast<long>(texel / side));
    Vec3d p{0, 0, 0}, n{0, 0, 0};
    for (int c = 0; c < 3; ++c) {
      p = p + mesh.positions[tri[c]] * w[c];
      n = n + vertices[tri[c]].normal * w[c];
    }
    if (Length(n) == 0) {
      n = Cross(mesh.positions[tri[1]] - mesh.positions[tri[0]],
                mesh.positions[tri[2]] - mesh.positions[tri[0]]);
    }
    n = Normalized(n);
    out.texels.push_back(static_cast<std::uint32_t>(texel));
    out.points.push_back({p, Length(n) > 0 ? n : Vec3d{0, 0, 1}});
  }
  return out;
}

std::vector<std::uint8_t> AoTexture(const TexelPoints& texels, std::span<const float> ao) {
  const std::size_t side = static_cast<std::size_t>(texels.size);
  std::vector<float> value(side * side, 0.f);
  std::vector<std::uint8_t> filled(side * side, 0);
  std::vector<std::size_t> ring;
  for (std::size_t i = 0; i < texels.texels.size(); ++i) {
    value[texels.texels[i]] = 1.f - std::clamp(ao[i], 0.f, 1.f);
    filled[texels.texels[i]] = 1;
    ring.push_back(texels.texels[i]);
  }
  // Dilation ring by ring (8-neighbourhood): each empty texel next to the filled ones takes the
  // mean of those, then the ring counts as filled.
  auto neighbours = [&](std::size_t texel, auto&& visit) {
    const long x = static_cast<long>(texel % side), y = static_cast<long>(texel / side);
    for (long dy = -1; dy <= 1; ++dy) {
      for (long dx = -1; dx <= 1; ++dx) {
        const long nx = x + dx, ny = y + dy;
        if ((dx == 0 && dy == 0) || nx < 0 || ny < 0 || nx >= static_cast<long>(side) ||
            ny >= static_cast<long>(side)) {
          continue;
        }
        visit(static_cast<std::size_t>(ny) * side + static_cast<std::size_t>(nx));
      }
    }
  };
  while (!ring.empty()) {
    std::vector<std::size_t> next;
    for (const std::size_t texel : ring) {
      neighbours(texel, [&](std::size_t n) {
        if (filled[n] == 0) {
          filled[n] = 2;  // in the next ring
          next.push_back(n);
        }
      });
    }
    std::sort(next.begin(), next.end());
    std::vector<float> next_value(next.size());
    for (std::size_t i = 0; i < next.size(); ++i) {
      float sum = 0;
      int count = 0;
      neighbours(next[i], [&](std::size_t n) {
        if (filled[n] == 1) {
          sum += value[n];
          ++count;
        }
      });
      next_value[i] = sum / static_cast<float>(count);
    }
    for (std::size_t i = 0; i < next.size(); ++i) {
      value[next[i]] = next_value[i];
      filled[next[i]] = 1;
    }
    ring = std::move(next);
  }
  std::vector<std::uint8_t> pixels(side * side, 255);
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    if (filled[i] == 1) pixels[i] = static_cast<std::uint8_t>(std::lround(255.f * value[i]));
  }
  return pixels;
}

Status WriteAoPly(const Mesh& mesh, std::span<const AoPoint> points, std::span<const float> ao,
                  const std::filesystem::path& path) {
  ByteWriter w;
  const std::string header = fmt::format(
      "ply\nformat binary_little_endian 1.0\ncomment svokit baked ambient occlusion (ao: 0 open, "
      "1 occluded; colour: 1 - ao)\nelement vertex {}\nproperty float x\nproperty float y\n"
      "property float z\nproperty float nx\nproperty float ny\nproperty float nz\n"
      "property float ao\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n"
      "element face {}\nproperty list uchar int vertex_indices\nend_header\n",
      mesh.positions.size(), mesh.triangles.size());
  w.PutArray<char>(std::span<const char>(header.data(), header.size()));
  for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
    for (const double v : {mesh.positions[i].x, mesh.positions[i].y, mesh.positions[i].z,
                           points[i].normal.x, points[i].normal.y, points[i].normal.z}) {
      w.Put(static_cast<float>(v));
    }
    w.Put(ao[i]);
    const std::uint8_t grey = static_cast<std::uint8_t>(255 - EncodeAo(ao[i]));
    for (int c = 0; c < 3; ++c) w.Put(grey);
  }
  for (const Triangle& t : mesh.triangles) {
    w.Put(std::uint8_t{3});
    for (const std::uint32_t v : t) w.Put(static_cast<std::int32_t>(v));
  }
  return WriteFileAtomic(path, w.bytes());
}

Status CheckMeshMatchesOctree(const Mesh& mesh, const GridTransform& grid,
                              const std::string& metadata, const std::string& mesh_name) {
  const Provenance recorded = ParseProvenance(metadata);
  if (recorded.triangles > 0 && recorded.triangles != mesh.triangle_count()) {
    return Status::BadInput(
        "{}: the mesh has {} triangles, the octree's {}: not the mesh it was voxelized from",
        mesh_name, mesh.triangle_count(), recorded.triangles);
  }
  const Box3d bounds = mesh.Bounds();
  if (!recorded.grid) {
    // No recorded grid fit: the mesh must at least lie inside the grid.
    if (grid.Encloses(bounds)) return Status::Ok();
    return Status::BadInput("{}: the mesh lies outside the octree's grid: not its mesh", mesh_name);
  }
  const StatusOr<GridTransform> fitted = recorded.grid->Fit(bounds);
  const GridTransform& g = grid;
  const double tolerance = 1e-6 * g.voxel_size();
  if (!fitted.ok() || fitted->dims() != g.dims() ||
      std::abs(fitted->voxel_size() - g.voxel_size()) > 1e-9 * g.voxel_size() ||
      Length(fitted->origin() - g.origin()) > tolerance) {
    return Status::BadInput(
        "{}: the mesh's bounds [{:.9g}, {:.9g}, {:.9g}] .. [{:.9g}, {:.9g}, {:.9g}] do not give "
        "the octree's grid: not the mesh it was voxelized from (or not turned as it was: "
        "--up, --rotate)",
        mesh_name, bounds.lo.x, bounds.lo.y, bounds.lo.z, bounds.hi.x, bounds.hi.y, bounds.hi.z);
  }
  return Status::Ok();
}

}  // namespace svokit
