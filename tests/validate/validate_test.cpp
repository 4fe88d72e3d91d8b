// svo-validate's checks: valid files pass (conservative, thin, every brick option, an open
// mesh, real meshes), the occupancy sandwich agrees with a brute-force distance, and each
// deliberately broken file is caught by the check meant for it, with the finding's kind.

#include "svokit/validate/validate.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <map>

#include <fmt/format.h>

#include "svokit/core/morton.hpp"
#include "svokit/core/thread_limit.hpp"
#include "svokit/formats/mesh_import.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/svo/build_options.hpp"
#include "svokit/svo/compact_build.hpp"
#include "svokit/svo/compact_svo.hpp"
#include "svokit/svo/reference_build.hpp"
#include "svokit/validate/checks.hpp"
#include "svokit/voxelize/voxel_space.hpp"
#include "svokit/voxelize/voxelize.hpp"
#include "tests/formats/svo_v1_writer.hpp"
#include "tests/test_util.hpp"

namespace svokit::validate {
namespace {

Mesh Load(const std::filesystem::path& path) {
  auto m = ImportMesh(path);
  EXPECT_TRUE(m.ok()) << m.status().message();
  return m.ok() ? std::move(*m) : Mesh{};
}

const Mesh& Torus() {
  static const Mesh mesh = Load(test::DataDir() / "uv-torus.obj");
  return mesh;
}

// An open surface: a wavy height field, no boundary closed.
Mesh OpenPatch() {
  Mesh m;
  const int n = 12;
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) {
      m.positions.push_back(
          {i / double(n), j / double(n), 0.15 * std::sin(5.0 * i / n) * std::cos(4.0 * j / n)});
    }
  }
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const auto v = [&](int a, int b) { return std::uint32_t(b * (n + 1) + a); };
      m.triangles.push_back({v(i, j), v(i + 1, j), v(i + 1, j + 1)});
      m.triangles.push_back({v(i, j), v(i + 1, j + 1), v(i, j + 1)});
    }
  }
  EnsureDefaultMaterial(m);
  return m;
}

VoxelSet VoxelsOf(const Mesh& mesh, std::uint32_t resolution, VoxelMode mode) {
  auto grid = GridTransform::FitResolution(mesh.Bounds(), resolution);
  EXPECT_TRUE(grid.ok());
  VoxelizeOptions options;
  options.mode = mode;
  options.colors = options.normals = true;
  auto voxels = Voxelize(mesh, *grid, options);
  EXPECT_TRUE(voxels.ok()) << voxels.status().message();
  return voxels.ok() ? std::move(*voxels) : VoxelSet{};
}

Svo Build(const VoxelSet& voxels, const Mesh& mesh, std::uint32_t side = 3, bool contours = true,
          int brick_filter = kBrickFilter) {
  BuildOptions options;
  options.brick_side = side;
  options.contours = contours;
  options.brick_filter = brick_filter;
  auto svo = BuildReferenceSvo(voxels, &mesh, options);
  EXPECT_TRUE(svo.ok()) << svo.status().message();
  return svo.ok() ? std::move(*svo) : Svo{};
}

// The file of the voxels' octree, as svo-build writes it.
std::vector<std::uint8_t> File(const VoxelSet& voxels, const Mesh& mesh, std::uint32_t side = 3,
                               bool contours = true) {
  BuildOptions options;
  options.brick_side = side;
  options.contours = contours;
  auto svo = BuildCompactSvo(voxels, &mesh, options);
  EXPECT_TRUE(svo.ok()) << svo.status().message();
  return svo.ok() ? EncodeSvo(*svo) : std::vector<std::uint8_t>{};
}

Report ValidateBytes(const std::vector<std::uint8_t>& bytes, const Mesh* mesh) {
  auto file = DecodeSvoLenient(bytes, "t.svo");
  EXPECT_TRUE(file.ok()) << file.status().message();
  if (!file.ok()) return {};
  ValidateOptions options;
  options.mesh = mesh;
  return Validate(*file, "t.svo", options);
}

