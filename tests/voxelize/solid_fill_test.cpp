// Solid voxelization (solid_fill.hpp) against exact references. On closed meshes the solid (the
// surface voxels and the interior cubes) must be exactly the surface voxels and the voxels whose
// centre CGAL puts strictly inside (exact_reference.hpp); on broken meshes it must agree with the
// exact generalized winding number (|w| ≥ ½, winding_number.hpp) but for a few voxels next to the
// surface. Every result's cubes are checked against the header's contract too: levels sorted,
// cubes disjoint, inside the grid, holding no surface voxel, Contains() and the counts consistent
// with the levels, and on cycles each cube a free child of a node of the surface's octree.
// Failures print the offending voxels with the cube holding them (or the free node they belong
// to). The Slow* tests (resolutions 256 and 512, larger broken meshes) are labelled "slow".

#include <gtest/gtest-spi.h>
#include <gtest/gtest.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <initializer_list>
#include <iostream>
#include <limits>
#include <map>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "svokit/core/grid_transform.hpp"
#include "svokit/core/morton.hpp"
#include "svokit/core/thread_limit.hpp"
#include "svokit/formats/mesh_import.hpp"
#include "svokit/voxelize/solid_fill.hpp"
#include "svokit/voxelize/voxel_space.hpp"
#include "svokit/voxelize/voxelize.hpp"
#include "svokit/voxelize/winding_number.hpp"
#include "tests/test_meshes.hpp"
#include "tests/test_util.hpp"
#include "tests/voxelize/exact_reference.hpp"
#include "tests/voxelize/solid_test_meshes.hpp"

