#include "svokit/export/dag_build.hpp"

#include <algorithm>
#include <memory>
#include <utility>
#include <vector>

#include "svokit/core/byte_size.hpp"
#include "svokit/core/parallel.hpp"
#include "svokit/formats/svo/svo_chunk.hpp"
#include "svokit/formats/svo/svo_stream.hpp"

namespace svokit {

namespace {

Status TooLarge(const SvoReader& reader, std::uint64_t dag_limit) {
  return Status::OutOfMemory(
      "{}: its DAG outgrows the {} the memory limit leaves it besides the pages; raise "
      "--memory-limit or export a coarser --level",
      reader.name(), ByteSizeText(static_cast<double>(dag_limit)));
}

// Bytes a page holds while it is reduced: its stored bytes, and per node above the voxels its
// mask and child offset once decoded, its distinct node (up to 9 words), table slot and offset.
constexpr std::uint64_t kReducedBytesPerNode = 1 + 8 + 36 + 6 + 4;

// The pages in key order, decoded to their masks, as many in flight as fit a quarter of
// `memory_limit` (one at least; 0: a few per thread); largest_page is what each one holds.
StatusOr<SvoStreamPlan> PlanReduction(const SvoReader& reader, std::uint64_t memory_limit) {
  SvoStreamPlan plan;
  plan.pages = PageOrder(reader, SvoPageOrder::kKeys);
  plan.parts = ChunkParts::kMasks;
  plan.largest_page = 1;
  for (const std::size_t i : plan.pages) {
    StatusOr<ChunkBytes> streams = reader.PageStreamBytes(i);
    if (!streams.ok()) return streams.status();
    std::uint64_t nodes = 0;
    for (const auto& [name, sizes] : streams->by_name) {
      if (name == "masks") nodes += sizes.first;
    }
    plan.largest_page =
        std::max(plan.largest_page, reader.page(i).stored_bytes + kReducedBytesPerNode * nodes);
  }
  StatusOr<std::size_t> in_flight = InFlightWithin(
      memory_limit, 0, plan.largest_page, plan.largest_page, "this file", "a page and its subtree");
  if (!in_flight.ok()) return in_flight.status().WithContext(reader.name());
  plan.in_flight = memory_limit == 0 ? *in_flight
                                     : std::clamp<std::size_t>(memory_limit / 4 / plan.largest_page,
                                                               1, *in_flight);
  return plan;
}

// The page roots' masks (and full masks) appended to the top chunk's tree as its level P, for a
// DAG whose voxels are level P + 1: its leaves are the page roots.
Status AddPageRoots(const SvoReader& reader, const SvoStreamPlan& plan, MaskTree& tree,
                    Progress::Stage* stage) {
  using RootMasks = std::pair<std::uint8_t, std::uint8_t>;  // mask, full mask
  std::vector<std::uint8_t> masks, full;
  SVOKIT_RETURN_IF_ERROR(StreamPages<RootMasks>(
      reader, plan,
      [](std::size_t, SvoChunk page) -> StatusOr<RootMasks> {
        const std::uint8_t f = page.tree.full.empty() ? 0 : page.tree.full[0][0];
        return std::pair(page.tree.masks[0][0], f);
      },
      [&](std::size_t, RootMasks root) {
        masks.push_back(root.first);
        full.push_back(root.second);
        return Status::Ok();
      },
      stage));
  if (!tree.full.empty()) tree.full.push_back(std::move(full));
  tree.masks.push_back(std::move(masks));
  tree.LinkChildren();
  return Status::Ok();
}

}  // namespace

StatusOr<VoxelDag> BuildDag(const SvoReader& reader, std::uint32_t level,
                            std::uint64_t memory_limit, Progress::Stage* stage) {
  SVOKIT_RETURN_IF_ERROR(CheckSvoLevel(reader, level));
  if (level < 2) {
    return Status::BadInput("{}: a DAG needs level 2 or deeper (its leaves are 4³ voxels)",
                            reader.name());
  }
  // Pages in flight take at most a quarter of the limit (one page at least), the DAG the rest.
  StatusOr<SvoStreamPlan> plan = PlanReduction(reader, memory_limit);
  if (!plan.ok()) return plan.status();
  const std::uint64_t dag_limit =
      memory_limit - std::min(memory_limit, plan->in_flight * plan->largest_page);
  StatusOr<SvoChunk> top = reader.Top(ChunkParts::kMasks);
  if (!top.ok()) return top.status();

  // Levels the top chunk holds: the DAG is the top tree's, with the page roots below it when
  // they are the leaves' children.
  const std::uint32_t page_level = reader.page_level();
  if (level <= page_level + 1) {
    if (level == page_level + 1)
      SVOKIT_RETURN_IF_ERROR(AddPageRoots(reader, *plan, top->tree, stage));
    DagBuilder builder(level);
    StatusOr<std::uint32_t> root = builder.Add(ReduceSubtree(top->tree, level));
    if (!root.ok()) return root.status().WithContext(reader.name());
    return builder.Finish(MaskTree{}, std::vector<std::uint32_t>{*root});
  }

  DagBuilder builder(level);
  std::vector<std::uint32_t> roots;
  roots.reserve(plan->pages.size());
  // Held by pointer: GCC 12 warns of a moved-from DagSubtree inside StatusOr's variant.
  using Subtree = std::unique_ptr<DagSubtree>;
  SVOKIT_RETURN_IF_ERROR(StreamPages<Subtree>(
      reader, *plan,
      [&](std::size_t, SvoChunk page) -> StatusOr<Subtree> {
        return std::make_unique<DagSubtree>(ReduceSubtree(page.tree, level));
      },
      [&](std::size_t, Subtree subtree) -> Status {
        StatusOr<std::uint32_t> root = builder.Add(*subtree);
        if (!root.ok()) return root.status().WithContext(reader.name());
        if (memory_limit != 0 && builder.held_bytes() > dag_limit)
          return TooLarge(reader, dag_limit);
        roots.push_back(*root);
        return Status::Ok();
      },
      stage));
  StatusOr<VoxelDag> dag = builder.Finish(top->tree, roots);
  if (!dag.ok()) return dag.status().WithContext(reader.name());
  return dag;
}

}  // namespace svokit