const CheckResult& Check(const Report& r, const std::string& name) {
  for (const CheckResult& c : r.checks) {
    if (c.name == name) return c;
  }
  static const CheckResult none("none");
  ADD_FAILURE() << "no check " << name;
  return none;
}

std::uint64_t Count(const CheckResult& c, const std::string& kind) {
  const auto it = c.counts.find(kind);
  return it == c.counts.end() ? 0 : it->second;
}

std::uint64_t Stat(const CheckResult& c, const std::string& key) {
  for (const auto& [k, v] : c.stats) {
    if (k == key) return v;
  }
  ADD_FAILURE() << "no stat " << key << " in " << c.name;
  return 0;
}

// Every check passed or was skipped for a stated reason; occupancy and contours really ran.
void ExpectValid(const Report& r, bool contours = true) {
  EXPECT_TRUE(r.ok()) << r.Text();
  EXPECT_EQ(Check(r, "structure").state, CheckResult::State::kPassed);
  EXPECT_EQ(Check(r, "occupancy").state, CheckResult::State::kPassed) << r.Text();
  if (contours) {
    EXPECT_EQ(Check(r, "contour_surface").state, CheckResult::State::kPassed);
  }
  const CheckResult& occ = Check(r, "occupancy");
  EXPECT_EQ(Stat(occ, "matched"), Stat(occ, "leaves"));
  EXPECT_GT(Stat(occ, "required"), 0u);
}

// Kinds of failing findings across all checks, e.g. {"occupancy/missing_voxel": 1}.
std::map<std::string, std::uint64_t> Kinds(const Report& r) {
  std::map<std::string, std::uint64_t> out;
  for (const CheckResult& c : r.checks) {
    for (const auto& [kind, n] : c.counts) out[c.name + "/" + kind] += n;
  }
  return out;
}

std::string Describe(const std::map<std::string, std::uint64_t>& kinds) {
  std::string s;
  for (const auto& [k, n] : kinds) s += k + "=" + std::to_string(n) + " ";
  return s;
}

// Closest distance from p to triangle abc (Ericson, Real-Time Collision Detection 5.1.5).
double PointTriangleDistance(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  const Vec3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = Dot(ab, ap), d2 = Dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return Length(p - a);
  const Vec3d bp = p - b;
  const double d3 = Dot(ab, bp), d4 = Dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return Length(p - b);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return Length(p - (a + ab * (d1 / (d1 - d3))));
  const Vec3d cp = p - c;
  const double d5 = Dot(ab, cp), d6 = Dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return Length(p - c);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return Length(p - (a + ac * (d2 / (d2 - d6))));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    return Length(p - (b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)))));
  }
  const double denom = 1 / (va + vb + vc);
  return Length(p - (a + ab * (vb * denom) + ac * (vc * denom)));
}

// Voxel-space distance from voxel (x, y, z)'s centre to the snapped mesh, by brute force.
double CentreDistance(const Mesh& mesh, const GridTransform& grid, MortonCoord c) {
  const Vec3d p{c.x + 0.5, c.y + 0.5, c.z + 0.5};
  double best = std::numeric_limits<double>::infinity();
  for (const Triangle& t : mesh.triangles) {
    const auto v = [&](int i) {
      return FixedToVoxel(SnapToVoxelSpace(mesh.positions[t[i]], grid));
    };
    best = std::min(best, PointTriangleDistance(p, v(0), v(1), v(2)));
  }
  return best;
}

// ---------------------------------------------------------------------------------------------
// Valid files