namespace svokit {
namespace {

using test::Box;
using test::ExactInside;
using test::FaceSplit;
using test::Finish;
using test::FlippedComponent;
using test::Grid3;
using test::MakeSurface;
using test::NestedShells;
using test::OverlappingSpheres;
using test::SignedVolume6;
using test::Surface;
using test::VoxelName;
using test::VoxelShape;

constexpr VoxelMode kModes[] = {VoxelMode::kConservative, VoxelMode::kThin};

const char* ModeName(VoxelMode mode) {
  return mode == VoxelMode::kThin ? "thin" : "conservative";
}

const char* MethodName(FillMethod method) {
  return method == FillMethod::kColumns ? "kColumns" : "kWindingNumber";
}

double Seconds(std::chrono::steady_clock::time_point a, std::chrono::steady_clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

// ---------------------------------------------------------------------------------------------
// Meshes.

/// The octahedron |x − c.x| + |y − c.y| + |z − c.z| ≤ r, outward.
VoxelShape Octahedron(const Vec3d& c, double r) {
  VoxelShape s;
  s.points = {c + Vec3d{r, 0, 0}, c - Vec3d{r, 0, 0}, c + Vec3d{0, r, 0},
              c - Vec3d{0, r, 0}, c + Vec3d{0, 0, r}, c - Vec3d{0, 0, r}};
  for (int sx = 0; sx < 2; ++sx) {
    for (int sy = 0; sy < 2; ++sy) {
      for (int sz = 0; sz < 2; ++sz) {
        const std::uint32_t x = sx, y = 2 + sy, z = 4 + sz;
        // (+x, +y, +z) is counter-clockwise from outside; each sign flip mirrors it.
        if ((sx + sy + sz) % 2 == 0) {
          s.triangles.push_back({x, y, z});
        } else {
          s.triangles.push_back({x, z, y});
        }
      }
    }
  }
  return s;
}

/// The shape's corners in the world space of `grid`, snapping back exactly to the given voxel
/// coordinates (they are multiples of 2⁻¹⁶, and the grid's origin and voxel size are dyadic).
Mesh ToWorld(const VoxelShape& s, const GridTransform& grid) {
  Mesh mesh;
  for (const Vec3d& p : s.points) mesh.positions.push_back(grid.VoxelToWorld(p));
  mesh.triangles = s.triangles;
  Finish(mesh);
  const std::vector<FixedPoint3> fixed = SnapToVoxelSpace(mesh, grid);
  for (std::size_t i = 0; i < fixed.size(); ++i) {
    EXPECT_EQ(FixedToVoxel(fixed[i]), s.points[i]) << "corner " << i << " does not snap exactly";
  }
  return mesh;
}

/// Triangles whose corners all lie above `z`, removed (with their corner attributes).
Mesh WithoutCap(const Mesh& mesh, double z) {
  Mesh out = mesh;
  out.triangles.clear();
  for (const Triangle& t : mesh.triangles) {
    if (mesh.positions[t[0]].z > z && mesh.positions[t[1]].z > z && mesh.positions[t[2]].z > z) {
      continue;
    }
    out.triangles.push_back(t);
  }
  Finish(out);
  return out;
}

/// Holes: the fans of triangles around every `stride`-th vertex removed.
Mesh WithCutHoles(const Mesh& mesh, std::uint32_t stride) {
  Mesh out = mesh;
  out.triangles.clear();
  for (const Triangle& t : mesh.triangles) {
    if (t[0] % stride == 0 || t[1] % stride == 0 || t[2] % stride == 0) continue;
    out.triangles.push_back(t);
  }
  Finish(out);
  return out;
}

/// Every `stride`-th triangle reversed.
Mesh WithFlippedTriangles(const Mesh& mesh, std::size_t stride) {
  Mesh out = mesh;
  for (std::size_t i = 0; i < out.triangles.size(); i += stride) {
    std::swap(out.triangles[i][1], out.triangles[i][2]);
  }
  Finish(out);
  return out;
}

/// A soup: every triangle with corners of its own. Every `drop`-th triangle is left out (0: none),
/// and every `jitter`-th gets one corner moved by up to `amount` per axis (0: none).
Mesh Soup(const Mesh& mesh, std::size_t drop, std::size_t jitter, double amount,
          std::uint32_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-amount, amount);
  Mesh out;
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
    if (drop != 0 && i % drop == drop - 1) continue;
    const Triangle& t = mesh.triangles[i];
    const auto first = static_cast<std::uint32_t>(out.positions.size());
    for (const std::uint32_t v : t) out.positions.push_back(mesh.positions[v]);
    if (jitter != 0 && i % jitter == 0) {
      Vec3d& p = out.positions[first + i % 3];
      p = p + Vec3d{u(rng), u(rng), u(rng)};
    }
    out.triangles.push_back({first, first + 1, first + 2});
  }
  Finish(out);
  return out;
}

std::optional<Mesh> LoadCgalMesh(const std::string& file) {
  static std::map<std::string, Mesh> cache;
  const auto it = cache.find(file);
  if (it != cache.end()) return it->second;
  const std::filesystem::path path = test::CgalMeshes() / file;
  if (!std::filesystem::exists(path)) return std::nullopt;
  StatusOr<Mesh> mesh = ImportMesh(path);
  EXPECT_TRUE(mesh.ok()) << path << ": " << mesh.status().message();
  if (!mesh.ok()) return std::nullopt;
  return cache.emplace(file, std::move(*mesh)).first->second;
}

// ---------------------------------------------------------------------------------------------
// Dense grids and descriptions.

std::string CubeName(std::uint32_t depth, std::uint32_t level, std::uint64_t key) {
  const MortonCoord c = MortonDecode(key);
  const std::int64_t side = std::int64_t{1} << (depth - level);
  std::ostringstream s;
  s << "level-" << level << " cube (key " << key << ") at voxel " << c.x * side << "," << c.y * side
    << "," << c.z * side << " side " << side;
  return s.str();
}

std::uint64_t VoxelKey(const std::array<std::int64_t, 3>& c) {
  return MortonEncode(static_cast<std::uint32_t>(c[0]), static_cast<std::uint32_t>(c[1]),
                      static_cast<std::uint32_t>(c[2]));
}

/// The cube holding voxel `c`, by the levels (not Contains()).
std::string HoldingCube(const InteriorCubes& cubes, const std::array<std::int64_t, 3>& c) {
  const std::uint64_t key = VoxelKey(c);
  for (std::uint32_t level = 0; level < cubes.levels.size() && level <= cubes.depth; ++level) {
    const std::uint64_t k = key >> (3 * (cubes.depth - level));
    const auto& l = cubes.levels[level];
    if (std::binary_search(l.begin(), l.end(), k)) return CubeName(cubes.depth, level, k);
  }
  return "no cube";
}

/// The surface's octree: per level, the sorted keys of the nodes holding a surface voxel.
std::vector<std::vector<std::uint64_t>> SurfaceNodes(const std::vector<std::uint64_t>& keys,
                                                     std::uint32_t depth) {
  std::vector<std::vector<std::uint64_t>> nodes(depth + 1);
  for (std::uint32_t level = 0; level <= depth; ++level) {
    for (const std::uint64_t k : keys) {
      const std::uint64_t n = k >> (3 * (depth - level));
      if (nodes[level].empty() || nodes[level].back() != n) nodes[level].push_back(n);
    }
  }
  return nodes;
}

/// The largest octree node holding voxel `c` but no surface voxel: the cube it belongs to when
/// its centre is inside.
std::string FreeNode(const std::vector<std::vector<std::uint64_t>>& nodes, std::uint32_t depth,
                     const std::array<std::int64_t, 3>& c) {
  const std::uint64_t key = VoxelKey(c);
  for (std::uint32_t level = 0; level <= depth; ++level) {
    const std::uint64_t k = key >> (3 * (depth - level));
    if (!std::binary_search(nodes[level].begin(), nodes[level].end(), k)) {
      return "belongs in the free " + CubeName(depth, level, k);
    }
  }
  return "is a surface voxel";
}

/// Whether a surface voxel is within Chebyshev distance 1 of voxel i.
bool NearSurface(const Grid3& g, const std::vector<std::uint8_t>& surface, std::size_t i) {
  const auto c = g.Coord(i);
  for (std::int64_t dz = -1; dz <= 1; ++dz) {
    for (std::int64_t dy = -1; dy <= 1; ++dy) {
      for (std::int64_t dx = -1; dx <= 1; ++dx) {
        if (g.In(c[0] + dx, c[1] + dy, c[2] + dz) &&
            surface[g.Index(c[0] + dx, c[1] + dy, c[2] + dz)]) {
          return true;
        }
      }
    }
  }
  return false;
}

// ---------------------------------------------------------------------------------------------
// The cubes' structure.

/// Checks `cubes` against the header's contract and returns which grid voxels they hold (1 per
/// voxel): depth + 1 levels, each strictly ascending with keys inside its level; no voxel in two
/// cubes, none outside the grid, none a surface voxel; cube_count(), voxel_count() and Contains()
/// as the levels say. On a cycle (kColumns), every cube a child of a node holding a surface voxel:
/// the cubes are the maximal free nodes (the winding number may split free nodes further).
std::vector<std::uint8_t> CheckCubes(const InteriorCubes& cubes, const GridTransform& grid,
                                     const Surface& surface, const std::string& label) {
  SCOPED_TRACE(label);
  const Grid3 g(grid);
  std::vector<std::uint8_t> covered(g.size(), 0);
  const std::uint32_t depth = cubes.depth;
  EXPECT_LE(depth, 21u);
  EXPECT_GE(std::uint64_t{1} << std::min(depth, 21u), grid.max_dim()) << "depth " << depth;
  EXPECT_EQ(cubes.levels.size(), std::size_t{depth} + 1) << "depth " << depth;
  if (depth > 21 || cubes.levels.size() != std::size_t{depth} + 1) return covered;
  const auto nodes = SurfaceNodes(surface.keys, depth);

  std::uint64_t cube_count = 0, voxel_count = 0, outside = 0, overlaps = 0, on_surface = 0,
                unsorted = 0, out_of_level = 0, not_maximal = 0;
  std::string unsorted_at, out_of_level_at, outside_at, overlap_at, on_surface_at, not_maximal_at;
  const auto note = [](std::string& s, std::uint64_t count, const std::string& what) {
    if (count <= 3) s += "\n    " + what;
  };
  for (std::uint32_t level = 0; level <= depth; ++level) {
    const std::vector<std::uint64_t>& keys = cubes.levels[level];
    const std::int64_t side = std::int64_t{1} << (depth - level);
    for (std::size_t i = 0; i < keys.size(); ++i) {
      const std::uint64_t key = keys[i];
      if (i > 0 && keys[i - 1] >= key) {
        note(unsorted_at, ++unsorted,
             CubeName(depth, level, key) + " after key " + std::to_string(keys[i - 1]));
      }
      if (level < 21 && (key >> (3 * level)) != 0) {
        note(out_of_level_at, ++out_of_level,
             "level " + std::to_string(level) + " key " + std::to_string(key));
        continue;
      }
      ++cube_count;
      voxel_count += static_cast<std::uint64_t>(side * side * side);
      if (cubes.method == FillMethod::kColumns &&
          (level == 0 ||
           !std::binary_search(nodes[level - 1].begin(), nodes[level - 1].end(), key >> 3))) {
        note(not_maximal_at, ++not_maximal, CubeName(depth, level, key));
      }
      const MortonCoord c = MortonDecode(key);
      const std::int64_t lo[3] = {c.x * side, c.y * side, c.z * side};
      const std::int64_t hi[3] = {std::min(lo[0] + side, g.nx), std::min(lo[1] + side, g.ny),
                                  std::min(lo[2] + side, g.nz)};
      const std::int64_t inside_volume = std::max<std::int64_t>(0, hi[0] - lo[0]) *
                                         std::max<std::int64_t>(0, hi[1] - lo[1]) *
                                         std::max<std::int64_t>(0, hi[2] - lo[2]);
      if (inside_volume != side * side * side) {
        outside += static_cast<std::uint64_t>(side * side * side - inside_volume);
        note(outside_at, outside, CubeName(depth, level, key));
      }
      for (std::int64_t z = lo[2]; z < hi[2]; ++z) {
        for (std::int64_t y = lo[1]; y < hi[1]; ++y) {
          for (std::int64_t x = lo[0]; x < hi[0]; ++x) {
            const std::size_t v = g.Index(x, y, z);
            if (covered[v]) {
              note(overlap_at, ++overlaps,
                   VoxelName({x, y, z}) + " again in " + CubeName(depth, level, key));
            }
            covered[v] = 1;
            if (surface.dense[v]) {
              note(on_surface_at, ++on_surface,
                   "surface voxel " + VoxelName({x, y, z}) + " in " + CubeName(depth, level, key));
            }
          }
        }
      }
    }
  }
  EXPECT_EQ(unsorted, 0u) << "keys not strictly ascending within a level:" << unsorted_at;
  EXPECT_EQ(out_of_level, 0u) << "keys beyond their level's 2^L cube:" << out_of_level_at;
  EXPECT_EQ(overlaps, 0u) << "voxels in more than one cube:" << overlap_at;
  EXPECT_EQ(on_surface, 0u) << "cubes holding surface voxels:" << on_surface_at;
  EXPECT_EQ(outside, 0u) << "cube voxels outside the grid:" << outside_at;
  EXPECT_EQ(not_maximal, 0u) << "cubes whose parent holds no surface voxel (not the free "
                                "children of the surface's octree):"
                             << not_maximal_at;
  EXPECT_EQ(cubes.cube_count(), cube_count);
  EXPECT_EQ(cubes.voxel_count(), voxel_count);

  // Contains() against the levels: every grid voxel on grids up to 2^22 voxels, a sample on
  // larger ones.
  const std::int64_t stride = g.size() > (std::size_t{1} << 22) ? 61 : 1;
  std::atomic<std::uint64_t> wrong{0};
  std::atomic<std::size_t> first_wrong{std::numeric_limits<std::size_t>::max()};
  tbb::parallel_for(tbb::blocked_range<std::int64_t>(0, g.nz), [&](const auto& r) {
    for (std::int64_t z = r.begin(); z < r.end(); ++z) {
      for (std::int64_t y = 0; y < g.ny; ++y) {
        for (std::int64_t x = (y + z) % stride; x < g.nx; x += stride) {
          const std::size_t v = g.Index(x, y, z);
          const bool got =
              cubes.Contains(static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(y),
                             static_cast<std::uint32_t>(z));
          if (got != (covered[v] != 0)) {
            ++wrong;
            std::size_t prev = first_wrong.load();
            while (v < prev && !first_wrong.compare_exchange_weak(prev, v)) {
            }
          }
        }
      }
    }
  });
  if (wrong.load() != 0) {
    const auto c = g.Coord(first_wrong.load());
    ADD_FAILURE() << "Contains() disagrees with the levels at " << wrong.load() << " voxels, e.g. "
                  << VoxelName(c) << ": Contains() " << !covered[g.Index(c[0], c[1], c[2])]
                  << ", levels: " << HoldingCube(cubes, c);
  }
  return covered;
}

/// Edits a result before it is checked: for the tests of the checks themselves.
using Corrupt = std::function<void(InteriorCubes&)>;

std::optional<InteriorCubes> Fill(const Mesh& mesh, const GridTransform& grid,
                                  const std::vector<std::uint64_t>& keys, double* seconds) {
  const auto start = std::chrono::steady_clock::now();
  StatusOr<InteriorCubes> cubes = FillInterior(mesh, grid, keys);
  if (seconds) *seconds = Seconds(start, std::chrono::steady_clock::now());
  EXPECT_TRUE(cubes.ok()) << cubes.status().message();
  if (!cubes.ok()) return std::nullopt;
  return std::move(*cubes);
}

// ---------------------------------------------------------------------------------------------
// Closed meshes: exactly CGAL's inside.

constexpr std::int8_t kUnknown = 2;

/// CGAL's side (+1 in, 0 on, −1 out) of the centre of every grid voxel that is not a surface
/// voxel (kUnknown for those). On grids of up to `direct_limit` voxels every centre is queried.
/// On larger ones one centre per 6-connected component of the voxels outside the conservative
/// surface is (the segment between two 6-adjacent centres lies in the two closed voxel boxes, so
/// a surface crossing it would make one of them conservative: a component is on one side), plus
/// every non-surface voxel of the conservative set (thin mode); then every `shell_stride`-th
/// voxel of the components within one voxel (Chebyshev) of the conservative set is queried too,
/// and must agree with its component.
std::vector<std::int8_t> CgalSides(const ExactInside& cgal, const GridTransform& grid,
                                   const Surface& surface, const Surface& conservative,
                                   std::size_t direct_limit, std::size_t shell_stride) {
  const Grid3 g(grid);
  std::vector<std::int8_t> sides(g.size(), kUnknown);
  const auto query = [&](const std::vector<std::size_t>& voxels) {
    std::vector<Vec3d> centres(voxels.size());
    for (std::size_t i = 0; i < voxels.size(); ++i) centres[i] = g.Centre(voxels[i]);
    const std::vector<int> s = cgal.Sides(centres);
    return s;
  };
  if (g.size() <= direct_limit) {
    std::vector<std::size_t> voxels;
    for (std::size_t i = 0; i < g.size(); ++i) {
      if (!surface.dense[i]) voxels.push_back(i);
    }
    const std::vector<int> s = query(voxels);
    for (std::size_t i = 0; i < voxels.size(); ++i)
      sides[voxels[i]] = static_cast<std::int8_t>(s[i]);
    return sides;
  }
  std::vector<std::size_t> stack;
  std::size_t components = 0;
  for (std::size_t i = 0; i < g.size(); ++i) {
    if (conservative.dense[i] || sides[i] != kUnknown) continue;
    const int s = cgal.Side(g.Centre(i));
    EXPECT_NE(s, 0) << "centre of " << VoxelName(g.Coord(i))
                    << " is on the mesh but its voxel is not conservative";
    ++components;
    sides[i] = static_cast<std::int8_t>(s);
    stack.push_back(i);
    while (!stack.empty()) {
      const std::size_t j = stack.back();
      stack.pop_back();
      const auto c = g.Coord(j);
      for (int a = 0; a < 3; ++a) {
        for (const std::int64_t d : {-1, 1}) {
          std::array<std::int64_t, 3> n = c;
          n[a] += d;
          if (!g.In(n[0], n[1], n[2])) continue;
          const std::size_t k = g.Index(n[0], n[1], n[2]);
          if (conservative.dense[k] || sides[k] != kUnknown) continue;
          sides[k] = static_cast<std::int8_t>(s);
          stack.push_back(k);
        }
      }
    }
  }
  std::vector<std::uint8_t> next_to_surface(g.size(), 0);
  for (const std::uint64_t key : conservative.keys) {
    const MortonCoord c = MortonDecode(key);
    for (std::int64_t dz = -1; dz <= 1; ++dz) {
      for (std::int64_t dy = -1; dy <= 1; ++dy) {
        for (std::int64_t dx = -1; dx <= 1; ++dx) {
          const std::int64_t x = c.x + dx, y = c.y + dy, z = c.z + dz;
          if (g.In(x, y, z)) next_to_surface[g.Index(x, y, z)] = 1;
        }
      }
    }
  }
  std::vector<std::size_t> gaps, shell;
  std::size_t shell_seen = 0;
  for (std::size_t i = 0; i < g.size(); ++i) {
    if (conservative.dense[i]) {
      if (!surface.dense[i]) gaps.push_back(i);
    } else if (next_to_surface[i] && shell_seen++ % shell_stride == 0) {
      shell.push_back(i);
    }
  }
  const std::vector<int> gap_sides = query(gaps);
  for (std::size_t i = 0; i < gaps.size(); ++i)
    sides[gaps[i]] = static_cast<std::int8_t>(gap_sides[i]);
  const std::vector<int> shell_sides = query(shell);
  std::size_t inconsistent = 0;
  for (std::size_t i = 0; i < shell.size(); ++i) {
    if (shell_sides[i] != sides[shell[i]] && inconsistent++ < 3) {
      ADD_FAILURE() << "reference: " << VoxelName(g.Coord(shell[i])) << " has side "
                    << shell_sides[i] << " but its component " << int{sides[shell[i]]};
    }
  }
  std::cout << "  reference: " << components << " components, " << gaps.size()
            << " thin-mode gaps and " << shell.size() << " shell voxels queried\n";
  return sides;
}

struct SolidStats {
  std::uint64_t grid_voxels = 0, surface = 0, interior = 0, cubes = 0;
};

struct CgalOptions {
  std::size_t direct_limit = std::size_t{1} << 25;
  std::size_t shell_stride = 1;
  /// The least share of the grid's voxels the interior must have (the test is not trivial).
  double min_interior = 0.05;
  Corrupt corrupt;
};

/// FillInterior on `mesh`'s `mode` surface in `grid`: the solid must be the surface voxels and
/// the non-surface voxels whose centre CGAL puts strictly inside, and nothing else.
SolidStats ExpectSolidMatchesCgal(const Mesh& mesh, const GridTransform& grid, VoxelMode mode,
                                  const std::string& name, const CgalOptions& options = {}) {
  const std::string label = name + " " + ModeName(mode) + " " + std::to_string(grid.dims()[0]) +
                            "x" + std::to_string(grid.dims()[1]) + "x" +
                            std::to_string(grid.dims()[2]);
  SCOPED_TRACE(label);
  SolidStats stats;
  const Grid3 g(grid);
  stats.grid_voxels = g.size();
  const std::vector<FixedPoint3> fixed = SnapToVoxelSpace(mesh, grid);
  const Surface surface = MakeSurface(mesh, grid, mode);
  stats.surface = surface.keys.size();
  EXPECT_FALSE(surface.keys.empty());
  double fill_seconds = 0;
  std::optional<InteriorCubes> cubes = Fill(mesh, grid, surface.keys, &fill_seconds);
  if (!cubes) return stats;
  if (options.corrupt) options.corrupt(*cubes);
  EXPECT_EQ(cubes->method, FillMethod::kColumns) << MethodName(cubes->method);
  EXPECT_EQ(cubes->open_edges, 0u);
  EXPECT_EQ(CountOpenEdges(fixed, mesh.triangles), 0u);
  const std::vector<std::uint8_t> covered = CheckCubes(*cubes, grid, surface, label);
  stats.interior = cubes->voxel_count();
  stats.cubes = cubes->cube_count();

  const auto reference_start = std::chrono::steady_clock::now();
  const ExactInside cgal(fixed, mesh.triangles);
  if (cgal.degenerate_dropped() == 0) {
    EXPECT_TRUE(cgal.closed()) << "the reference is not closed";
  }
  const Surface conservative = mode == VoxelMode::kConservative
                                   ? surface
                                   : MakeSurface(mesh, grid, VoxelMode::kConservative);
  const std::vector<std::int8_t> sides =
      CgalSides(cgal, grid, surface, conservative, options.direct_limit, options.shell_stride);
  const double reference_seconds = Seconds(reference_start, std::chrono::steady_clock::now());

  const auto nodes = SurfaceNodes(surface.keys, cubes->depth);
  std::uint64_t inside = 0, missing = 0, extra = 0;
  std::string missing_at, extra_at;
  for (std::size_t i = 0; i < g.size(); ++i) {
    if (surface.dense[i]) continue;
    const bool want = sides[i] == 1;
    inside += want;
    if (want == (covered[i] != 0)) continue;
    const auto c = g.Coord(i);
    if (want && ++missing <= 8) {
      missing_at +=
          "\n    " + VoxelName(c) + " " + FreeNode(nodes, cubes->depth, c) + ", ColumnWinding " +
          std::to_string(ColumnWinding(fixed, mesh.triangles, static_cast<std::uint32_t>(c[0]),
                                       static_cast<std::uint32_t>(c[1]),
                                       static_cast<std::uint32_t>(c[2])));
    } else if (!want && ++extra <= 8) {
      extra_at += "\n    " + VoxelName(c) + (sides[i] == 0 ? " centre ON the mesh" : " outside") +
                  ", in " + HoldingCube(*cubes, c) + ", ColumnWinding " +
                  std::to_string(ColumnWinding(
                      fixed, mesh.triangles, static_cast<std::uint32_t>(c[0]),
                      static_cast<std::uint32_t>(c[1]), static_cast<std::uint32_t>(c[2])));
    }
  }
  EXPECT_EQ(missing, 0u) << missing << " voxels with centre strictly inside (CGAL) in no cube, of "
                         << inside << " inside:" << missing_at;
  EXPECT_EQ(extra, 0u) << extra
                       << " voxels in cubes whose centre is not strictly inside:" << extra_at;
  EXPECT_EQ(stats.interior, inside);
  EXPECT_GT(static_cast<double>(inside), options.min_interior * static_cast<double>(g.size()))
      << "the interior is too small to test anything";
  std::cout << "  " << label << ": " << stats.surface << " surface voxels, " << stats.interior
            << " interior voxels in " << stats.cubes << " cubes ("
            << (stats.cubes ? static_cast<double>(stats.interior) / static_cast<double>(stats.cubes)
                            : 0.0)
            << " voxels a cube); FillInterior " << fill_seconds << " s, reference "
            << reference_seconds << " s\n";
  ::testing::Test::RecordProperty(ModeName(mode) + std::string("_fill_seconds"),
                                  std::to_string(fill_seconds));
  return stats;
}

void CheckCgalFile(const std::string& file, std::uint32_t resolution,
                   std::initializer_list<VoxelMode> modes, double min_voxels_per_cube = 0,
                   const CgalOptions& options = {}) {
  const std::filesystem::path path = test::CgalMeshes() / file;
  SVOKIT_REQUIRE_FILE(path);
  const std::optional<Mesh> mesh = LoadCgalMesh(file);
  ASSERT_TRUE(mesh.has_value());
  StatusOr<GridTransform> grid = GridTransform::FitResolution(mesh->Bounds(), resolution);
  ASSERT_TRUE(grid.ok()) << grid.status().message();
  for (const VoxelMode mode : modes) {
    const SolidStats stats = ExpectSolidMatchesCgal(*mesh, *grid, mode, file, options);
    if (min_voxels_per_cube > 0) {
      EXPECT_GT(static_cast<double>(stats.interior),
                min_voxels_per_cube * static_cast<double>(stats.cubes))
          << file << ": the interior did not collapse into large cubes (" << stats.cubes
          << " cubes for " << stats.interior << " voxels)";
    }
  }
}

void CheckGeneratedClosed(const Mesh& mesh, const std::string& name, std::uint32_t resolution,
                          std::initializer_list<VoxelMode> modes, double min_voxels_per_cube = 0) {
  StatusOr<GridTransform> grid = GridTransform::FitResolution(mesh.Bounds(), resolution);
  ASSERT_TRUE(grid.ok()) << grid.status().message();
  for (const VoxelMode mode : modes) {
    const SolidStats stats = ExpectSolidMatchesCgal(mesh, *grid, mode, name);
    if (min_voxels_per_cube > 0) {
      EXPECT_GT(static_cast<double>(stats.interior),
                min_voxels_per_cube * static_cast<double>(stats.cubes));
    }
  }
}

TEST(SolidFill, Armadillo64) {
  CheckCgalFile("armadillo.off", 64, {VoxelMode::kConservative, VoxelMode::kThin});
}
TEST(SolidFill, Armadillo128) {
  CheckCgalFile("armadillo.off", 128, {VoxelMode::kConservative, VoxelMode::kThin}, 4);
}
TEST(SolidFill, Bunny00_64) {
  CheckCgalFile("bunny00.off", 64, {VoxelMode::kConservative, VoxelMode::kThin});
}
TEST(SolidFill, Bunny00_128) {
  CheckCgalFile("bunny00.off", 128, {VoxelMode::kConservative, VoxelMode::kThin}, 4);
}
TEST(SolidFill, Elephant64) {
  CheckCgalFile("elephant.off", 64, {VoxelMode::kConservative, VoxelMode::kThin});
}
TEST(SolidFill, Elephant128) {
  CheckCgalFile("elephant.off", 128, {VoxelMode::kConservative, VoxelMode::kThin}, 4);
}

// Slow: resolutions 256 and 512 (ctest label "slow"). The reference goes by components there.
TEST(SlowSolidFill, Armadillo256) {
  CheckCgalFile("armadillo.off", 256, {VoxelMode::kConservative, VoxelMode::kThin}, 4);
}
TEST(SlowSolidFill, Armadillo512) {
  CheckCgalFile("armadillo.off", 512, {VoxelMode::kConservative}, 4);
}
TEST(SlowSolidFill, Elephant256) {
  CheckCgalFile("elephant.off", 256, {VoxelMode::kConservative, VoxelMode::kThin}, 4);
}
TEST(SlowSolidFill, Elephant512) {
  CheckCgalFile("elephant.off", 512, {VoxelMode::kConservative}, 4);
}

// A box whose faces lie on planes of voxel centres, its vertical edges on columns through voxel
// centres and its top and bottom diagonals through a row of them: every column test ties, and
// simulation of simplicity must still give each column one crossing in and one out.
TEST(SolidFill, GridAlignedBox64) {
  const GridTransform grid({-2, 1, 0.5}, 0.5, {64, 64, 64});
  for (const FaceSplit split : {FaceSplit::kDiagonal02, FaceSplit::kDiagonal13, FaceSplit::kFan}) {
    const VoxelShape box = Box({3.5, 5.5, 2.5}, {43.5, 45.5, 52.5}, split);
    ASSERT_GT(SignedVolume6(box.points, box.triangles), 0);
    const Mesh mesh = ToWorld(box, grid);
    for (const VoxelMode mode : kModes) {
      const SolidStats stats = ExpectSolidMatchesCgal(
          mesh, grid, mode, "box split " + std::to_string(static_cast<int>(split)));
      // The centres strictly inside: x 4..42, y 6..44, z 3..51.
      EXPECT_EQ(stats.interior, 39u * 39u * 49u);
    }
  }
}

TEST(SolidFill, GridAlignedBox128) {
  // Not a power of two: the octree (128) reaches beyond the grid on two axes.
  const GridTransform grid({0.25, -3, 7}, 0.25, {112, 104, 128});
  const VoxelShape box = Box({7.5, 4.5, 9.5}, {103.5, 100.5, 109.5});
  ASSERT_GT(SignedVolume6(box.points, box.triangles), 0);
  const SolidStats stats =
      ExpectSolidMatchesCgal(ToWorld(box, grid), grid, VoxelMode::kConservative, "box");
  EXPECT_EQ(stats.interior, 95u * 95u * 99u);
  EXPECT_GT(stats.interior, 8 * stats.cubes);
}

// Faces through voxel centres along diagonals (x + y + z = const), edges through centres, and a
// vertex on every axis' column.
TEST(SolidFill, GridAlignedOctahedron64) {
  const GridTransform grid({0, 0, 0}, 1, {64, 64, 64});
  const VoxelShape octahedron = Octahedron({32.5, 31.5, 30.5}, 25);
  ASSERT_GT(SignedVolume6(octahedron.points, octahedron.triangles), 0);
  const Mesh mesh = ToWorld(octahedron, grid);
  for (const VoxelMode mode : kModes) ExpectSolidMatchesCgal(mesh, grid, mode, "octahedron");
}

// A hollow ball with a ball in its cavity: parity (CGAL) and winding number (±1 shells) agree.
TEST(SolidFill, NestedShells64) {
  CheckGeneratedClosed(NestedShells(), "nested shells", 64,
                       {VoxelMode::kConservative, VoxelMode::kThin});
}
TEST(SolidFill, NestedShells128) {
  CheckGeneratedClosed(NestedShells(), "nested shells", 128, {VoxelMode::kConservative}, 4);
}

// Triangles with corners of their own but at equal positions: merged by position, the surface is
// still a cycle.
TEST(SolidFill, UnsharedCornersAreStillACycle64) {
  const Mesh soup = Soup(test::Icosphere(3), 0, 0, 0, 1);
  CheckGeneratedClosed(soup, "icosphere soup", 64, {VoxelMode::kConservative, VoxelMode::kThin});
}

// ---------------------------------------------------------------------------------------------
// Broken meshes: the exact generalized winding number, |w| ≥ ½.

/// FillInterior on `mesh` in a grid of `resolution`, both modes, against the exact winding number
/// at every non-surface voxel centre. With `exact`, no voxel may disagree (the surface is a cycle:
/// the winding number is an integer off it); otherwise at most 0.01 % of the grid's voxels, each
/// within one voxel (Chebyshev) of a surface voxel.
void ExpectSolidMatchesWindingNumbers(const Mesh& mesh, const std::string& name,
                                      std::uint32_t resolution, FillMethod method, bool exact,
                                      double min_voxels_per_cube = 0, const Corrupt& corrupt = {}) {
  StatusOr<GridTransform> grid_or = GridTransform::FitResolution(mesh.Bounds(), resolution);
  ASSERT_TRUE(grid_or.ok()) << grid_or.status().message();
  const GridTransform& grid = *grid_or;
  const Grid3 g(grid);
  const std::vector<FixedPoint3> fixed = SnapToVoxelSpace(mesh, grid);
  std::vector<Vec3d> positions;
  for (const FixedPoint3& f : fixed) positions.push_back(FixedToVoxel(f));
  const std::uint64_t open = CountOpenEdges(fixed, mesh.triangles);
  if (method == FillMethod::kColumns) {
    EXPECT_EQ(open, 0u) << name;
  } else {
    EXPECT_GT(open, 0u) << name;
  }

  // The exact winding number at every voxel centre outside the thin surface (a subset of the
  // conservative one), in parallel.
  const Surface thin = MakeSurface(mesh, grid, VoxelMode::kThin);
  const auto start = std::chrono::steady_clock::now();
  std::vector<double> w(g.size(), std::numeric_limits<double>::quiet_NaN());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, g.size(), 64), [&](const auto& r) {
    for (std::size_t i = r.begin(); i < r.end(); ++i) {
      if (!thin.dense[i]) w[i] = WindingNumber(positions, mesh.triangles, g.Centre(i));
    }
  });
  const double reference_seconds = Seconds(start, std::chrono::steady_clock::now());

  for (const VoxelMode mode : kModes) {
    const std::string label = name + " " + ModeName(mode) + " " + std::to_string(g.nx) + "x" +
                              std::to_string(g.ny) + "x" + std::to_string(g.nz);
    SCOPED_TRACE(label);
    const Surface surface = mode == VoxelMode::kThin ? thin : MakeSurface(mesh, grid, mode);
    double fill_seconds = 0;
    std::optional<InteriorCubes> cubes = Fill(mesh, grid, surface.keys, &fill_seconds);
    if (!cubes) continue;
    if (corrupt) corrupt(*cubes);
    EXPECT_EQ(cubes->method, method) << MethodName(cubes->method);
    EXPECT_EQ(cubes->open_edges, open);
    const std::vector<std::uint8_t> covered = CheckCubes(*cubes, grid, surface, label);
    const auto nodes = SurfaceNodes(surface.keys, cubes->depth);

    std::uint64_t inside = 0, disagree = 0, far = 0;
    std::string disagree_at, far_at;
    for (std::size_t i = 0; i < g.size(); ++i) {
      if (surface.dense[i]) continue;
      const bool want = std::abs(w[i]) >= 0.5;
      inside += want;
      if (want == (covered[i] != 0)) continue;
      const bool near = NearSurface(g, surface.dense, i);
      const auto c = g.Coord(i);
      std::ostringstream s;
      s.precision(17);
      s << "\n    " << VoxelName(c) << " w = " << w[i] << (want ? " inside but " : " outside but ")
        << (want ? FreeNode(nodes, cubes->depth, c) : "in " + HoldingCube(*cubes, c))
        << (near ? "" : " (not next to the surface)");
      if (++disagree <= 8) disagree_at += s.str();
      if (!near && ++far <= 8) far_at += s.str();
    }
    EXPECT_EQ(far, 0u) << far
                       << " disagreements farther than one voxel from the surface:" << far_at;
    EXPECT_LE(static_cast<double>(disagree), 1e-4 * static_cast<double>(g.size()))
        << disagree << " disagreements of " << g.size() << " voxels:" << disagree_at;
    if (exact) {
      EXPECT_EQ(disagree, 0u) << "the surface is a cycle, the winding number an integer:"
                              << disagree_at;
    }
    EXPECT_GT(static_cast<double>(inside), 0.01 * static_cast<double>(g.size()))
        << "the interior is too small to test anything";
    EXPECT_GE(static_cast<double>(cubes->voxel_count()),
              min_voxels_per_cube * static_cast<double>(cubes->cube_count()))
        << "the interior did not collapse into larger cubes";
    std::cout << "  " << label << ": " << MethodName(cubes->method) << ", " << cubes->open_edges
              << " open edges, " << surface.keys.size() << " surface voxels, "
              << cubes->voxel_count() << " interior voxels in " << cubes->cube_count() << " cubes, "
              << inside << " by the winding number, " << disagree << " disagreements; FillInterior "
              << fill_seconds << " s, reference " << reference_seconds << " s\n";
  }
}

