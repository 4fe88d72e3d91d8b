#include "svokit/validate/contour_surface.hpp"

#include <algorithm>
#include <cmath>
#include <memory>
#include <random>

#include <tbb/parallel_for.h>

#include "svokit/svo/key_index.hpp"
#include "svokit/svo/svo.hpp"

namespace svokit::validate {
namespace {

struct Partial {
  std::uint64_t points = 0, checks = 0, violations = 0, orphans = 0;
  std::vector<SlabViolation> first;
  std::vector<std::array<std::uint64_t, 3>> order;  // triangle, point, check of each of first
};

// Per axis, the node coordinates at a level whose closed extent [c·s, (c + 1)·s] holds v (one,
// or two on a boundary), with a relative slack of 1e-9 node sizes for rounding in the mapping.
int Candidates(double v, double s, std::int64_t limit, std::int64_t out[2]) {
  const double t = v / s;
  int n = 0;
  const auto lo = static_cast<std::int64_t>(std::floor(t - 1e-9)),
             hi = static_cast<std::int64_t>(std::floor(t + 1e-9));
  for (std::int64_t c = lo; c <= hi; ++c) {
    if (c >= 0 && c < limit && n < 2) out[n++] = c;
  }
  return n;
}

}  // namespace

SlabSampleResult SampleContourSlabs(const Mesh& mesh, const GridTransform& grid,
                                    std::uint32_t depth,
                                    std::span<const std::vector<std::uint64_t>> level_keys,
                                    std::span<const std::vector<std::uint32_t>> words,
                                    const SlabSampleOptions& options) {
  std::vector<std::unique_ptr<KeyIndex>> index;
  std::vector<SlabLevel> levels;
  for (std::size_t l = 0; l < level_keys.size(); ++l) {
    index.push_back(std::make_unique<KeyIndex>(level_keys[l]));
    levels.push_back({index.back().get(), words[l]});
  }
  std::vector<std::uint32_t> all(mesh.triangles.size());
  for (std::size_t t = 0; t < all.size(); ++t) all[t] = static_cast<std::uint32_t>(t);
  return SampleContourSlabsOf(mesh, grid, depth, levels, all, nullptr, options, nullptr);
}

SlabSampleResult SampleContourSlabsOf(const Mesh& mesh, const GridTransform& grid,
                                      std::uint32_t depth, std::span<const SlabLevel> levels,
                                      std::span<const std::uint32_t> triangles,
                                      const std::function<bool(const Vec3d&)>& owns,
                                      const SlabSampleOptions& options,
                                      std::vector<std::array<std::uint64_t, 3>>* order) {
  const std::size_t count = triangles.size();
  constexpr std::size_t kChunk = 256;
  std::vector<Partial> parts((count + kChunk - 1) / kChunk);
  tbb::parallel_for(std::size_t{0}, parts.size(), [&](std::size_t part) {
    Partial& r = parts[part];
    std::vector<Vec3d> pts;
    for (std::size_t n = part * kChunk; n < std::min(count, (part + 1) * kChunk); ++n) {
      const std::size_t t = triangles[n];
      // Sampled in voxel space, the voxelizer's frame: world areas of a 1e-300 mesh underflow.
      const Triangle& tri = mesh.triangles[t];
      const bool may_be_hole = options.holes && mesh.ReadsAlpha(t);
      const Vec3d a = grid.WorldToVoxel(mesh.positions[tri[0]]),
                  b = grid.WorldToVoxel(mesh.positions[tri[1]]),
                  c = grid.WorldToVoxel(mesh.positions[tri[2]]);
      pts = {a, b, c};
      for (int e = 1; e <= 8; ++e) {
        const double w = e / 9.0;
        pts.push_back(a * (1 - w) + b * w);
        pts.push_back(b * (1 - w) + c * w);
        pts.push_back(c * (1 - w) + a * w);
      }
      int interior = options.interior;
      if (interior <= 0) {
        const double area = 0.5 * Length(Cross(b - a, c - a));
        interior = static_cast<int>(std::clamp(std::ceil(2 * area), 4.0, 4096.0));
      }
      std::mt19937_64 rng(options.seed ^ (0x9E3779B97F4A7C15ull * (t + 1)));
      std::uniform_real_distribution<double> uni(0.0, 1.0);
      for (int i = 0; i < interior; ++i) {
        double u = uni(rng), v = uni(rng);
        if (u + v > 1) u = 1 - u, v = 1 - v;
        pts.push_back(a * (1 - u - v) + b * u + c * v);
      }
      for (std::size_t p = 0; p < pts.size(); ++p) {
        const Vec3d& q = pts[p];
        if (owns && !owns(q)) continue;
        ++r.points;
        std::uint64_t check = 0;
        for (std::uint32_t level = 0; level <= depth; ++level) {
          const double s = std::ldexp(1.0, static_cast<int>(depth - level));
          const std::int64_t limit = std::int64_t{1} << level;
          std::int64_t cx[2], cy[2], cz[2];
          const int nx = Candidates(q.x, s, limit, cx), ny = Candidates(q.y, s, limit, cy),
                    nz = Candidates(q.z, s, limit, cz);
          bool found = false;
          for (int iz = 0; iz < nz; ++iz) {
            for (int iy = 0; iy < ny; ++iy) {
              for (int ix = 0; ix < nx; ++ix) {
                const std::int64_t node = levels[level].index->Find(MortonEncode(
                    static_cast<std::uint32_t>(cx[ix]), static_cast<std::uint32_t>(cy[iy]),
                    static_cast<std::uint32_t>(cz[iz])));
                if (node < 0) continue;
                found = true;
                const std::uint32_t word = levels[level].words[static_cast<std::size_t>(node)];
                if (word == 0) continue;  // no contour: the whole cube
                const Contour ct = DecodeContour(word);
                const Vec3d u{(q.x - (static_cast<double>(cx[ix]) + 0.5) * s) / s,
                              (q.y - (static_cast<double>(cy[iy]) + 0.5) * s) / s,
                              (q.z - (static_cast<double>(cz[iz]) + 0.5) * s) / s};
                const double d = ct.nx * u.x + ct.ny * u.y + ct.nz * u.z;
                const double tol = 1e-9 * (std::abs(ct.nx) + std::abs(ct.ny) + std::abs(ct.nz));
                ++r.checks;
                ++check;
                if (d < ct.Low() - tol || d > ct.High() + tol) {
                  if (r.violations++ < options.max_violations) {
                    r.first.push_back(
                        {level,
                         {static_cast<std::uint32_t>(cx[ix]), static_cast<std::uint32_t>(cy[iy]),
                          static_cast<std::uint32_t>(cz[iz])},
                         grid.VoxelToWorld(q),
                         d,
                         ct.Low(),
                         ct.High()});
                    r.order.push_back({t, p, check});
                  }
                }
              }
            }
          }
          if (!found && !may_be_hole) ++r.orphans;
        }
      }
    }
  });
  SlabSampleResult out;
  for (Partial& p : parts) {
    out.points += p.points;
    out.checks += p.checks;
    out.violations += p.violations;
    out.orphans += p.orphans;
    for (std::size_t i = 0; i < p.first.size(); ++i) {
      if (out.first.size() < options.max_violations) {
        out.first.push_back(p.first[i]);
        if (order != nullptr) order->push_back(p.order[i]);
      }
    }
  }
  return out;
}

}  // namespace svokit::validate