TEST(Validate, ValidFilesPassEveryCheck) {
  const VoxelSet conservative = VoxelsOf(Torus(), 64, VoxelMode::kConservative);
  ExpectValid(ValidateBytes(File(conservative, Torus()), &Torus()));
  ExpectValid(ValidateBytes(File(conservative, Torus(), 2, false), &Torus()), false);
  ExpectValid(ValidateBytes(File(conservative, Torus(), 0, true), &Torus()));
  const VoxelSet thin = VoxelsOf(Torus(), 64, VoxelMode::kThin);
  const Report t = ValidateBytes(File(thin, Torus()), &Torus());
  ExpectValid(t);
  EXPECT_NE(Check(t, "occupancy").note.find("thin"), std::string::npos);
  // Without the mesh, the mesh checks are skipped, not passed.
  const Report bare = ValidateBytes(File(conservative, Torus()), nullptr);
  EXPECT_TRUE(bare.ok());
  EXPECT_EQ(Check(bare, "occupancy").state, CheckResult::State::kSkipped);
  EXPECT_EQ(Check(bare, "bricks").state, CheckResult::State::kPassed);
}

// The brick check is the long one (4 s at 1024³): it counts the nodes it filters and compares,
// rather than sitting at 0 % until it ends.
TEST(Validate, TheBrickCheckReportsItsNodesAsItGoes) {
  const VoxelSet voxels = VoxelsOf(Torus(), 48, VoxelMode::kConservative);
  auto file = DecodeSvoLenient(File(voxels, Torus()), "t.svo");
  ASSERT_TRUE(file.ok()) << file.status().message();
  Progress progress(Progress::Style::kQuiet);
  ValidateOptions options;
  options.mesh = &Torus();
  ExpectValid(Validate(*file, "t.svo", options, progress));
  std::uint64_t nodes = 0;
  for (const SvoLevel& lv : file->svo.levels) nodes += lv.node_count;
  bool found = false;
  for (const Progress::Timing& t : progress.timings()) {
    if (t.stage != "bricks") continue;
    found = true;
    EXPECT_GT(t.units, nodes);  // each node compared, and filtered
    EXPECT_EQ(t.units_done, t.units);
  }
  EXPECT_TRUE(found);
}

TEST(Validate, OpenMeshPasses) {
  const Mesh patch = OpenPatch();
  for (VoxelMode mode : {VoxelMode::kConservative, VoxelMode::kThin}) {
    ExpectValid(ValidateBytes(File(VoxelsOf(patch, 100, mode), patch), &patch));
  }
}

TEST(Validate, RealMeshesPass) {
  const auto armadillo = test::CgalMeshes() / "armadillo.off";
  SVOKIT_REQUIRE_FILE(armadillo);
  const Mesh mesh = Load(armadillo);
  for (VoxelMode mode : {VoxelMode::kConservative, VoxelMode::kThin}) {
    const Report r = ValidateBytes(File(VoxelsOf(mesh, 160, mode), mesh), &mesh);
    ExpectValid(r);
    std::printf("%s", r.Text().c_str());
  }
  const auto wuson = test::AssimpModels() / "OBJ" / "WusonOBJ.obj";
  SVOKIT_REQUIRE_FILE(wuson);
  const Mesh w = Load(wuson);
  ExpectValid(ValidateBytes(File(VoxelsOf(w, 128, VoxelMode::kConservative), w), &w));
}

// The OpenVDB distances against brute force over every voxel of a small grid: the voxels the
// check requires are exactly those within h/2, and the voxelizer's leaves match the sandwich.
TEST(Validate, SandwichAgreesWithBruteForceDistances) {
  const VoxelSet voxels = VoxelsOf(Torus(), 24, VoxelMode::kConservative);
  std::uint64_t required = 0;
  const auto& d = voxels.grid.dims();
  for (std::uint32_t z = 0; z < d[2]; ++z) {
    for (std::uint32_t y = 0; y < d[1]; ++y) {
      for (std::uint32_t x = 0; x < d[0]; ++x) {
        const double dist = CentreDistance(Torus(), voxels.grid, {x, y, z});
        const bool leaf =
            std::binary_search(voxels.keys.begin(), voxels.keys.end(), MortonEncode(x, y, z));
        if (dist <= 0.5) {
          ++required;
          EXPECT_TRUE(leaf) << x << " " << y << " " << z;
        }
        if (leaf) {
          EXPECT_LE(dist, 0.5 * std::sqrt(3.0)) << x << " " << y << " " << z;
        }
      }
    }
  }
  const Report r = ValidateBytes(File(voxels, Torus()), &Torus());
  ExpectValid(r);
  const std::uint64_t vdb_required = Stat(Check(r, "occupancy"), "required");
  // Only voxels within the tolerance of exactly h/2 may be counted differently.
  EXPECT_NEAR(double(vdb_required), double(required), 2.0);
  EXPECT_GT(required, 100u);
}