TEST(SolidFillBroken, ElephantWithHoles) {
  std::optional<Mesh> mesh = LoadCgalMesh("elephant-with-holes.off");
  if (!mesh) {
    // Not shipped: holes of our own.
    SVOKIT_REQUIRE_FILE(test::CgalMeshes() / "elephant.off");
    mesh = WithCutHoles(*LoadCgalMesh("elephant.off"), 97);
  }
  ExpectSolidMatchesWindingNumbers(*mesh, "elephant with holes", 32, FillMethod::kWindingNumber,
                                   false);
}

TEST(SolidFillBroken, ElephantWithCutHoles) {
  SVOKIT_REQUIRE_FILE(test::CgalMeshes() / "elephant.off");
  const Mesh mesh = WithCutHoles(*LoadCgalMesh("elephant.off"), 97);
  ASSERT_LT(mesh.triangles.size(), LoadCgalMesh("elephant.off")->triangles.size());
  ExpectSolidMatchesWindingNumbers(mesh, "elephant, fans cut", 40, FillMethod::kWindingNumber,
                                   false);
}

TEST(SlowSolidFillBroken, ElephantWithHoles64) {
  const std::filesystem::path path = test::CgalMeshes() / "elephant-with-holes.off";
  SVOKIT_REQUIRE_FILE(path);
  ExpectSolidMatchesWindingNumbers(*LoadCgalMesh("elephant-with-holes.off"), "elephant with holes",
                                   64, FillMethod::kWindingNumber, false);
}

