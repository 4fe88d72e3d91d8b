#include "svokit/pipeline/memory_policy.hpp"

#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <vector>

#include <fmt/format.h>

#include "svokit/core/byte_size.hpp"

namespace svokit {

std::uint64_t MachineMemory() {
  if (const char* env = std::getenv("SVOKIT_MACHINE_MEMORY"); env != nullptr) {
    if (const StatusOr<std::uint64_t> v = ParseByteSize("SVOKIT_MACHINE_MEMORY", env); v.ok()) {
      return *v;
    }
  }
  const long pages = ::sysconf(_SC_PHYS_PAGES), size = ::sysconf(_SC_PAGE_SIZE);
  std::uint64_t memory = pages > 0 && size > 0
                             ? static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(size)
                             : 0;
  // The cgroup's limit: v2 "0::/PATH" in /proc/self/cgroup, limit in /sys/fs/cgroup/PATH/
  // memory.max; v1 "N:memory:/PATH", in /sys/fs/cgroup/memory/PATH/memory.limit_in_bytes (or at
  // the top of that hierarchy, where a container sees its own). "max" or a huge value: none.
  std::ifstream self("/proc/self/cgroup");
  std::string line;
  std::vector<std::string> limits = {"/sys/fs/cgroup/memory/memory.limit_in_bytes"};
  while (std::getline(self, line)) {
    if (line.starts_with("0::"))
      limits.push_back("/sys/fs/cgroup" + line.substr(3) + "/memory.max");
    if (const std::size_t at = line.find(":memory:"); at != std::string::npos) {
      limits.push_back("/sys/fs/cgroup/memory" + line.substr(at + 8) + "/memory.limit_in_bytes");
    }
  }
  for (const std::string& path : limits) {
    std::ifstream file(path);
    std::uint64_t allowed = 0;
    if (file >> allowed && allowed > 0 && (memory == 0 || allowed < memory)) memory = allowed;
  }
  return memory;
}

std::string MemoryPlan::WithinText() const {
  return fmt::format("within {}{}", ByteSizeText(static_cast<double>(limit)),
                     by_default ? fmt::format(" (half the machine: whole, it would need ~{})",
                                              ByteSizeText(whole_bytes))
                                : "");
}

MemoryPlan ChooseMemoryPlan(std::optional<std::uint64_t> given, double whole_bytes,
                            bool can_split) {
  MemoryPlan plan;
  plan.whole_bytes = whole_bytes;
  if (given) {
    plan.limit = *given;
    return plan;
  }
  const std::uint64_t half_machine = MachineMemory() / 2;
  if (can_split && half_machine > 0 && whole_bytes > static_cast<double>(half_machine)) {
    plan.limit = half_machine;
    plan.by_default = true;
  }
  return plan;
}

}  // namespace svokit