// ---------------------------------------------------------------------------------------------
// Broken files, one per check

struct Fixture {
  Mesh mesh = Torus();
  VoxelSet voxels = VoxelsOf(mesh, 48, VoxelMode::kConservative);
  Svo svo = Build(voxels, mesh, 3, true, 1);  // version 1's bricks are by filter 1
  std::vector<std::uint8_t> bytes = test::EncodeSvoV1(svo);
};
const Fixture& Base() {
  static const Fixture f;
  return f;
}

TEST(ValidateMutation, BaseFileIsValid) {
  ExpectValid(ValidateBytes(Base().bytes, &Base().mesh));
}

TEST(ValidateMutation, FlippedBitsAreChecksumFindings) {
  // A bit inside the last section's payload (META), then in the section table.
  auto bytes = Base().bytes;
  bytes[bytes.size() - 3] ^= 0x08;
  Report r = ValidateBytes(bytes, &Base().mesh);
  EXPECT_EQ(Count(Check(r, "structure"), "section_checksum"), 1u) << r.Text();
  bytes = Base().bytes;
  bytes[40] ^= 0x01;  // first table entry's tag
  r = ValidateBytes(bytes, &Base().mesh);
  EXPECT_EQ(Count(Check(r, "structure"), "header_checksum"), 1u) << r.Text();
  EXPECT_FALSE(r.ok());
}

TEST(ValidateMutation, TruncatedFileIsAFileSizeFinding) {
  auto bytes = Base().bytes;
  bytes.resize(bytes.size() - 200);
  const Report r = ValidateBytes(bytes, &Base().mesh);
  const CheckResult& s = Check(r, "structure");
  EXPECT_EQ(Count(s, "file_size"), 1u) << r.Text();
  EXPECT_GE(Count(s, "section_bounds"), 1u) << r.Text();
  EXPECT_EQ(Check(r, "occupancy").state, CheckResult::State::kSkipped);
}

TEST(ValidateMutation, RemovedLeafIsAMissingVoxel) {
  const Fixture& f = Base();
  // The leaf whose centre is nearest the surface (brute force), removed with its attributes.
  std::size_t victim = 0;
  double best = 1e9;
  for (std::size_t i = 0; i < f.voxels.size(); i += 7) {
    const double d = CentreDistance(f.mesh, f.voxels.grid, MortonDecode(f.voxels.keys[i]));
    if (d < best) best = d, victim = i;
  }
  ASSERT_LT(best, 0.45);
  VoxelSet v = f.voxels;
  const auto at = static_cast<std::ptrdiff_t>(victim);
  v.keys.erase(v.keys.begin() + at);
  v.colors.erase(v.colors.begin() + at);
  v.normals.erase(v.normals.begin() + at);
  v.coverage.erase(v.coverage.begin() + at);
  const Report r = ValidateBytes(File(v, f.mesh), &f.mesh);
  const CheckResult& occ = Check(r, "occupancy");
  auto kinds = Kinds(r);
  EXPECT_EQ(kinds["occupancy/missing_voxel"], 1u) << Describe(kinds);
  // The surface points in the hole belong to no leaf: the contour sampling sees it too.
  kinds.erase("occupancy/missing_voxel");
  kinds.erase("contour_surface/point_outside_octree");
  EXPECT_TRUE(kinds.empty()) << Describe(kinds);
  ASSERT_EQ(occ.examples.size(), 1u);
  const MortonCoord c = MortonDecode(f.voxels.keys[victim]);
  EXPECT_EQ(*occ.examples[0].voxel, (std::array<std::int64_t, 3>{c.x, c.y, c.z}));
  EXPECT_NEAR(*occ.examples[0].distance, best, 1e-4);
}

