// The DAG of a paged .svo: it expands to the file's voxels at every level (below, at and above the
// page level), is the same DAG and the same files whatever the memory limit and thread count, and
// the two renderers' node arrays hold what their specs' worked examples say (formats/dag.md).
// Bad requests fail with one line and leave no file.

#include <gtest/gtest.h>

#include <unistd.h>

#include "svokit/core/thread_limit.hpp"
#include "svokit/export/dag_build.hpp"
#include "svokit/export/dag_files.hpp"
#include "svokit/formats/svo/svo_stream.hpp"
#include "tests/formats/paged_torus.hpp"

namespace svokit {
namespace {

std::filesystem::path Out(const std::string& name) {
  return std::filesystem::temp_directory_path() /
         ("svokit_dag_" + std::to_string(::getpid()) + "_" + name);
}

std::vector<std::uint64_t> LevelKeys(const SvoReader& reader, std::uint32_t level) {
  std::vector<std::uint64_t> keys;
  EXPECT_TRUE(ForEachVoxelPage(reader, level, {}, [&](SvoVoxelPage& page) {
                keys.insert(keys.end(), page.keys.begin(), page.keys.end());
                return Status::Ok();
              }).ok());
  return keys;
}

// SymVox's node array of `dag`, and its node count.
std::vector<std::uint32_t> SvdagWords(VoxelDag dag, std::uint64_t& nodes) {
  const SvdagLayout layout(dag);
  nodes = layout.nodes();
  std::vector<std::uint32_t> words;
  EXPECT_TRUE(layout
                  .Emit(dag,
                        [&](std::span<const std::uint32_t> w) {
                          words.insert(words.end(), w.begin(), w.end());
                          return Status::Ok();
                        })
                  .ok());
  EXPECT_EQ(words.size(), layout.words());
  return words;
}

// HashDAG's node array of `dag`: its levels turned, one after another.
std::vector<std::uint32_t> HashDagWords(VoxelDag dag, std::vector<std::uint64_t>& enclosed) {
  ToHashDagLayout(dag, 1, enclosed);
  std::vector<std::uint32_t> words;
  for (const DagLevel& level : dag.levels) {
    words.insert(words.end(), level.words.begin(), level.words.end());
  }
  return words;
}

TEST(DagExport, ExpandsToTheFilesNodesAtEveryLevel) {
  const SvoReader r = test::OpenPagedTorus();
  ASSERT_GT(r.page_count(), 8u);
  for (const std::uint32_t level :
       {r.depth(), r.page_level() + 2, r.page_level() + 1, r.page_level(), 2u}) {
    StatusOr<VoxelDag> dag = BuildDag(r, level, 0);
    ASSERT_TRUE(dag.ok()) << dag.status().message();
    EXPECT_EQ(dag->depth, level);
    EXPECT_EQ(DagVoxelKeys(*dag), LevelKeys(r, level)) << "level " << level;
  }
}

TEST(DagExport, SameDagAndFilesAtEveryMemoryLimitAndThreadCount) {
  const SvoReader r = test::OpenPagedTorus();
  StatusOr<VoxelDag> want = BuildDag(r, r.depth(), 0);
  ASSERT_TRUE(want.ok());
  const std::filesystem::path hashdag = Out("whole.dag.bin"), svdag = Out("whole.svdag");
  ASSERT_TRUE(ExportDag(r, hashdag, {r.depth(), 0}).ok());
  ASSERT_TRUE(ExportDag(r, svdag, {r.depth(), 0}).ok());
  const std::vector<std::uint8_t> want_hashdag = test::ReadBytes(hashdag),
                                  want_colors = test::ReadBytes(HashDagColorsPath(hashdag)),
                                  want_svdag = test::ReadBytes(svdag),
                                  want_packed = test::ReadBytes(PackedColorsPath(svdag));
  // The DAG by itself within 4 MiB (one page in flight); with its colours, whose pages are
  // decoded whole, within 16 MiB.
  {
    ThreadLimit t(2);
    StatusOr<VoxelDag> small = BuildDag(r, r.depth(), std::uint64_t{4} << 20);
    ASSERT_TRUE(small.ok()) << small.status().message();
    for (std::size_t l = 0; l < want->levels.size(); ++l) {
      EXPECT_TRUE(small->levels[l].words == want->levels[l].words) << "level " << l;
    }
  }
  for (const auto& [limit, threads] : {std::pair<std::uint64_t, std::size_t>{0, 1},
                                       {std::uint64_t{16} << 20, 2},
                                       {std::uint64_t{64} << 20, 1}}) {
    ThreadLimit t(threads);
    StatusOr<VoxelDag> got = BuildDag(r, r.depth(), limit);
    ASSERT_TRUE(got.ok()) << got.status().message();
    ASSERT_EQ(got->levels.size(), want->levels.size());
    for (std::size_t l = 0; l < want->levels.size(); ++l) {
      EXPECT_TRUE(got->levels[l].words == want->levels[l].words)
          << "level " << l << ", limit " << limit << ", threads " << threads;
    }
    const std::filesystem::path h = Out("limited.dag.bin"), s = Out("limited.svdag");
    ASSERT_TRUE(ExportDag(r, h, {r.depth(), limit}).ok());
    ASSERT_TRUE(ExportDag(r, s, {r.depth(), limit}).ok());
    EXPECT_TRUE(test::ReadBytes(h) == want_hashdag) << limit;
    EXPECT_TRUE(test::ReadBytes(HashDagColorsPath(h)) == want_colors) << limit;
    EXPECT_TRUE(test::ReadBytes(s) == want_svdag) << limit;
    EXPECT_TRUE(test::ReadBytes(PackedColorsPath(s)) == want_packed) << limit;
    for (const auto& p : {h, HashDagColorsPath(h), s, PackedColorsPath(s)}) {
      std::filesystem::remove(p);
    }
  }
  for (const auto& p : {hashdag, HashDagColorsPath(hashdag), svdag, PackedColorsPath(svdag)}) {
    std::filesystem::remove(p);
  }
}

TEST(DagExport, NodeArraysOfTheSpecsExamples) {
  // One voxel at (1, 0, 0) of an 8³ grid: HashDAG's root (child 0, its voxel count by index 0
  // of the enclosed counts) and one leaf with bit 4 (voxel 4x + 2y + z of octant 0).
  VoxelDag one;
  one.depth = 3;
  one.levels.resize(2);
  one.levels[0] = {{0x1u, 0u}, 1};
  one.levels[1] = {{1u << 1, 0u}, 1};  // svokit's leaf bit x + 2y + 4z = 1
  std::vector<std::uint64_t> enclosed;
  EXPECT_EQ(HashDagWords(one, enclosed), (std::vector<std::uint32_t>{0x1, 2, 0x10, 0}));
  EXPECT_EQ(enclosed, std::vector<std::uint64_t>{1});
  // One voxel at (0, 0, 0) of a 4³ grid in SymVox's layout: the root's mask, its pointer, the
  // 2³ leaf.
  VoxelDag corner;
  corner.depth = 2;
  corner.levels = {{{0x1u, 0u}, 1}};
  std::uint64_t nodes = 0;
  EXPECT_EQ(SvdagWords(corner, nodes), (std::vector<std::uint32_t>{0x1, 2, 0x1}));
  EXPECT_EQ(nodes, 2u);
  // A voxel at (0, 0, 1) of 8³: the leaf's byte moves to HashDAG's octant 1, its bit to bit 1 of
  // it; SymVox stores child pointers from child 7 down.
  VoxelDag z;
  z.depth = 3;
  z.levels.resize(2);
  z.levels[0] = {{0x1u, 0u}, 1};
  z.levels[1] = {{1u << 4, 0u}, 1};  // svokit's bit x + 2y + 4z = 4
  enclosed.clear();
  EXPECT_EQ(HashDagWords(z, enclosed), (std::vector<std::uint32_t>{0x1, 2, 0x1 << 1, 0}));
  EXPECT_EQ(SvdagWords(z, nodes), (std::vector<std::uint32_t>{0x1, 2, 0x1, 4, 0x2}));
  EXPECT_EQ(nodes, 3u);
}

TEST(DagExport, SsvdagOfTheSpecsExamples) {
  // Voxels (1, 0, 0) and (6, 0, 0) of an 8³ grid: one leaf, the second seen through mirror x
  // (pointer bit 13) from SymVox's child 4; pointers from child 7 down (formats/dag.md).
  VoxelDag pair;
  pair.depth = 3;
  pair.levels.resize(2);
  pair.levels[0] = {{0x1u | 0x2u, 0u, 2u}, 1};  // svokit children 0 and 1 (x = 0, x = 1)
  pair.levels[1] = {{1u << 1, 0u,               // (1, 0, 0): x bit 0 of octant 0
                     1u << 8, 0u},              // (6, 0, 0) = (2, 0, 0) in octant 1: bit 8
                    2};
  StatusOr<SymmetricDag> symmetric = ReduceSymmetries(pair);
  ASSERT_TRUE(symmetric.ok());
  std::uint64_t nodes = 0;
  std::vector<std::uint8_t> got;
  ASSERT_TRUE(WriteSsvdagBody(*symmetric, nodes, [&](std::span<const std::uint8_t> bytes) {
                got.insert(got.end(), bytes.begin(), bytes.end());
                return Status::Ok();
              }).ok());
  const std::vector<std::uint8_t> want = {
      3,    0,    0,    0,                  // 3 inner u16
      0x01, 0x01, 0x00, 0x20, 0, 0,         // header 0x0101, child 4 → leaf 0 mirrored x, child 0
      8,    0,    0,    0,                  // 8 leaf bytes
      0,    0,    1,    0,    0, 0, 0, 0,   // bit 16: (1, 0, 0)
      1,    0,    0,    0,    0, 0, 0, 0};  // one inner level, at 0
  EXPECT_EQ(got, want);
  EXPECT_EQ(nodes, 1u);
}

TEST(DagExport, BadRequestsFailAndLeaveNoFile) {
  const SvoReader r = test::OpenPagedTorus();
  const std::filesystem::path svdag = Out("bad.svdag"), hashdag = Out("bad.dag.bin");
  const auto expect_refused = [&](const StatusOr<DagExport>& got, const std::filesystem::path& p,
                                  const std::string& says) {
    ASSERT_FALSE(got.ok()) << p;
    EXPECT_NE(got.status().message().find(says), std::string::npos) << got.status().message();
    EXPECT_EQ(got.status().message().find('\n'), std::string::npos);
    EXPECT_FALSE(std::filesystem::exists(p));
    EXPECT_FALSE(std::filesystem::exists(HashDagColorsPath(hashdag)));
    EXPECT_FALSE(std::filesystem::exists(PackedColorsPath(p)));
  };
  expect_refused(ExportDag(r, svdag, {1, 0}), svdag, "level 2 or deeper");
  expect_refused(ExportDag(r, hashdag, {2, 0}), hashdag, "level 3 or deeper");
  expect_refused(ExportDag(r, hashdag, {r.depth() + 1, 0}), hashdag, "exceeds the octree's depth");
  // One page's masks and subtree fit 1.75 MiB, the DAG (about 1 MiB with its tables) not what
  // is left.
  expect_refused(ExportDag(r, svdag, {r.depth(), std::uint64_t{7} << 18, DagColorFile::kNone}),
                 svdag, "--memory-limit");
  // A limit below one page's: refused before anything is built.
  expect_refused(ExportDag(r, hashdag, {r.depth(), std::uint64_t{1} << 20}), hashdag,
                 "too small for this file");
}

}  // namespace
}  // namespace svokit