// A bowl: a sphere with its cap above z = 0.5 removed.
TEST(SolidFillBroken, OpenCup) {
  ExpectSolidMatchesWindingNumbers(WithoutCap(test::Icosphere(3), 0.5), "open cup", 48,
                                   FillMethod::kWindingNumber, false, 2);
}

TEST(SolidFillBroken, FlippedTriangles) {
  ExpectSolidMatchesWindingNumbers(WithFlippedTriangles(test::Icosphere(3), 23),
                                   "icosphere, every 23rd triangle flipped", 48,
                                   FillMethod::kWindingNumber, false);
}

// Corners of their own, every 31st triangle left out, one corner of every 9th moved by up to
// 0.3 voxel.
TEST(SolidFillBroken, TriangleSoup) {
  const Mesh soup = Soup(test::Icosphere(3), 31, 9, 0.3 * 2.0 / 48, 5);
  ExpectSolidMatchesWindingNumbers(soup, "jittered soup", 48, FillMethod::kWindingNumber, false);
}

TEST(SlowSolidFillBroken, TriangleSoup96) {
  const Mesh soup = Soup(test::Icosphere(3), 31, 9, 0.3 * 2.0 / 96, 5);
  ExpectSolidMatchesWindingNumbers(soup, "jittered soup", 96, FillMethod::kWindingNumber, false);
}