TEST(ValidateMutation, StrayLeafIsAnExtraVoxel) {
  const Fixture& f = Base();
  // The torus's hole: the grid's centre column, far from the surface.
  const auto& d = f.voxels.grid.dims();
  const MortonCoord stray{d[0] / 2, d[1] / 2, d[2] / 2};
  const double dist = CentreDistance(f.mesh, f.voxels.grid, stray);
  ASSERT_GT(dist, 2.0);
  VoxelSet v = f.voxels;
  const std::uint64_t key = MortonEncode(stray.x, stray.y, stray.z);
  const auto at = std::lower_bound(v.keys.begin(), v.keys.end(), key) - v.keys.begin();
  v.keys.insert(v.keys.begin() + at, key);
  v.colors.insert(v.colors.begin() + at, Rgba{1, 0, 0, 1});
  v.normals.insert(v.normals.begin() + at, Vec3f{0, 0, 1});
  v.coverage.insert(v.coverage.begin() + at, 1.f);
  const Report r = ValidateBytes(File(v, f.mesh), &f.mesh);
  const CheckResult& occ = Check(r, "occupancy");
  EXPECT_EQ(Count(occ, "extra_voxel"), 1u) << r.Text();
  EXPECT_EQ(Count(occ, "missing_voxel"), 0u);
  ASSERT_EQ(occ.examples.size(), 1u);
  EXPECT_EQ(*occ.examples[0].voxel, (std::array<std::int64_t, 3>{stray.x, stray.y, stray.z}));
  // Only the occupancy check can know: structure, bricks and contours still hold.
  for (const char* check : {"structure", "bricks", "contours"}) {
    EXPECT_NE(Check(r, check).state, CheckResult::State::kFailed) << check;
  }
}

TEST(ValidateMutation, WrongMaskIsAStructureFinding) {
  Svo svo = Base().svo;
  // A child bit that names a child the next level does not hold (re-encoded: checksums valid).
  auto& nodes = svo.levels[svo.depth - 2].nodes;
  const auto it = std::find_if(nodes.begin(), nodes.end(),
                               [](const SvoNode& x) { return x.child_mask != 0xff; });
  ASSERT_NE(it, nodes.end());
  SvoNode& n = *it;
  const unsigned free = std::countr_one(static_cast<unsigned>(n.child_mask));
  n.child_mask = static_cast<std::uint8_t>(n.child_mask | (1u << free));
  Report r = ValidateBytes(test::EncodeSvoV1(svo), &Base().mesh);
  const CheckResult& s = Check(r, "structure");
  // The next node's first child no longer follows; the sums then resynchronize (one finding).
  ASSERT_LT(static_cast<std::size_t>(it - nodes.begin()) + 1, nodes.size());
  EXPECT_EQ(s.counts, (std::map<std::string, std::uint64_t>{{"child_index", 1}})) << r.Text();
  ASSERT_EQ(s.examples.size(), 1u);
  EXPECT_NE(s.examples[0].message.find(fmt::format("level {} node {}: first child index",
                                                   svo.depth - 2, it - nodes.begin() + 1)),
            std::string::npos)
      << s.examples[0].message;
  EXPECT_EQ(Check(r, "bricks").state, CheckResult::State::kSkipped);
  // A leaf bit above the voxel level.
  svo = Base().svo;
  svo.levels[1].nodes[0].leaf_mask = svo.levels[1].nodes[0].child_mask;
  r = ValidateBytes(test::EncodeSvoV1(svo), &Base().mesh);
  EXPECT_EQ(Count(Check(r, "structure"), "mask"), 1u) << r.Text();
}

