#pragma once
// Whole or by pages: how every tool that may hold a grid decides, the same way. A stage runs
// whole unless a memory limit is given, or the whole run would not fit in half the machine's
// memory (then by pages within that half: the same file either way).

#include <cstdint>
#include <optional>
#include <string>

namespace svokit {

/// The memory the tools may count on, in bytes (0 if unknown): the machine's physical memory, or
/// less where the process's cgroup (a container's or batch job's allocation) allows less; the
/// environment variable SVOKIT_MACHINE_MEMORY (a size such as 8G) overrides both.
std::uint64_t MachineMemory();

/// Bytes a voxel takes while a stage holds its grid whole: voxelizing (keys; with colour or
/// normal, their attributes too) and building the octree (nodes; with bricks, their samples).
inline constexpr double kVoxelizeBytes = 8, kVoxelizeAttributeBytes = 16;
inline constexpr double kBuildBytes = 48, kBuildBrickBytes = 100;

/// How a stage runs: whole, or a page (or cube) at a time within `limit` bytes.
struct MemoryPlan {
  std::uint64_t limit = 0;  ///< 0: whole
  bool by_default = false;  ///< `limit` is half the machine, as the whole would not fit there
  double whole_bytes = 0;   ///< what the whole run would take (0: not estimated)
  bool by_pages() const { return limit > 0; }
  /// "within 4.0 GiB", and when the limit is the default, what the whole run would have needed.
  std::string WithinText() const;
};

/// The plan for a stage: `given` when a limit is given; else by pages within half of
/// MachineMemory() when `whole_bytes` exceed it and the stage `can_split` (a solid of an open
/// surface builds whole), else whole.
MemoryPlan ChooseMemoryPlan(std::optional<std::uint64_t> given, double whole_bytes,
                            bool can_split = true);

}  // namespace svokit