// Cycles that are not boundaries of one solid: winding 2 where two spheres overlap, −1 in a sphere
// turned inside out. Both are inside (|w| ≥ ½), found by columns.
TEST(SolidFillBroken, OverlappingSpheres) {
  ExpectSolidMatchesWindingNumbers(OverlappingSpheres(), "overlapping spheres", 64,
                                   FillMethod::kColumns, true);
}

TEST(SolidFillBroken, FlippedComponent) {
  ExpectSolidMatchesWindingNumbers(FlippedComponent(), "flipped component", 64,
                                   FillMethod::kColumns, true);
}

// ---------------------------------------------------------------------------------------------
// The checks above fail on wrong results: FillInterior's output edited before it is checked.

/// How many failures `run` reports (intercepted: they do not fail this test).
int Failures(const std::function<void()>& run) {
  ::testing::TestPartResultArray results;
  {
    const ::testing::ScopedFakeTestPartResultReporter reporter(
        ::testing::ScopedFakeTestPartResultReporter::INTERCEPT_ONLY_CURRENT_THREAD, &results);
    run();
  }
  int failures = 0;
  for (int i = 0; i < results.size(); ++i) failures += results.GetTestPartResult(i).failed();
  return failures;
}

/// The level of the largest cubes.
std::uint32_t LargestLevel(const InteriorCubes& cubes) {
  std::uint32_t level = 0;
  while (level + 1 < cubes.levels.size() && cubes.levels[level].empty()) ++level;
  return level;
}