TEST(ValidateMutation, WrongBrickBorderIsABorderFinding) {
  Svo svo = Base().svo;
  const std::uint32_t leaf = svo.depth;
  const auto keys = svo.LevelKeys(leaf);
  // A voxel with a +x neighbour: its x = 2 face is that neighbour's x = 0 face.
  std::size_t node = 0;
  for (; node < keys.size(); ++node) {
    const MortonCoord c = MortonDecode(keys[node]);
    if (std::binary_search(keys.begin(), keys.end(), MortonEncode(c.x + 1, c.y, c.z))) break;
  }
  ASSERT_LT(node, keys.size());
  const std::size_t sample = node * 27 + (2 + 3 * (1 + 3 * 1));  // face centre (2, 1, 1)
  svo.levels[leaf].color[sample] ^= 0x00404040u;
  const Report r = ValidateBytes(test::EncodeSvoV1(svo), &Base().mesh);
  const CheckResult& b = Check(r, "bricks");
  EXPECT_EQ(Count(b, "brick_border"), 1u) << r.Text();
  const auto border = std::find_if(b.examples.begin(), b.examples.end(),
                                   [](const Finding& f) { return f.kind == "brick_border"; });
  ASSERT_NE(border, b.examples.end());
  const MortonCoord c = MortonDecode(keys[node]);
  EXPECT_EQ(*border->voxel, (std::array<std::int64_t, 3>{c.x, c.y, c.z}));
  EXPECT_EQ(*border->level, leaf);
  // The parent read the changed sample: its brick is no longer the filter of its children.
  EXPECT_GE(Count(b, "brick_filter"), 1u);
  EXPECT_EQ(Check(r, "structure").state, CheckResult::State::kPassed);
}

TEST(ValidateMutation, WrongParentSampleIsAFilterFinding) {
  Svo svo = Base().svo;
  const std::uint32_t level = svo.depth - 2;
  // A brick centre (shared with no neighbour), far off the tent of its children.
  const std::size_t sample = 5 * 27 + 13;
  svo.levels[level].opacity[sample] =
      static_cast<std::uint8_t>(svo.levels[level].opacity[sample] ^ 0x40);
  Report r = ValidateBytes(test::EncodeSvoV1(svo), &Base().mesh);
  const auto kinds = Kinds(r);
  ASSERT_EQ(kinds.size(), 1u) << Describe(kinds);
  EXPECT_GE(kinds.at("bricks/brick_filter"), 1u);
  // Found at the changed sample itself (its own level), besides the parents that read it.
  const CheckResult& b = Check(r, "bricks");
  EXPECT_TRUE(std::any_of(b.examples.begin(), b.examples.end(), [&](const Finding& f) {
    return *f.level == level && f.message.find("node 5 ") != std::string::npos &&
           f.message.find("sample 13:") != std::string::npos;
  })) << r.Text();
  // A normal code with a zero axis is out of range.
  svo = Base().svo;
  svo.levels[level].normal[sample] = 0x0080;
  r = ValidateBytes(test::EncodeSvoV1(svo), &Base().mesh);
  EXPECT_GE(Count(Check(r, "bricks"), "brick_range"), 1u) << r.Text();
}

// Version 3: the level above the voxels comes from the voxels' own attributes, so a voxel whose
// colour or normal was changed in its page (consistently: its voxel bricks follow it on load) no
// longer matches the samples stored above it. A version-2 file is checked by filter 1.
TEST(ValidateMutation, ChangedVoxelAttributeIsAFilterFindingAboveIt) {
  const Fixture& f = Base();
  BuildOptions options;
  auto compact = BuildCompactSvo(f.voxels, &f.mesh, options);
  ASSERT_TRUE(compact.ok()) << compact.status().message();
  ExpectValid(ValidateBytes(EncodeSvo(*compact), &f.mesh));
  for (const bool normal : {false, true}) {
    CompactSvo changed = *compact;
    SvoChunk& voxels = changed.whole;
    const std::size_t v = voxels.normals.size() / 2;
    if (normal) {
      const Vec3f n = voxels.normals[v];
      voxels.normals[v] = Vec3f{-n.x, -n.y, -n.z};
    } else if (!voxels.colors.empty()) {
      voxels.colors[v] = HalfRgba(Rgba{1, 0, 1, 1});
    } else {
      changed.frame.shape.shared_color[0] = HalfRgba(Rgba{1, 0, 1, 1});
    }
    const Report r = ValidateBytes(EncodeSvo(changed), &f.mesh);
    const auto kinds = Kinds(r);
    ASSERT_EQ(kinds.size(), 1u) << Describe(kinds);
    EXPECT_GE(kinds.at("bricks/brick_filter"), 1u);
    const CheckResult& b = Check(r, "bricks");
    EXPECT_TRUE(std::all_of(b.examples.begin(), b.examples.end(), [&](const Finding& x) {
      return x.level && *x.level == changed.depth() - 1;
    })) << r.Text();
  }
}

