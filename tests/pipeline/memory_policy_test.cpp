// The memory policy every tool shares: SVOKIT_MACHINE_MEMORY stands for the machine; a given
// limit is used as given; without one a stage runs whole when its estimate fits in half the
// machine, else by pages within that half, unless it cannot split; and the texts the summaries
// print.

#include "svokit/pipeline/memory_policy.hpp"

#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <optional>
#include <string>

namespace svokit {
namespace {

constexpr std::uint64_t kGiB = std::uint64_t{1} << 30;

// Sets (or, with nullopt, unsets) SVOKIT_MACHINE_MEMORY for the scope, and restores what was.
class MachineMemoryOverride {
 public:
  explicit MachineMemoryOverride(const std::optional<std::string>& value) {
    if (const char* old = std::getenv(kName)) old_ = old;
    Set(value);
  }
  ~MachineMemoryOverride() { Set(old_); }
  MachineMemoryOverride(const MachineMemoryOverride&) = delete;
  MachineMemoryOverride& operator=(const MachineMemoryOverride&) = delete;

 private:
  static constexpr const char* kName = "SVOKIT_MACHINE_MEMORY";
  static void Set(const std::optional<std::string>& value) {
    if (value) {
      ::setenv(kName, value->c_str(), 1);
    } else {
      ::unsetenv(kName);
    }
  }
  std::optional<std::string> old_;
};

TEST(MachineMemory, TheEnvironmentOverridesTheMachine) {
  {
    const MachineMemoryOverride machine("8G");
    EXPECT_EQ(MachineMemory(), 8 * kGiB);
  }
  {
    const MachineMemoryOverride machine("512m");
    EXPECT_EQ(MachineMemory(), std::uint64_t{512} << 20);
  }
  {
    const MachineMemoryOverride machine("3000000");
    EXPECT_EQ(MachineMemory(), 3000000u);
  }
}

TEST(MachineMemory, WithoutTheOverrideTheMachinesOwnAtMostItsPhysicalMemory) {
  std::uint64_t real = 0;
  {
    const MachineMemoryOverride machine(std::nullopt);
    real = MachineMemory();
  }
  const long pages = ::sysconf(_SC_PHYS_PAGES), page_size = ::sysconf(_SC_PAGE_SIZE);
  ASSERT_GT(pages, 0);
  ASSERT_GT(page_size, 0);
  EXPECT_GT(real, 0u);
  EXPECT_LE(real, static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(page_size));
  // An override that is not a size is ignored.
  for (const std::string bad : {"", "lots", "0", "1.5G"}) {
    const MachineMemoryOverride machine(bad);
    EXPECT_EQ(MachineMemory(), real) << "'" << bad << "'";
  }
}

TEST(ChooseMemoryPlan, AGivenLimitIsUsedAsGiven) {
  const MachineMemoryOverride machine("8G");
  for (const double whole : {0.0, 1e6, 1e15}) {
    for (const bool can_split : {true, false}) {
      const MemoryPlan plan = ChooseMemoryPlan(std::uint64_t{512} << 20, whole, can_split);
      EXPECT_TRUE(plan.by_pages());
      EXPECT_EQ(plan.limit, std::uint64_t{512} << 20);
      EXPECT_FALSE(plan.by_default);
      EXPECT_EQ(plan.whole_bytes, whole);
    }
  }
  // Even a limit above the machine: the caller asked for it.
  const MemoryPlan above = ChooseMemoryPlan(64 * kGiB, 1e9);
  EXPECT_EQ(above.limit, 64 * kGiB);
  EXPECT_FALSE(above.by_default);
}

TEST(ChooseMemoryPlan, WithoutALimitWholeWhenItFitsInHalfTheMachine) {
  const MachineMemoryOverride machine("8G");
  for (const double whole :
       {0.0, 1e6, 3.9 * static_cast<double>(kGiB), static_cast<double>(4 * kGiB)}) {
    const MemoryPlan plan = ChooseMemoryPlan(std::nullopt, whole);
    EXPECT_FALSE(plan.by_pages()) << whole;
    EXPECT_EQ(plan.limit, 0u);
    EXPECT_FALSE(plan.by_default);
    EXPECT_EQ(plan.whole_bytes, whole);
  }
}

TEST(ChooseMemoryPlan, WithoutALimitByPagesWithinHalfTheMachineWhenItDoesNot) {
  const MachineMemoryOverride machine("8G");
  for (const double whole :
       {static_cast<double>(4 * kGiB) + 1, 20.0 * static_cast<double>(kGiB), 1e15}) {
    const MemoryPlan plan = ChooseMemoryPlan(std::nullopt, whole);
    EXPECT_TRUE(plan.by_pages()) << whole;
    EXPECT_EQ(plan.limit, 4 * kGiB);
    EXPECT_TRUE(plan.by_default);
    EXPECT_EQ(plan.whole_bytes, whole);
  }
  // Half of another machine.
  const MachineMemoryOverride small("1G");
  EXPECT_EQ(ChooseMemoryPlan(std::nullopt, 1e9).limit, kGiB / 2);
  EXPECT_FALSE(ChooseMemoryPlan(std::nullopt, 5e8).by_pages());
}

TEST(ChooseMemoryPlan, NeverByPagesWhenTheStageCannotSplit) {
  const MachineMemoryOverride machine("8G");
  for (const double whole : {1e6, 20.0 * static_cast<double>(kGiB), 1e15}) {
    const MemoryPlan plan = ChooseMemoryPlan(std::nullopt, whole, false);
    EXPECT_FALSE(plan.by_pages()) << whole;
    EXPECT_FALSE(plan.by_default);
    EXPECT_EQ(plan.whole_bytes, whole);
  }
}

TEST(MemoryPlan, WithinTextSaysTheLimitAndWhyWhenItIsTheDefault) {
  const MachineMemoryOverride machine("8G");
  EXPECT_EQ(ChooseMemoryPlan(4 * kGiB, 0).WithinText(), "within 4.0 GiB");
  EXPECT_EQ(ChooseMemoryPlan(std::uint64_t{512} << 20, 1e12).WithinText(), "within 512 MiB");
  EXPECT_EQ(ChooseMemoryPlan(std::nullopt, 10.0 * static_cast<double>(kGiB)).WithinText(),
            "within 4.0 GiB (half the machine: whole, it would need ~10.0 GiB)");
  EXPECT_EQ(ChooseMemoryPlan(std::nullopt, 1.26 * 1099511627776).WithinText(),
            "within 4.0 GiB (half the machine: whole, it would need ~1290.2 GiB)");
  const MachineMemoryOverride small("1G");
  EXPECT_EQ(ChooseMemoryPlan(std::nullopt, 600.0 * 1048576).WithinText(),
            "within 512 MiB (half the machine: whole, it would need ~600 MiB)");
}

}  // namespace
}  // namespace svokit