void Insert(std::vector<std::uint64_t>& level, std::uint64_t key) {
  level.insert(std::upper_bound(level.begin(), level.end(), key), key);
}

const std::pair<const char*, Corrupt> kCorruptions[] = {
    {"nothing", [](InteriorCubes&) {}},
    {"a largest cube dropped",
     [](InteriorCubes& c) {
       auto& l = c.levels[LargestLevel(c)];
       l.erase(l.begin() + static_cast<std::ptrdiff_t>(l.size() / 2));
     }},
    {"a voxel outside added",
     [](InteriorCubes& c) { Insert(c.levels[c.depth], MortonEncode(0, 0, 0)); }},
    {"a cube covered twice",
     [](InteriorCubes& c) {
       const std::uint32_t level = LargestLevel(c);
       Insert(c.levels[level + 1], c.levels[level][0] << 3 | 5);
     }},
    {"two keys out of order",
     [](InteriorCubes& c) {
       auto& l = c.levels[c.depth];
       std::swap(l[0], l[1]);
     }},
};

TEST(SolidFillChecks, FailOnWrongCubesOfACycle) {
  const GridTransform grid({0, 0, 0}, 1, {64, 64, 64});
  const Mesh box = ToWorld(Box({3.5, 5.5, 2.5}, {43.5, 45.5, 52.5}), grid);
  std::vector<std::pair<const char*, Corrupt>> corruptions(std::begin(kCorruptions),
                                                           std::end(kCorruptions));
  corruptions.push_back({"a surface voxel added", [](InteriorCubes& c) {
                           Insert(c.levels[c.depth], MortonEncode(3, 10, 10));
                         }});
  // The same voxels, but not as the maximal free nodes.
  corruptions.push_back({"a cube split into its children", [](InteriorCubes& c) {
                           const std::uint32_t level = LargestLevel(c);
                           const std::uint64_t key = c.levels[level].back();
                           c.levels[level].pop_back();
                           for (std::uint64_t i = 0; i < 8; ++i) {
                             Insert(c.levels[level + 1], key << 3 | i);
                           }
                         }});
  corruptions.push_back({"the last level missing", [](InteriorCubes& c) { c.levels.pop_back(); }});
  for (const auto& [name, corrupt] : corruptions) {
    const int failures = Failures([&, &corrupt = corrupt] {
      ExpectSolidMatchesCgal(box, grid, VoxelMode::kConservative, "box", {.corrupt = corrupt});
    });
    if (std::string(name) == "nothing") {
      EXPECT_EQ(failures, 0) << name;
    } else {
      EXPECT_GT(failures, 0) << name << " went unnoticed";
    }
  }
}