TEST(ValidateMutation, ContourCuttingOffGeometryIsASurfaceFinding) {
  const Fixture& f = Base();
  Svo svo = f.svo;
  const std::uint32_t leaf = svo.depth;
  // The voxel holding the most surface that has a contour (many sample points fall inside it).
  std::size_t word = 0;
  float most = 0;
  for (const SvoNode& p : svo.levels[leaf - 1].nodes) {
    for (unsigned ch = 0; ch < 8; ++ch) {
      if ((p.contour_mask & (1u << ch)) && f.voxels.coverage[p.Child(ch)] > most) {
        most = f.voxels.coverage[p.Child(ch)];
        word = p.ChildContour(ch);
      }
    }
  }
  ASSERT_GT(most, 1.f);
  // Thinnest possible slab at the cube's far side along its normal: it still meets the cube
  // (contour_range holds) but the surface inside the voxel is cut off.
  Contour c = DecodeContour(svo.levels[leaf].contours[word]);
  const double half = 0.5 * (std::abs(c.nx) + std::abs(c.ny) + std::abs(c.nz));
  c.thickness = 0;
  c.position = static_cast<int>(std::floor(half / 0.75));
  svo.levels[leaf].contours[word] = EncodeContour(c);
  Report r = ValidateBytes(test::EncodeSvoV1(svo), &Base().mesh);
  const auto kinds = Kinds(r);
  EXPECT_GE(kinds.count("contour_surface/point_outside_slab"), 1u) << Describe(kinds);
  EXPECT_EQ(kinds.size(), 1u) << Describe(kinds);
  // Beyond the cube altogether: the contour's own range check fires too.
  c.position = 63;
  svo.levels[leaf].contours[word] = EncodeContour(c);
  r = ValidateBytes(test::EncodeSvoV1(svo), &Base().mesh);
  EXPECT_EQ(Count(Check(r, "contours"), "contour_range"), 1u) << r.Text();
}

TEST(ValidateMutation, ReportDoesNotDependOnTheThreadCount) {
  // Many findings of several kinds: a brick byte flipped in every 50th leaf.
  Svo svo = Base().svo;
  for (std::size_t i = 0; i < svo.levels[svo.depth].opacity.size(); i += 50 * 27 + 4) {
    svo.levels[svo.depth].opacity[i] ^= 0x80;
  }
  const auto bytes = test::EncodeSvoV1(svo);
  std::string one, two;
  {
    ThreadLimit limit(1);
    one = ValidateBytes(bytes, &Base().mesh).Json();
  }
  {
    ThreadLimit limit(2);
    two = ValidateBytes(bytes, &Base().mesh).Json();
  }
  EXPECT_EQ(one, two);
  EXPECT_NE(one.find("\"brick_border\""), std::string::npos) << one;
}

TEST(ValidateMutation, ForeignBytesAreUnusableNotFindings) {
  const std::vector<std::uint8_t> text = {'h', 'e', 'l', 'l', 'o'};
  auto r = DecodeSvoLenient(text, "x.svo");
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), StatusCode::kBadInput);
  EXPECT_NE(r.status().message().find("x.svo"), std::string::npos);
}

}  // namespace
}  // namespace svokit::validate
