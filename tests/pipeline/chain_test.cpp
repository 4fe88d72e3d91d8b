// The chain as the tools run it (pipeline/chain.hpp): MeshToVoxels then VoxelsToSvo writes the
// file MeshToSvo writes, whole or by pages; the reports' numbers are the files'; a part request
// writes a part; warnings reach the sink; and a bad output is refused before any work.

#include "svokit/pipeline/chain.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "svokit/formats/provenance.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/formats/svo/svo_part.hpp"
#include "svokit/pipeline/svo_parts.hpp"
#include "tests/test_util.hpp"

namespace svokit {
namespace {

namespace fs = std::filesystem;

constexpr std::uint32_t kResolution = 200;  // depth 8: pages of level 1, several of them
constexpr std::uint64_t kLimit = std::uint64_t{64} << 20;

fs::path Torus() {
  return test::DataDir() / "uv-torus.obj";
}

VoxelizeRequest Voxelize() {
  VoxelizeRequest v;
  v.grid = GridFit{kResolution};
  return v;
}

// A request of the torus (MeshToVoxels' or MeshToSvo's) at kResolution, default settings.
template <class Request>
Request FromTorus(const fs::path& output, std::optional<std::uint64_t> limit) {
  Request r;
  r.input = Torus();
  r.output = output;
  r.voxelize = Voxelize();
  r.memory_limit = limit;
  return r;
}

MeshToVoxelsRequest ToVoxels(const fs::path& output,
                             std::optional<std::uint64_t> limit = std::nullopt) {
  return FromTorus<MeshToVoxelsRequest>(output, limit);
}

MeshToSvoRequest MeshTo(const fs::path& output, std::optional<std::uint64_t> limit = std::nullopt) {
  return FromTorus<MeshToSvoRequest>(output, limit);
}

VoxelsToSvoRequest ToSvo(const fs::path& vfrag, const fs::path& output,
                         std::optional<std::uint64_t> limit = std::nullopt) {
  VoxelsToSvoRequest r;
  r.input = vfrag;
  r.mesh = Torus();
  r.output = output;
  r.memory_limit = limit;
  return r;
}

// What an octree report must say of the file it describes.
void ExpectReportOfFile(const OctreeReport& report, const fs::path& file, bool whole) {
  SCOPED_TRACE(file.filename().string());
  const StatusOr<Svo> svo = ReadSvo(file);
  ASSERT_TRUE(svo.ok()) << svo.status().message();
  EXPECT_GT(report.voxels, 0u);
  EXPECT_EQ(report.voxels, svo->voxel_count());
  EXPECT_EQ(report.depth, svo->depth);
  EXPECT_EQ(report.file.file_bytes, fs::file_size(file));
  EXPECT_EQ(report.file.voxels, svo->voxel_count());
  EXPECT_EQ(report.memory.by_pages(), !whole);
  EXPECT_EQ(report.level_table.empty(), !whole);
  // The level table's rows: level, node size, nodes, … with the file's node counts.
  std::istringstream rows(report.level_table);
  std::string header;
  std::getline(rows, header);
  for (std::uint32_t l = 0; whole && l <= svo->depth; ++l) {
    std::uint32_t level = 0;
    double size = 0;
    std::uint64_t nodes = 0;
    std::string rest;
    ASSERT_TRUE(rows >> level >> size >> nodes) << report.level_table;
    std::getline(rows, rest);
    EXPECT_EQ(level, l);
    EXPECT_EQ(nodes, svo->levels[l].node_count) << "level " << l;
  }
  EXPECT_FALSE(report.interior);
}

TEST(Chain, VoxelsThenOctreeIsTheFileOfMeshToSvo) {
  test::TempDir dir;
  const StatusOr<MeshToVoxelsReport> voxels = MeshToVoxels(ToVoxels(dir / "t.vfrag"));
  ASSERT_TRUE(voxels.ok()) << voxels.status().message();
  const StatusOr<OctreeReport> built = VoxelsToSvo(ToSvo(dir / "t.vfrag", dir / "built.svo"));
  ASSERT_TRUE(built.ok()) << built.status().message();
  const StatusOr<MeshToSvoReport> direct = MeshToSvo(MeshTo(dir / "direct.svo"));
  ASSERT_TRUE(direct.ok()) << direct.status().message();

  EXPECT_TRUE(test::ReadBytes(dir / "built.svo") == test::ReadBytes(dir / "direct.svo"));
  ExpectReportOfFile(*built, dir / "built.svo", true);
  ExpectReportOfFile(direct->octree, dir / "direct.svo", true);
  EXPECT_FALSE(direct->part);

  EXPECT_EQ(voxels->triangles, 2304u);
  EXPECT_EQ(direct->triangles, 2304u);
  EXPECT_EQ(voxels->grid, direct->grid);
  EXPECT_EQ(voxels->grid.max_dim(), kResolution);
  EXPECT_EQ(voxels->voxels, built->voxels);
  EXPECT_FALSE(voxels->memory.by_pages());
  EXPECT_FALSE(voxels->interior);

  // The file records what shaped it.
  const Provenance meta = ParseProvenance(ReadSvo(dir / "direct.svo")->metadata);
  EXPECT_EQ(meta.source, "uv-torus.obj");
  EXPECT_EQ(meta.triangles, 2304u);
  EXPECT_EQ(meta.grid, Voxelize().grid);
  EXPECT_EQ(meta.voxelize, VoxelSettings{});
  EXPECT_EQ(meta.build, BuildSettings{});
}

TEST(Chain, AMemoryLimitBuildsByPagesTheSameBytes) {
  test::TempDir dir;
  ASSERT_TRUE(MeshToVoxels(ToVoxels(dir / "whole.vfrag")).ok());
  ASSERT_TRUE(MeshToSvo(MeshTo(dir / "whole.svo")).ok());
  const std::vector<std::uint8_t> want = test::ReadBytes(dir / "whole.svo");

  const StatusOr<MeshToVoxelsReport> voxels = MeshToVoxels(ToVoxels(dir / "cubes.vfrag", kLimit));
  ASSERT_TRUE(voxels.ok()) << voxels.status().message();
  EXPECT_TRUE(voxels->memory.by_pages());
  EXPECT_EQ(voxels->memory.limit, kLimit);
  EXPECT_FALSE(voxels->memory.by_default);
  EXPECT_TRUE(test::ReadBytes(dir / "cubes.vfrag") == test::ReadBytes(dir / "whole.vfrag"));

  const StatusOr<MeshToSvoReport> direct = MeshToSvo(MeshTo(dir / "direct.svo", kLimit));
  ASSERT_TRUE(direct.ok()) << direct.status().message();
  EXPECT_EQ(direct->octree.memory.limit, kLimit);
  EXPECT_FALSE(direct->octree.memory.by_default);
  ExpectReportOfFile(direct->octree, dir / "direct.svo", false);
  EXPECT_TRUE(test::ReadBytes(dir / "direct.svo") == want);

  const StatusOr<OctreeReport> built =
      VoxelsToSvo(ToSvo(dir / "cubes.vfrag", dir / "built.svo", kLimit));
  ASSERT_TRUE(built.ok()) << built.status().message();
  EXPECT_EQ(built->memory.limit, kLimit);
  ExpectReportOfFile(*built, dir / "built.svo", false);
  EXPECT_TRUE(test::ReadBytes(dir / "built.svo") == want);
}

TEST(Chain, APartRequestWritesAPartThatMergesIntoTheFile) {
  test::TempDir dir;
  ASSERT_TRUE(MeshToSvo(MeshTo(dir / "whole.svo")).ok());
  std::vector<fs::path> parts;
  std::uint64_t pages = 0, voxels = 0;
  for (std::uint32_t k = 0; k < 2; ++k) {
    MeshToSvoRequest r = MeshTo(dir / fmt::format("p{}.svopart", k));
    r.part = SvoPartOf{k, 2, 0};
    const StatusOr<MeshToSvoReport> made = MeshToSvo(r);
    ASSERT_TRUE(made.ok()) << made.status().message();
    ASSERT_TRUE(made->part);
    EXPECT_EQ(made->triangles, 2304u);
    const StatusOr<SvoPart> part = ReadSvoPart(r.output);
    ASSERT_TRUE(part.ok()) << part.status().message();
    EXPECT_EQ(part->head.of.part, k);
    EXPECT_EQ(part->head.of.parts, 2u);
    EXPECT_NE(part->head.of.identity, 0u);  // computed from the input and the options
    EXPECT_EQ(made->part->pages, part->pages.size());
    EXPECT_EQ(made->part->cells, part->head.end - part->head.first);
    pages += made->part->pages;
    voxels += made->part->voxels;
    parts.push_back(r.output);
  }
  const StatusOr<SvoFileStats> merged = MergeSvoParts(parts, dir / "merged.svo");
  ASSERT_TRUE(merged.ok()) << merged.status().message();
  EXPECT_EQ(merged->pages, pages);
  EXPECT_EQ(merged->voxels, voxels);
  EXPECT_EQ(voxels, ReadSvo(dir / "whole.svo")->voxel_count());
  EXPECT_TRUE(test::ReadBytes(dir / "merged.svo") == test::ReadBytes(dir / "whole.svo"));

  // A part is a .svopart, and a .svopart is a part.
  MeshToSvoRequest misnamed = MeshTo(dir / "p.svo");
  misnamed.part = SvoPartOf{0, 2, 0};
  EXPECT_FALSE(MeshToSvo(misnamed).ok());
  EXPECT_FALSE(MeshToSvo(MeshTo(dir / "whole.svopart")).ok());
  EXPECT_FALSE(fs::exists(dir / "p.svo"));
  EXPECT_FALSE(fs::exists(dir / "whole.svopart"));
}

// The torus with a texture that does not decode: each route warns through the sink, and the file
// is still written.
TEST(Chain, WarningsReachTheSink) {
  test::TempDir dir;
  const fs::path mesh = dir / "uv-torus.obj";
  fs::copy_file(Torus(), mesh);
  fs::copy_file(test::DataDir() / "uv-torus.mtl", dir / "uv-torus.mtl");
  dir.Write("uv-torus.png", std::string("not a PNG"));
  std::vector<std::string> warnings;
  const WarningSink sink = [&](const std::string& w) { warnings.push_back(w); };
  const auto voxels = [&](std::optional<std::uint64_t> limit) {
    return [&, limit] {
      MeshToVoxelsRequest r = ToVoxels(dir / "t.vfrag", limit);
      r.input = mesh;
      r.warn = sink;
      return MeshToVoxels(r).status();
    };
  };
  const auto octree = [&](const std::string& output, std::optional<std::uint64_t> limit,
                          std::optional<SvoPartOf> part, const WarningSink& warn) {
    return [&, output, limit, part, warn] {
      MeshToSvoRequest r = MeshTo(dir / output, limit);
      r.input = mesh;
      r.part = part;
      r.warn = warn;
      return MeshToSvo(r).status();
    };
  };
  struct Route {
    std::string name;
    std::function<Status()> run;
  };
  for (const Route& route : std::vector<Route>{
           {"voxels whole", voxels(std::nullopt)},
           {"voxels by cubes", voxels(kLimit)},
           {"octree whole", octree("t.svo", std::nullopt, std::nullopt, sink)},
           {"octree by pages", octree("t.svo", kLimit, std::nullopt, sink)},
           {"a part", octree("t.svopart", std::nullopt, SvoPartOf{0, 1, 0}, sink)}}) {
    SCOPED_TRACE(route.name);
    warnings.clear();
    const Status run = route.run();
    ASSERT_TRUE(run.ok()) << run.message();
    ASSERT_FALSE(warnings.empty());
    EXPECT_NE(warnings[0].find("uv-torus.png"), std::string::npos) << warnings[0];
    EXPECT_NE(warnings[0].find("base colour"), std::string::npos) << warnings[0];
  }
  // No sink: the warnings go nowhere.
  EXPECT_TRUE(octree("t.svo", std::nullopt, std::nullopt, nullptr)().ok());
}

// The stages that run long on large grids (bricks, contours, write, read) count their units as
// they go: by the time each finishes it has reported (nearly) all of them, so a bar moves instead
// of sitting at 0 % and jumping to 100 %.
TEST(Chain, LongStagesReportTheirUnitsAsTheyGo) {
  test::TempDir dir;
  const auto units = [](const Progress& progress, const std::string& name) {
    for (const Progress::Timing& t : progress.timings()) {
      if (t.stage == name) return std::pair{t.units_done, t.units};
    }
    ADD_FAILURE() << "no stage " << name;
    return std::pair<std::uint64_t, std::uint64_t>{0, 0};
  };
  Progress build(Progress::Style::kQuiet);
  ASSERT_TRUE(MeshToSvo(MeshTo(dir / "t.svo"), build).ok());
  const auto [bricks_done, bricks] = units(build, "bricks");
  EXPECT_GT(bricks, 10'000u);  // every node above the voxels
  EXPECT_EQ(bricks_done, bricks);
  // Nodes without a piece of a triangle are not fitted: nearly all are.
  const auto [contours_done, contours] = units(build, "contours");
  EXPECT_GT(contours, bricks);
  EXPECT_LE(contours_done, contours);
  EXPECT_GE(contours_done, contours * 9 / 10);
  const auto [written, pages] = units(build, "write");
  EXPECT_GE(pages, 4u);
  EXPECT_EQ(written, pages);

  Progress read(Progress::Style::kQuiet);
  ASSERT_TRUE(ReadSvoStage(read, dir / "t.svo", std::nullopt).ok());
  EXPECT_EQ(units(read, "read"), std::pair(pages, pages));
}

// Each call checks its output before it imports anything: no stage runs, no file appears.
TEST(Chain, ABadOutputIsRefusedBeforeAnyWork) {
  test::TempDir dir;
  const fs::path missing = dir / "no-such-dir";
  const fs::path vfrag = dir / "t.vfrag";
  ASSERT_TRUE(MeshToVoxels(ToVoxels(vfrag)).ok());
  const auto expect_refused = [&](const auto& run, const fs::path& output, const std::string& why,
                                  StatusCode code = StatusCode::kBadInput) {
    SCOPED_TRACE(output.string());
    Progress progress(Progress::Style::kQuiet);
    const std::vector<std::string> before = dir.Files();
    const auto result = run(progress);
    ASSERT_FALSE(result.ok());
    EXPECT_EQ(result.status().code(), code);
    const std::string& message = result.status().message();
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    EXPECT_EQ(message.rfind(output.string(), 0), 0u) << message;
    EXPECT_NE(message.find(why), std::string::npos) << message;
    EXPECT_TRUE(progress.timings().empty()) << progress.timings().front().stage;
    EXPECT_EQ(dir.Files(), before);
  };
  const auto voxels = [&](const fs::path& input, const fs::path& output) {
    return [=](Progress& progress) {
      MeshToVoxelsRequest r = ToVoxels(output);
      r.input = input;
      return MeshToVoxels(r, progress);
    };
  };
  const auto build = [&](const fs::path& input, const fs::path& output) {
    return [=](Progress& progress) { return VoxelsToSvo(ToSvo(input, output), progress); };
  };
  const auto mesh = [&](const fs::path& input, const fs::path& output) {
    return [=](Progress& progress) {
      MeshToSvoRequest r = MeshTo(output);
      r.input = input;
      return MeshToSvo(r, progress);
    };
  };

  expect_refused(voxels(Torus(), dir / "t.svo"), dir / "t.svo", "output must be");
  expect_refused(build(vfrag, dir / "t.vfrag2"), dir / "t.vfrag2", "output must be a .svo file");
  expect_refused(mesh(Torus(), dir / "t.vfrag"), dir / "t.vfrag", "output must be a .svo file");
  expect_refused(mesh(Torus(), dir / "t"), dir / "t", "output must be a .svo file");

  expect_refused(voxels(Torus(), missing / "t.vfrag"), missing / "t.vfrag",
                 "output directory does not exist", StatusCode::kCannotWrite);
  expect_refused(build(vfrag, missing / "t.svo"), missing / "t.svo",
                 "output directory does not exist", StatusCode::kCannotWrite);
  expect_refused(mesh(Torus(), missing / "t.svo"), missing / "t.svo",
                 "output directory does not exist", StatusCode::kCannotWrite);

  // The input as its own output: a mesh that imports, kept as it was.
  const fs::path ply = dir / "box-room.ply";
  fs::copy_file(test::DataDir() / "box-room.ply", ply);
  const fs::path as_svo = dir / "mesh.svo";
  fs::copy_file(test::DataDir() / "box-room.ply", as_svo);
  const std::vector<std::uint8_t> mesh_bytes = test::ReadBytes(ply);
  expect_refused(voxels(ply, ply), ply, "is the input file");
  expect_refused(build(as_svo, as_svo), as_svo, "is the input file");
  expect_refused(mesh(as_svo, as_svo), as_svo, "is the input file");
  EXPECT_TRUE(test::ReadBytes(ply) == mesh_bytes);
  EXPECT_TRUE(test::ReadBytes(as_svo) == mesh_bytes);
  EXPECT_FALSE(fs::exists(missing));
}

}  // namespace
}  // namespace svokit
