// Variable-resolution leaves (svo-build --prune): the tolerances' syntax; a pruned octree of a
// textured mesh keeps the full octree's bricks, contours and voxels for every node it keeps,
// drops only what lies below its leaves, and each leaf meets the tolerances by the validator's own
// recomputation from the full octree's voxels; the validator finds leaves beyond the tolerances
// META records; the strict whole-file reader and the renderer take pruned files, and a render of
// one stays close to the full octree's; pruning is the same at any thread count.

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "svokit/core/thread_limit.hpp"
#include "svokit/formats/container/container.hpp"
#include "svokit/formats/mesh_import.hpp"
#include "svokit/formats/provenance.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/formats/svo/svo_reader.hpp"
#include "svokit/inspect/ray_cast.hpp"
#include "svokit/svo/build_options.hpp"
#include "svokit/svo/compact_build.hpp"
#include "svokit/svo/prune_tree.hpp"
#include "svokit/validate/pruned_octree.hpp"
#include "svokit/validate/validate.hpp"
#include "svokit/voxelize/voxelize.hpp"
#include "tests/test_util.hpp"

namespace svokit::validate {
namespace {

// The textured torus at `resolution` with colour and normal, 3³ bricks and contours, pruned to
// `prune` when given (META records the build as the tools do).
std::vector<std::uint8_t> TorusFile(std::uint32_t resolution, std::optional<PruneTolerances> prune,
                                    bool contours = true) {
  static const Mesh mesh = [] {
    auto m = ImportMesh(test::DataDir() / "uv-torus.obj");
    EXPECT_TRUE(m.ok()) << m.status().message();
    return std::move(*m);
  }();
  auto grid = GridTransform::FitResolution(mesh.Bounds(), resolution);
  VoxelizeOptions vo;
  vo.colors = vo.normals = true;
  auto voxels = Voxelize(mesh, *grid, vo);
  EXPECT_TRUE(voxels.ok());
  BuildOptions bo;
  bo.prune = prune;
  bo.contours = contours;
  Provenance provenance;
  provenance.source = "uv-torus.obj";
  provenance.build = BuildSettings{3, contours, {}, prune};
  auto svo = BuildCompactSvo(std::move(*voxels), &mesh, bo, ProvenanceJson(provenance));
  EXPECT_TRUE(svo.ok()) << svo.status().message();
  return EncodeSvo(*svo);
}

SvoReader Open(const std::vector<std::uint8_t>& bytes, const std::string& name) {
  StatusOr<SvoReader> reader = SvoReader::FromBytes(bytes, name);
  EXPECT_TRUE(reader.ok()) << reader.status().message();
  return std::move(*reader);
}

// The same file with META's recorded tolerances replaced by `recorded`.
std::vector<std::uint8_t> WithRecordedTolerances(const std::vector<std::uint8_t>& bytes,
                                                 const PruneTolerances& recorded) {
  auto frame = container::Frame::FromBytes(bytes, "p.svo", kSvoFormat);
  EXPECT_TRUE(frame.ok());
  container::Writer writer(kSvoFormat, 0);
  for (const container::Frame::Section& s : frame->sections()) {
    if (s.tag != container::MakeTag("META")) {
      writer.AddSection(s.tag, {s.bytes.begin(), s.bytes.end()});
      continue;
    }
    Provenance p = ParseProvenance({reinterpret_cast<const char*>(s.bytes.data()), s.bytes.size()});
    p.build->prune = recorded;
    const std::string json = ProvenanceJson(p);
    writer.AddSection(s.tag, {json.begin(), json.end()});
  }
  return writer.Serialize();
}

TEST(PruneTolerances, ParseTermsInAnyOrderAndRefuseBadOnes) {
  auto t = ParsePruneTolerances("default");
  ASSERT_TRUE(t.ok());
  EXPECT_EQ(*t, PruneTolerances{});
  EXPECT_DOUBLE_EQ(t->color, 16.0 / 256.0);
  EXPECT_DOUBLE_EQ(t->geometry, std::sqrt(3.0));
  t = ParsePruneTolerances("geometry=2.5,color=0.1");
  ASSERT_TRUE(t.ok());
  EXPECT_DOUBLE_EQ(t->geometry, 2.5);
  EXPECT_DOUBLE_EQ(t->color, 0.1);
  EXPECT_DOUBLE_EQ(t->normal, 0.01);
  auto back = ParsePruneTolerances(PruneSpec(*t));
  ASSERT_TRUE(back.ok());
  EXPECT_EQ(*back, *t);
  for (const char* bad : {"colour", "shape=1", "color=-1", "color=2", "geometry=9", "normal=nan",
                          "color=0.1,", "color=0.1x"}) {
    auto r = ParsePruneTolerances(bad);
    ASSERT_FALSE(r.ok()) << bad;
    EXPECT_NE(r.status().message().find("--prune"), std::string::npos) << r.status().message();
  }
}

TEST(PrunedOctree, LeavesMeetTheTolerancesAndKeptNodesAreTheFullOctrees) {
  const std::vector<std::uint8_t> full = TorusFile(256, std::nullopt);
  const std::vector<std::uint8_t> pruned = TorusFile(256, PruneTolerances{});
  const SvoReader f = Open(full, "full.svo"), p = Open(pruned, "pruned.svo");
  ASSERT_TRUE(p.shape().pruned);
  ASSERT_FALSE(f.shape().pruned);
  ASSERT_GT(f.page_count(), 1u);  // leaves next to other pages' voxels: halos across pages
  EXPECT_LT(pruned.size(), full.size() / 2);
  EXPECT_LT(p.NodeCount(p.depth()), f.NodeCount(f.depth()) / 4);

  auto [bricks, leaves] = CheckPrunedOctree(p, f, Progress::Silent());
  EXPECT_EQ(bricks.state, CheckResult::State::kPassed) << bricks.examples.front().message;
  EXPECT_EQ(leaves.state, CheckResult::State::kPassed) << leaves.note;
  ASSERT_EQ(leaves.stats.size(), 1u);
  EXPECT_GT(leaves.stats[0].second, 100u);

  // The whole validator: structure (masks, halos under leaves, counts) and the checks above.
  auto lenient = LenientSvoReader::FromBytes(pruned, "pruned.svo");
  ASSERT_TRUE(lenient.ok());
  ValidateOptions options;
  options.full = &f;
  StatusOr<Report> report = ValidatePaged(*lenient, "pruned.svo", options);
  ASSERT_TRUE(report.ok()) << report.status().message();
  EXPECT_TRUE(report->ok()) << report->Text();
  // Without the full octree the bricks cannot be vouched for, and say so.
  options.full = nullptr;
  report = ValidatePaged(*lenient, "pruned.svo", options);
  ASSERT_TRUE(report.ok());
  EXPECT_NE(report->Text().find("pruned_leaves   skipped"), std::string::npos) << report->Text();

  // The strict whole-file reader takes it: leaves are nodes without children above the voxels.
  StatusOr<Svo> whole = DecodeSvo(pruned, "pruned.svo");
  ASSERT_TRUE(whole.ok()) << whole.status().message();
  std::uint64_t childless = 0;
  for (std::uint32_t l = 0; l < whole->depth; ++l) {
    for (const SvoNode& n : whole->levels[l].nodes) childless += n.child_mask == 0;
  }
  EXPECT_EQ(childless, leaves.stats[0].second);
}

TEST(PrunedOctree, TheValidatorFindsLeavesBeyondTheRecordedTolerances) {
  const std::vector<std::uint8_t> full = TorusFile(128, std::nullopt);
  const PruneTolerances loose{0.5, 1.0, 6.0};
  const std::vector<std::uint8_t> pruned = TorusFile(128, loose);
  const SvoReader f = Open(full, "full.svo");
  {
    const SvoReader p = Open(pruned, "pruned.svo");
    auto [bricks, leaves] = CheckPrunedOctree(p, f, Progress::Silent());
    EXPECT_EQ(leaves.state, CheckResult::State::kPassed) << leaves.note;
  }
  const std::vector<std::uint8_t> claimed = WithRecordedTolerances(pruned, PruneTolerances{});
  const SvoReader p = Open(claimed, "claimed.svo");
  auto [bricks, leaves] = CheckPrunedOctree(p, f, Progress::Silent());
  EXPECT_EQ(bricks.state, CheckResult::State::kPassed);
  EXPECT_EQ(leaves.state, CheckResult::State::kFailed);
  EXPECT_GT(leaves.counts["pruned_leaf"], 0u);

  // A reference that is not the octree it was pruned from.
  const std::vector<std::uint8_t> other = TorusFile(128, PruneTolerances{});
  const SvoReader o = Open(other, "other.svo");
  auto [wrong, skipped] = CheckPrunedOctree(p, o, Progress::Silent());
  EXPECT_EQ(wrong.state, CheckResult::State::kFailed);
  EXPECT_EQ(skipped.state, CheckResult::State::kSkipped);
}

// Without contours a leaf's region is its whole cube: only nodes whose cube its voxels fill to
// within the geometric tolerance become leaves.
TEST(PrunedOctree, WithoutContoursLeavesAreTheirCubes) {
  const std::vector<std::uint8_t> full = TorusFile(128, std::nullopt, false);
  const std::vector<std::uint8_t> pruned = TorusFile(128, PruneTolerances{}, false);
  const SvoReader f = Open(full, "full.svo"), p = Open(pruned, "pruned.svo");
  auto [bricks, leaves] = CheckPrunedOctree(p, f, Progress::Silent());
  EXPECT_EQ(bricks.state, CheckResult::State::kPassed);
  EXPECT_EQ(leaves.state, CheckResult::State::kPassed) << leaves.note;
  ASSERT_EQ(leaves.stats.size(), 1u);
  EXPECT_GT(leaves.stats[0].second, 0u);
  EXPECT_LT(p.NodeCount(p.depth()), f.NodeCount(f.depth()));
}

TEST(PrunedOctree, SameBytesAtAnyThreadCount) {
  const std::vector<std::uint8_t> two = TorusFile(256, PruneTolerances{});
  ThreadLimit one(1);
  EXPECT_EQ(TorusFile(256, PruneTolerances{}), two);
}

TEST(PrunedOctree, RendersCloseToTheFullOctree) {
  const std::vector<std::uint8_t> full = TorusFile(256, std::nullopt);
  const std::vector<std::uint8_t> pruned = TorusFile(256, PruneTolerances{});
  RenderOptions options;
  options.view = View::kIso;
  options.width = options.height = 256;
  StatusOr<RenderResult> a = RenderSvo(Open(full, "f.svo"), options, 0);
  StatusOr<RenderResult> b = RenderSvo(Open(pruned, "p.svo"), options, 0);
  ASSERT_TRUE(a.ok() && b.ok());
  std::uint64_t both = 0, either = 0;
  double diff = 0;
  for (int y = 0; y < options.height; ++y) {
    for (int x = 0; x < options.width; ++x) {
      const std::size_t at = 4 * (static_cast<std::size_t>(y) * options.width + x);
      const std::uint8_t* pa = &a->image.pixels[at];
      const std::uint8_t* pb = &b->image.pixels[at];
      const bool ha = pa[3] != 0, hb = pb[3] != 0;
      either += ha || hb;
      if (!(ha && hb)) continue;
      ++both;
      for (int c = 0; c < 3; ++c) diff += std::abs(int(pa[c]) - int(pb[c])) / 255.0;
    }
  }
  ASSERT_GT(both, 10000u);
  EXPECT_GT(static_cast<double>(both) / static_cast<double>(either), 0.97);
  EXPECT_LT(diff / (3.0 * static_cast<double>(both)), 0.04);
}

}  // namespace
}  // namespace svokit::validate