TEST(SolidFillChecks, FailOnWrongCubesByWindingNumber) {
  const Mesh cup = WithoutCap(test::Icosphere(3), 0.5);
  for (const auto& [name, corrupt] : kCorruptions) {
    const int failures = Failures([&, &corrupt = corrupt] {
      ExpectSolidMatchesWindingNumbers(cup, "open cup", 32, FillMethod::kWindingNumber, false, 0,
                                       corrupt);
    });
    if (std::string(name) == "nothing") {
      EXPECT_EQ(failures, 0) << name;
    } else {
      EXPECT_GT(failures, 0) << name << " went unnoticed";
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Determinism and bad input.

void ExpectSameForOneAndTwoThreads(const Mesh& mesh, std::uint32_t resolution,
                                   const std::string& name) {
  StatusOr<GridTransform> grid = GridTransform::FitResolution(mesh.Bounds(), resolution);
  ASSERT_TRUE(grid.ok());
  for (const VoxelMode mode : kModes) {
    SCOPED_TRACE(name + " " + ModeName(mode));
    const Surface surface = MakeSurface(mesh, *grid, mode);
    std::optional<InteriorCubes> runs[2];
    for (const std::size_t threads : {1, 2}) {
      const ThreadLimit limit(threads);
      runs[threads - 1] = Fill(mesh, *grid, surface.keys, nullptr);
      ASSERT_TRUE(runs[threads - 1].has_value());
    }
    EXPECT_EQ(runs[0]->depth, runs[1]->depth);
    EXPECT_EQ(runs[0]->method, runs[1]->method);
    EXPECT_EQ(runs[0]->open_edges, runs[1]->open_edges);
    ASSERT_EQ(runs[0]->levels.size(), runs[1]->levels.size());
    for (std::size_t l = 0; l < runs[0]->levels.size(); ++l) {
      EXPECT_EQ(runs[0]->levels[l], runs[1]->levels[l]) << "level " << l;
    }
    EXPECT_GT(runs[0]->voxel_count(), 0u);
  }
}

TEST(SolidFillThreads, SameCubesForOneAndTwoThreads) {
  ExpectSameForOneAndTwoThreads(WithoutCap(test::Icosphere(3), 0.5), 64, "open cup");
  ExpectSameForOneAndTwoThreads(NestedShells(), 64, "nested shells");
  for (const auto& [file, resolution] :
       {std::pair{"armadillo.off", 128}, std::pair{"elephant-with-holes.off", 64}}) {
    const std::optional<Mesh> mesh = LoadCgalMesh(file);
    if (!mesh) {
      if (test::TestDataRequired()) ADD_FAILURE() << file << " is missing";
      continue;
    }
    ExpectSameForOneAndTwoThreads(*mesh, static_cast<std::uint32_t>(resolution), file);
  }
}

TEST(SolidFillInput, EmptySurfaceIsAnError) {
  const Mesh sphere = test::Icosphere(2);
  StatusOr<GridTransform> grid = GridTransform::FitResolution(sphere.Bounds(), 32);
  ASSERT_TRUE(grid.ok());
  const StatusOr<InteriorCubes> cubes = FillInterior(sphere, *grid, {});
  EXPECT_FALSE(cubes.ok());
  EXPECT_FALSE(cubes.status().message().empty());
}

// Closed surfaces that enclose nothing: a triangle and its reverse; a flat "pillow" (a square
// and its reverse split along the other diagonal) in a plane of voxel centres, horizontal and
// vertical (holding columns). And an open triangle, which the winding number decides.
TEST(SolidFillInput, ZeroVolumeMeshesHaveNoInterior) {
  const GridTransform grid({0, 0, 0}, 1, {16, 16, 16});
  const VoxelShape back_to_back{{{2.5, 3.5, 4.5}, {12.5, 5.5, 4.5}, {6.5, 13.5, 4.5}},
                                {{0, 1, 2}, {0, 2, 1}}};
  // Corners 0..3 counter-clockwise; the top split along 0–2, the bottom along 1–3.
  const auto pillow = [](const std::vector<Vec3d>& q) {
    return VoxelShape{q, {{0, 1, 2}, {0, 2, 3}, {1, 0, 3}, {1, 3, 2}}};
  };
  const VoxelShape flat =
      pillow({{2.5, 2.5, 6.5}, {12.5, 2.5, 6.5}, {12.5, 12.5, 6.5}, {2.5, 12.5, 6.5}});
  const VoxelShape upright =
      pillow({{7.5, 2.5, 2.5}, {7.5, 12.5, 2.5}, {7.5, 12.5, 12.5}, {7.5, 2.5, 12.5}});
  const VoxelShape diagonal =
      pillow({{2.5, 2.5, 2.5}, {12.5, 12.5, 2.5}, {12.5, 12.5, 12.5}, {2.5, 2.5, 12.5}});
  const std::pair<VoxelShape, const char*> closed[] = {{back_to_back, "back-to-back triangles"},
                                                       {flat, "horizontal pillow"},
                                                       {upright, "vertical pillow"},
                                                       {diagonal, "diagonal vertical pillow"}};
  for (const auto& [shape, name] : closed) {
    const Mesh mesh = ToWorld(shape, grid);
    for (const VoxelMode mode : kModes) {
      SCOPED_TRACE(std::string(name) + " " + ModeName(mode));
      const Surface surface = MakeSurface(mesh, grid, mode);
      ASSERT_FALSE(surface.keys.empty());
      const std::optional<InteriorCubes> cubes = Fill(mesh, grid, surface.keys, nullptr);
      ASSERT_TRUE(cubes.has_value());
      EXPECT_EQ(cubes->method, FillMethod::kColumns);
      EXPECT_EQ(cubes->open_edges, 0u);
      EXPECT_EQ(cubes->voxel_count(), 0u);
      EXPECT_EQ(cubes->cube_count(), 0u);
      CheckCubes(*cubes, grid, surface, name);
    }
  }
  const Mesh open = ToWorld(VoxelShape{back_to_back.points, {{0, 1, 2}}}, grid);
  const Surface surface = MakeSurface(open, grid, VoxelMode::kConservative);
  const std::optional<InteriorCubes> cubes = Fill(open, grid, surface.keys, nullptr);
  ASSERT_TRUE(cubes.has_value());
  EXPECT_EQ(cubes->method, FillMethod::kWindingNumber);
  EXPECT_EQ(cubes->open_edges, 3u);
  EXPECT_EQ(cubes->voxel_count(), 0u);
}

}  // namespace
}  // namespace svokit
