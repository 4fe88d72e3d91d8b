// `--fill solid` as a user runs it: mesh2svo and svo-voxelize + svo-build write the same solid,
// byte for byte, whole or by pages and with any thread count; the summary states the interior;
// the exports fill it; bad input (formats that cannot hold a solid, builds that cannot fill, a
// damaged FILL section, an empty mesh) is one line on stderr, exit 2, and no output; a mesh that
// encloses no voxel centre is a solid that is its surface.

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cstdio>
#include <cstring>
#include <optional>
#include <sstream>
#include <tuple>

#include <fmt/format.h>

#include "svokit/core/morton.hpp"
#include "svokit/formats/container/container.hpp"
#include "svokit/formats/mesh_import.hpp"
#include "svokit/formats/provenance.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/formats/svo/svo_reader.hpp"
#include "svokit/formats/vfrag/vfrag.hpp"
#include "svokit/svo/compact_build.hpp"
#include "svokit/voxelize/solid_fill.hpp"
#include "svokit/voxelize/voxelize.hpp"
#include "tests/cli/run_tool.hpp"
#include "tests/test_meshes.hpp"

namespace svokit::test {
namespace {

namespace fs = std::filesystem;

std::string Torus() {
  return (DataDir() / "uv-torus.obj").string();
}

std::string WriteObj(const TempDir& dir, const std::string& name, const Mesh& mesh) {
  std::string text;
  for (const Vec3d& p : mesh.positions)
    text += fmt::format("v {:.17g} {:.17g} {:.17g}\n", p.x, p.y, p.z);
  for (const Triangle& t : mesh.triangles) {
    text += fmt::format("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
  }
  return dir.Write(name, text).string();
}

// Meshes written once for the whole program: a closed icosphere, the same with holes (open
// edges: winding numbers), a flat pillow (two triangles back to back: closed, no volume) and a
// file with vertices but no triangles.
const TempDir& Meshes() {
  static const TempDir dir;
  static const bool made = [] {
    WriteObj(dir, "ball.obj", Icosphere(4, false));
    Mesh holed = Icosphere(3, false);
    std::vector<Triangle> kept;
    for (const Triangle& t : holed.triangles) {
      if (t[0] % 61 == 7 || t[1] % 61 == 7 || t[2] % 61 == 7) continue;
      kept.push_back(t);
    }
    holed.triangles = kept;
    WriteObj(dir, "holed.obj", holed);
    dir.Write("pillow.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 3 2\n");
    dir.Write("empty.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n");
    return true;
  }();
  (void)made;
  return dir;
}
std::string Ball() {
  return (Meshes() / "ball.obj").string();
}
std::string Holed() {
  return (Meshes() / "holed.obj").string();
}

ToolResult RunOk(const std::string& tool, const std::vector<std::string>& args) {
  const ToolResult r = RunTool(tool, args);
  EXPECT_EQ(r.exit_code, 0) << tool << ": " << r.err;
  return r;
}

// The summary's interior line.
std::string InteriorLine(const std::string& out) {
  std::istringstream in(out);
  std::string line;
  while (std::getline(in, line)) {
    if (line.starts_with("interior ")) return line;
  }
  return "";
}

struct ReadSolid {
  Svo svo;
  std::uint64_t surface = 0, interior = 0;
};
ReadSolid Read(const fs::path& path) {
  ReadSolid s;
  auto svo = ReadSvo(path);
  EXPECT_TRUE(svo.ok()) << svo.status().message();
  if (!svo.ok()) return s;
  s.svo = std::move(*svo);
  s.surface = s.svo.voxel_count();
  s.interior = s.svo.InteriorVoxelCount();
  return s;
}

// ---------------------------------------------------------------------------------------------

// Both routes give one file: for a closed surface (exact crossings) and an open one (winding
// numbers, with nodes that hold full leaves only), and the summaries state the file's interior.
TEST(SolidCli, ChainEqualsMesh2svoByteForByte) {
  struct Case {
    std::string mesh, method;
  };
  for (const Case& c : {Case{Torus(), "by exact crossings (closed surface)"},
                        Case{Holed(), "by winding numbers ("}}) {
    SCOPED_TRACE(c.mesh);
    TempDir dir;
    const std::string direct = (dir / "a.svo").string(), vfrag = (dir / "a.vfrag").string(),
                      chained = (dir / "b.svo").string();
    const ToolResult m = RunOk("mesh2svo", {c.mesh, "-r", "64", "--fill", "solid", "-o", direct});
    const ToolResult v =
        RunOk("svo-voxelize", {c.mesh, "-r", "64", "--fill", "solid", "-o", vfrag});
    const ToolResult b = RunOk("svo-build", {vfrag, "--mesh", c.mesh, "-o", chained});
    const std::string a_bytes = ReadText(direct);
    ASSERT_GT(a_bytes.size(), 1000u);
    EXPECT_TRUE(a_bytes == ReadText(chained)) << "mesh2svo and svo-voxelize + svo-build differ";
    const ReadSolid s = Read(direct);
    ASSERT_TRUE(s.svo.solid);
    EXPECT_GT(s.interior, 0u);
    EXPECT_TRUE(ParseProvenance(s.svo.metadata).voxelize->solid) << s.svo.metadata;
    // "interior    N voxels in M cubes, by …", the same from each tool, N the file's.
    const std::string line = InteriorLine(m.out);
    EXPECT_TRUE(line.starts_with(fmt::format("interior    {} voxels in ", s.interior))) << m.out;
    EXPECT_NE(line.find(c.method), std::string::npos) << line;
    EXPECT_EQ(InteriorLine(v.out), line) << v.out;
    EXPECT_EQ(InteriorLine(b.out), line) << b.out;
    ExpectValidSvo(direct, c.mesh);

    // The surface of the same mesh: no interior line, not solid, the same voxels.
    const ToolResult surface =
        RunOk("mesh2svo", {c.mesh, "-r", "64", "-o", (dir / "s.svo").string()});
    EXPECT_EQ(InteriorLine(surface.out), "");
    const ReadSolid p = Read(dir / "s.svo");
    EXPECT_FALSE(p.svo.solid);
    EXPECT_EQ(p.interior, 0u);
    EXPECT_EQ(p.svo.LevelKeys(p.svo.depth), s.svo.LevelKeys(s.svo.depth));
  }
}

// By pages (--memory-limit) a closed surface's solid is the whole build's file, from the mesh and
// from the .vfrag: with bricks (the pages' faces) on the torus, and on a ball where a whole page
// cube is inside (a full leaf of the top chunk).
TEST(SolidCli, MemoryLimitWritesTheWholeBuildsFile) {
  struct Case {
    std::string mesh, resolution;
    std::vector<std::string> build;
  };
  for (const Case& c :
       {Case{Torus(), "256", {}}, Case{Ball(), "400", {"--bricks", "none", "--no-contours"}}}) {
    SCOPED_TRACE(c.mesh + " at " + c.resolution);
    TempDir dir;
    const auto mesh2svo = [&](const std::string& out, std::vector<std::string> extra) {
      std::vector<std::string> args = {c.mesh, "-r", c.resolution, "--fill", "solid", "-o", out};
      args.insert(args.end(), c.build.begin(), c.build.end());
      args.insert(args.end(), extra.begin(), extra.end());
      return RunOk("mesh2svo", args);
    };
    mesh2svo((dir / "whole.svo").string(), {"-q"});
    const ToolResult paged = mesh2svo((dir / "paged.svo").string(), {"--memory-limit", "16M"});
    EXPECT_NE(paged.out.find("build       by pages within 16 MiB"), std::string::npos) << paged.out;
    const std::string vfrag = (dir / "s.vfrag").string();
    RunOk("svo-voxelize", {c.mesh, "-r", c.resolution, "--fill", "solid", "-o", vfrag, "-q"});
    std::vector<std::string> build = {
        vfrag, "--mesh", c.mesh, "--memory-limit", "16M", "-o", (dir / "built.svo").string(), "-q"};
    build.insert(build.end(), c.build.begin(), c.build.end());
    const ToolResult built = RunOk("svo-build", build);
    const std::string whole = ReadText(dir / "whole.svo");
    EXPECT_TRUE(ReadText(dir / "paged.svo") == whole) << "mesh2svo --memory-limit";
    EXPECT_TRUE(ReadText(dir / "built.svo") == whole) << "svo-build --memory-limit";
    auto reader = SvoReader::Open(dir / "paged.svo");
    ASSERT_TRUE(reader.ok()) << reader.status().message();
    EXPECT_GE(reader->page_count(), 4u);
    EXPECT_TRUE(reader->shape().solid);
    ExpectValidSvo((dir / "paged.svo").string(), c.mesh);
  }
}

// svo-validate recomputes a solid's bricks with its interior: mesh2svo's solid passes; the same
// tree with the bricks its surface alone gives (the interior's opacity zeroed) exits 1, each
// finding one line saying what the filter gives.
TEST(SolidCli, ValidateRecomputesTheInteriorsOpacity) {
  TempDir dir;
  const std::string solid = (dir / "solid.svo").string();
  RunOk("mesh2svo", {Torus(), "-r", "96", "--fill", "solid", "-o", solid, "-q"});
  ExpectValidSvo(solid, Torus());

  auto mesh = ImportMesh(Torus());
  ASSERT_TRUE(mesh.ok()) << mesh.status().message();
  auto grid = GridTransform::FitResolution(mesh->Bounds(), 96);
  ASSERT_TRUE(grid.ok());
  auto voxels = Voxelize(*mesh, *grid, {});
  ASSERT_TRUE(voxels.ok());
  auto interior = FillInterior(*mesh, *grid, voxels->keys);
  ASSERT_TRUE(interior.ok());
  BuildOptions bo;
  bo.contours = false;
  auto surface = BuildCompactSvo(*voxels, nullptr, bo);
  bo.interior = &*interior;
  auto zeroed = BuildCompactSvo(*voxels, nullptr, bo);
  ASSERT_TRUE(surface.ok() && zeroed.ok());
  zeroed->whole.samples = surface->whole.samples;
  const std::string bad = (dir / "zeroed.svo").string();
  ASSERT_TRUE(WriteSvo(*zeroed, bad).ok());
  const ToolResult r = RunTool("svo-validate", {bad});
  EXPECT_EQ(r.exit_code, 1) << r.out << r.err;
  const std::size_t at = r.out.find("    brick_filter: level ");
  ASSERT_NE(at, std::string::npos) << r.out;
  const std::string line = r.out.substr(at, r.out.find('\n', at) - at);
  EXPECT_NE(line.find(" where the filter gives "), std::string::npos) << line;
  EXPECT_NE(r.out.find("result          INVALID"), std::string::npos) << r.out;
}

// Thread counts change nothing, whole and by pages, on closed and open surfaces.
TEST(SolidCli, ThreadCountDoesNotChangeTheFile) {
  TempDir dir;
  const std::vector<std::pair<std::string, std::vector<std::string>>> runs = {
      {"mesh2svo", {Torus(), "-r", "96", "--fill", "solid"}},
      {"mesh2svo", {Holed(), "-r", "96", "--fill", "solid"}},
      {"mesh2svo",
       {Ball(), "-r", "300", "--fill", "solid", "--bricks", "none", "--no-contours",
        "--memory-limit", "16M"}},
      {"svo-voxelize", {Holed(), "-r", "96", "--fill", "solid"}},
  };
  for (const auto& [tool, args] : runs) {
    const std::string ext = tool == "mesh2svo" ? "svo" : "vfrag";
    std::string first;
    for (const char* threads : {"1", "2"}) {
      std::vector<std::string> a = args;
      const std::string out = (dir / fmt::format("t{}.{}", threads, ext)).string();
      a.insert(a.end(), {"-j", threads, "-q", "-o", out});
      RunOk(tool, a);
      const std::string bytes = ReadText(out);
      ASSERT_GT(bytes.size(), 1000u);
      if (first.empty()) {
        first = bytes;
      } else {
        EXPECT_TRUE(bytes == first)
            << tool << " " << args[0] << " " << args[2] << ": -j 1 and -j 2 differ";
      }
    }
  }
}

// A mesh that encloses no voxel centre (a flat closed pillow) is a solid of its surface alone,
// said so in the summary; the chain agrees.
TEST(SolidCli, ZeroVolumeMeshIsItsSurface) {
  TempDir dir;
  const std::string pillow = (Meshes() / "pillow.obj").string();
  const ToolResult r =
      RunOk("mesh2svo", {pillow, "-r", "16", "--fill", "solid", "-o", (dir / "p.svo").string()});
  EXPECT_TRUE(InteriorLine(r.out).starts_with("interior    0 voxels in 0 cubes")) << r.out;
  EXPECT_NE(r.out.find("encloses no voxel centre"), std::string::npos) << r.out;
  EXPECT_TRUE(r.err.find("mesh2svo:") == std::string::npos) << r.err;
  const ReadSolid s = Read(dir / "p.svo");
  EXPECT_TRUE(s.svo.solid);
  EXPECT_EQ(s.interior, 0u);
  EXPECT_GT(s.surface, 0u);
  ExpectValidSvo((dir / "p.svo").string(), pillow);
  RunOk("mesh2svo", {pillow, "-r", "16", "-o", (dir / "surface.svo").string(), "-q"});
  EXPECT_EQ(Read(dir / "surface.svo").svo.LevelKeys(4), s.svo.LevelKeys(4));
  const ToolResult v = RunOk(
      "svo-voxelize", {pillow, "-r", "16", "--fill", "solid", "-o", (dir / "p.vfrag").string()});
  EXPECT_NE(v.out.find("encloses no voxel centre"), std::string::npos) << v.out;
  RunOk("svo-build",
        {(dir / "p.vfrag").string(), "--mesh", pillow, "-o", (dir / "b.svo").string(), "-q"});
  EXPECT_TRUE(ReadText(dir / "b.svo") == ReadText(dir / "p.svo"));
}

// .vfrag files whose FILL section is replaced (checksums made right, as another writer's bug
// would leave them).
std::vector<std::uint8_t> WithFill(const std::vector<std::uint8_t>& file,
                                   const std::vector<std::uint8_t>& fill) {
  auto frame = container::Frame::FromBytes(file, "v.vfrag", kVfragFormat);
  EXPECT_TRUE(frame.ok() && frame->issues().empty());
  container::Writer w(kVfragFormat, frame->flags());
  for (const container::Frame::Section& s : frame->sections()) {
    if (s.tag == container::MakeTag("FILL")) {
      w.AddSection(s.tag, fill);
    } else {
      w.AddSection(s.tag, {s.bytes.begin(), s.bytes.end()});
    }
  }
  return w.Serialize();
}

TEST(SolidCli, BadInputIsOneLineExitTwoAndNoOutput) {
  TempDir inputs;
  // A solid's .vfrag of the torus, and versions of it whose FILL is damaged.
  const std::string vfrag = (inputs / "t.vfrag").string();
  RunOk("svo-voxelize", {Torus(), "-r", "32", "--fill", "solid", "-o", vfrag, "-q"});
  const std::string open_vfrag = (inputs / "open.vfrag").string();
  RunOk("svo-voxelize", {Holed(), "-r", "32", "--fill", "solid", "-o", open_vfrag, "-q"});
  auto interior = ReadVfragInterior(vfrag);
  ASSERT_TRUE(interior.ok() && interior->has_value()) << interior.status().message();
  auto voxels = ReadVfrag(vfrag);
  ASSERT_TRUE(voxels.ok());
  const std::vector<std::uint8_t> clean = ReadBytes(vfrag);
  {
    InteriorCubes outside = **interior;
    outside.levels[2] = {std::uint64_t{1} << 6};  // level 2 has keys 0 .. 63
    inputs.Write("outside.vfrag", WithFill(clean, EncodeInteriorSection(outside)));
    // A cube that is a surface voxel: the interior contradicts the surface.
    InteriorCubes overlap = **interior;
    std::vector<std::uint64_t>& voxel_level = overlap.levels[overlap.depth];
    voxel_level.push_back(voxels->keys[voxels->keys.size() / 2]);
    std::sort(voxel_level.begin(), voxel_level.end());
    voxel_level.erase(std::unique(voxel_level.begin(), voxel_level.end()), voxel_level.end());
    inputs.Write("overlap.vfrag", WithFill(clean, EncodeInteriorSection(overlap)));
    std::vector<std::uint8_t> cut = EncodeInteriorSection(**interior);
    cut.resize(cut.size() - 1);
    inputs.Write("cut.vfrag", WithFill(clean, cut));
    std::vector<std::uint8_t> method = EncodeInteriorSection(**interior);
    method[4] = 7;
    inputs.Write("method.vfrag", WithFill(clean, method));
  }
  const std::string empty = (Meshes() / "empty.obj").string();
  const std::vector<std::tuple<std::string, std::vector<std::string>, std::string>> cases = {
      {"svo-voxelize", {Torus(), "-r", "32", "--fill", "solid", "-o", "{out}/x.xyz"}, ".vfrag"},
      {"svo-voxelize", {Torus(), "-r", "32", "--fill", "solid", "-o", "{out}/x.ply"}, ".vfrag"},
      {"svo-voxelize",
       {Torus(), "-r", "32", "--fill", "solid", "--memory-limit", "64M", "-o", "{out}/x.vfrag"},
       "--memory-limit"},
      {"svo-voxelize", {Torus(), "-r", "32", "--fill", "bogus", "-o", "{out}/x.vfrag"}, "--fill"},
      {"mesh2svo", {Torus(), "-r", "32", "--fill", "bogus", "-o", "{out}/x.svo"}, "--fill"},
      {"mesh2svo",
       {Torus(), "-r", "300", "--fill", "solid", "--pages", "0/2", "-o", "{out}/x.svopart"},
       "--pages"},
      {"mesh2svo",
       {Holed(), "-r", "64", "--fill", "solid", "--memory-limit", "64M", "-o", "{out}/x.svo"},
       "open edges"},
      {"mesh2svo", {empty, "-r", "16", "--fill", "solid", "-o", "{out}/x.svo"}, "no triangles"},
      {"svo-voxelize",
       {empty, "-r", "16", "--fill", "solid", "-o", "{out}/x.vfrag"},
       "no triangles"},
      {"svo-build",
       {open_vfrag, "--mesh", Holed(), "--memory-limit", "64M", "-o", "{out}/x.svo"},
       "open edges"},
      {"svo-build",
       {(inputs / "outside.vfrag").string(), "--no-contours", "-o", "{out}/x.svo"},
       "outside the grid"},
      {"svo-build",
       {(inputs / "overlap.vfrag").string(), "--no-contours", "-o", "{out}/x.svo"},
       "not a free child"},
      {"svo-build",
       {(inputs / "cut.vfrag").string(), "--no-contours", "-o", "{out}/x.svo"},
       "FILL"},
      {"svo-build",
       {(inputs / "method.vfrag").string(), "--no-contours", "-o", "{out}/x.svo"},
       "unknown method"},
  };
  for (const auto& [tool, args_template, expect] : cases) {
    TempDir out;
    std::vector<std::string> args;
    for (std::string a : args_template) {
      if (a.starts_with("{out}")) a = out.path().string() + a.substr(5);
      args.push_back(a);
    }
    const ToolResult r = RunTool(tool, args, 60);
    const std::string what = tool + " " + args[0] + " … " + args.back();
    EXPECT_EQ(r.exit_code, 2) << what << ": " << r.err;
    // Progress lines of finished stages may precede it; the error is the one last line.
    const auto lines = r.ErrLines();
    ASSERT_FALSE(lines.empty()) << what;
    const std::string prefix =
        tool + ": ";  // lambdas cannot capture structured bindings (clang 14)
    EXPECT_EQ(std::count_if(lines.begin(), lines.end(),
                            [&](const std::string& l) { return l.starts_with(prefix); }),
              1)
        << what << ": " << r.err;
    EXPECT_TRUE(lines.back().starts_with(tool + ": ")) << what << ": " << r.err;
    EXPECT_NE(lines.back().find(expect), std::string::npos) << what << ": " << r.err;
    EXPECT_TRUE(out.Files().empty()) << what << " left " << out.Files().front();
  }
  // The damaged files are exactly the sound one but for FILL: the sound one builds.
  TempDir out;
  RunOk("svo-build", {vfrag, "--no-contours", "-o", (out / "ok.svo").string(), "-q"});
}

// svo-build refuses FILL cubes that are not free children of the surface's nodes
// (formats/vfrag.md, "Interior"): a cube away from the surface contradicts a closed surface's
// exact crossings, which only ever decide the free children of its nodes.
TEST(SolidCli, SvoBuildRefusesAFillCubeAwayFromTheSurface) {
  TempDir inputs;
  const std::string vfrag = (inputs / "t.vfrag").string();
  RunOk("svo-voxelize", {Torus(), "-r", "32", "--fill", "solid", "-o", vfrag, "-q"});
  auto interior = ReadVfragInterior(vfrag);
  ASSERT_TRUE(interior.ok() && interior->has_value()) << interior.status().message();
  ASSERT_EQ((*interior)->method, FillMethod::kColumns);
  auto voxels = ReadVfrag(vfrag);
  ASSERT_TRUE(voxels.ok());
  // A voxel of the grid whose parent holds no surface voxel and which no cube holds.
  std::vector<std::uint64_t> parents;
  for (const std::uint64_t key : voxels->keys) parents.push_back(key >> 3);
  const auto& d = voxels->grid.dims();
  std::optional<std::uint64_t> away;
  for (std::uint32_t z = 0; z < d[2] && !away; ++z) {
    for (std::uint32_t y = 0; y < d[1] && !away; ++y) {
      for (std::uint32_t x = 0; x < d[0] && !away; ++x) {
        const std::uint64_t key = MortonEncode(x, y, z);
        if (!std::binary_search(parents.begin(), parents.end(), key >> 3) &&
            !(*interior)->Contains(x, y, z)) {
          away = key;
        }
      }
    }
  }
  ASSERT_TRUE(away.has_value());
  InteriorCubes extra = **interior;
  std::vector<std::uint64_t>& level = extra.levels[extra.depth];
  level.insert(std::lower_bound(level.begin(), level.end(), *away), *away);
  inputs.Write("away.vfrag", WithFill(ReadBytes(vfrag), EncodeInteriorSection(extra)));
  TempDir out;
  const ToolResult r = RunTool(
      "svo-build",
      {(inputs / "away.vfrag").string(), "--no-contours", "-o", (out / "x.svo").string(), "-q"},
      60);
  EXPECT_EQ(r.exit_code, 2) << "a cube away from the surface was accepted";
  EXPECT_NE(r.err.find("not a free child"), std::string::npos) << r.err;
  EXPECT_TRUE(out.Files().empty());
}

// A write refused part-way (a file-size limit, as a full disk) is exit 4 naming the output, and
// leaves nothing, for the solid's writers too.
TEST(SolidCli, AWriteRefusedPartWayIsFourAndLeavesNothing) {
  TempDir inputs;
  const std::string vfrag = (inputs / "t.vfrag").string();
  RunOk("svo-voxelize", {Torus(), "-r", "64", "--fill", "solid", "-o", vfrag, "-q"});
  TempDir out;
  const std::vector<std::pair<std::string, std::vector<std::string>>> runs = {
      {"mesh2svo", {Torus(), "-r", "64", "--fill", "solid", "-o", (out / "m.svo").string()}},
      {"mesh2svo",
       {Torus(), "-r", "256", "--fill", "solid", "--memory-limit", "16M", "-o",
        (out / "p.svo").string()}},
      {"svo-voxelize", {Torus(), "-r", "64", "--fill", "solid", "-o", (out / "v.vfrag").string()}},
      {"svo-build", {vfrag, "--no-contours", "-o", (out / "b.svo").string()}},
  };
  for (const auto& [tool, args] : runs) {
    std::vector<std::string> a = args;
    a.push_back("-q");
    const ToolResult r = RunTool(tool, a, RunOptions{60, 0, 512, {}});
    EXPECT_EQ(r.exit_code, 4) << tool << ": " << r.err;
    ASSERT_EQ(r.ErrLines().size(), 1u) << tool << ": " << r.err;
    EXPECT_EQ(r.err.rfind(tool + ": " + args.back() + ": ", 0), 0u) << r.err;
    EXPECT_TRUE(out.Files().empty()) << tool << " left " << out.Files().front();
  }
}

// ---------------------------------------------------------------------------------------------
// svo-export of a solid: the formats that hold volumes fill the interior, the point lists do not.

// binvox (patrickmin.com/binvox): text header, then (value, count) byte pairs over dim³.
std::uint64_t BinvoxFilled(const fs::path& path, std::uint64_t* dim_out = nullptr) {
  const std::string bytes = ReadText(path);
  const std::size_t data = bytes.find("\ndata\n");
  EXPECT_NE(data, std::string::npos);
  if (data == std::string::npos) return 0;
  std::uint64_t dim = 0;
  std::sscanf(bytes.c_str() + bytes.find("dim "), "dim %lu", &dim);
  std::uint64_t filled = 0, total = 0;
  for (std::size_t p = data + 6; p + 1 < bytes.size(); p += 2) {
    const auto value = static_cast<std::uint8_t>(bytes[p]);
    const auto count = static_cast<std::uint8_t>(bytes[p + 1]);
    EXPECT_LE(value, 1);
    total += count;
    if (value) filled += count;
  }
  EXPECT_EQ(total, dim * dim * dim);
  if (dim_out) *dim_out = dim;
  return filled;
}

// MagicaVoxel .vox: the voxels of every XYZI chunk.
std::uint64_t VoxVoxels(const fs::path& path) {
  const std::string bytes = ReadText(path);
  std::uint64_t voxels = 0;
  std::size_t p = 20;  // "VOX ", version, "MAIN", its two sizes
  while (p + 12 <= bytes.size()) {
    std::int32_t content = 0, children = 0, n = 0;
    std::memcpy(&content, bytes.data() + p + 4, 4);
    std::memcpy(&children, bytes.data() + p + 8, 4);
    if (bytes.compare(p, 4, "XYZI") == 0) {
      std::memcpy(&n, bytes.data() + p + 12, 4);
      voxels += static_cast<std::uint64_t>(n);
    }
    p += 12 + static_cast<std::size_t>(content) + static_cast<std::size_t>(children);
  }
  EXPECT_EQ(p, bytes.size());
  return voxels;
}

TEST(SolidCli, ExportsFillTheInterior) {
  TempDir dir;
  const std::string svo = (dir / "t.svo").string();
  RunOk("mesh2svo", {Torus(), "-r", "64", "--fill", "solid", "-o", svo, "-q"});
  const ReadSolid s = Read(svo);
  ASSERT_GT(s.interior, s.surface);
  for (const char* ext : {"binvox", "vox", "vdb", "ply", "xyz"}) {
    const ToolResult r =
        RunTool("svo-export", {svo, "-o", (dir / (std::string("t.") + ext)).string(), "-q"});
    ASSERT_EQ(r.exit_code, 0) << ext << ": " << r.err;
  }
  EXPECT_EQ(BinvoxFilled(dir / "t.binvox"), s.surface + s.interior);
  EXPECT_EQ(VoxVoxels(dir / "t.vox"), s.surface + s.interior);
  // Point lists: the surface's voxels only.
  const std::string xyz = ReadText(dir / "t.xyz");
  EXPECT_EQ(static_cast<std::uint64_t>(std::count(xyz.begin(), xyz.end(), '\n')), s.surface + 3);
  EXPECT_NE(ReadText(dir / "t.ply").find(fmt::format("element vertex {}\n", s.surface)),
            std::string::npos);
  // A coarser level: its nodes, and the full leaves of the levels above it at its resolution.
  for (const std::uint32_t level : {s.svo.depth - 1, s.svo.depth - 3}) {
    const std::string out = (dir / fmt::format("l{}.binvox", level)).string();
    ASSERT_EQ(
        RunTool("svo-export", {svo, "-o", out, "--level", std::to_string(level), "-q"}).exit_code,
        0);
    std::uint64_t expected = s.svo.levels[level].node_count;
    for (std::uint32_t l = 0; l < level; ++l) {
      for (const SvoNode& n : s.svo.levels[l].nodes) {
        expected += static_cast<std::uint64_t>(std::popcount(static_cast<unsigned>(n.full_mask)))
                    << (3 * (level - l - 1));
      }
    }
    EXPECT_EQ(BinvoxFilled(out), expected) << "level " << level;
  }
}

}  // namespace
}  // namespace svokit::test
