#include "svokit/core/release_pages.hpp"

#include <gtest/gtest.h>

#include <sys/mman.h>
#include <unistd.h>

#include <cstdint>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>

namespace svokit {
namespace {

// Whole pages inside the range read as zero afterwards; the partial pages at its ends, and
// everything outside it, keep their bytes.
TEST(ReleasePages, ZeroesTheWholePagesInsideTheRangeOnly) {
  const std::size_t page = static_cast<std::size_t>(::sysconf(_SC_PAGESIZE));
  constexpr std::size_t kPages = 8;
  void* map =
      ::mmap(nullptr, kPages * page, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  ASSERT_NE(map, MAP_FAILED);
  auto* bytes = static_cast<std::uint8_t*>(map);
  std::memset(bytes, 0xab, kPages * page);

  ReleasePages(bytes + 100, bytes + 5 * page + 10);  // whole pages 1–4
  for (std::size_t i = 0; i < kPages * page; ++i) {
    const bool released = i >= page && i < 5 * page;
    ASSERT_EQ(bytes[i], released ? 0 : 0xab) << "byte " << i;
  }
  std::memset(bytes, 0xab, kPages * page);
  ReleasePages(bytes + page + 1, bytes + 2 * page + page - 1);  // no whole page inside
  ReleasePages(bytes + 3 * page, bytes + 3 * page);             // empty
  for (std::size_t i = 0; i < kPages * page; ++i) ASSERT_EQ(bytes[i], 0xab) << "byte " << i;
  ReleasePages(bytes + 6 * page, bytes + 7 * page);  // exactly page 6
  for (std::size_t i = 5 * page; i < kPages * page; ++i) {
    ASSERT_EQ(bytes[i], i / page == 6 ? 0 : 0xab) << "byte " << i;
  }
  ::munmap(map, kPages * page);
}

// The VmFlags of the mapping that starts at `start` in /proc/self/smaps ("" if none does).
std::string VmFlagsAt(const void* start) {
  std::ifstream smaps("/proc/self/smaps");
  std::ostringstream want;
  want << std::hex << reinterpret_cast<std::uintptr_t>(start) << "-";
  bool in = false;
  for (std::string line; std::getline(smaps, line);) {
    if (line.find('-') != std::string::npos && line.find(' ') > line.find('-') &&
        line.find(':') > line.find(' ')) {
      in = line.rfind(want.str(), 0) == 0;
    } else if (in && line.rfind("VmFlags:", 0) == 0) {
      return line;
    }
  }
  return "";
}

// The whole pages inside the range get their own mapping flagged "nh" (no huge pages); partial
// pages at its ends do not. Inaccessible pages on both sides keep the kernel from merging the
// test's mapping with a neighbour.
TEST(PreferSmallPages, MarksTheWholePagesInsideTheRange) {
  if (!std::ifstream("/sys/kernel/mm/transparent_hugepage/enabled")) {
    GTEST_SKIP() << "no transparent huge pages in this kernel: no advice to take";
  }
  const std::size_t page = static_cast<std::size_t>(::sysconf(_SC_PAGESIZE));
  constexpr std::size_t kPages = 8;
  void* map = ::mmap(nullptr, (kPages + 2) * page, PROT_READ | PROT_WRITE,
                     MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  ASSERT_NE(map, MAP_FAILED);
  auto* bytes = static_cast<std::uint8_t*>(map) + page;
  ASSERT_EQ(::mprotect(bytes - page, page, PROT_NONE), 0);
  ASSERT_EQ(::mprotect(bytes + kPages * page, page, PROT_NONE), 0);
  ASSERT_FALSE(VmFlagsAt(bytes).empty());  // the test's pages are a mapping of their own
  ASSERT_EQ(VmFlagsAt(bytes).find(" nh"), std::string::npos) << VmFlagsAt(bytes);
  EXPECT_TRUE(PreferSmallPages(bytes + 100, bytes + 5 * page + 10));  // whole pages 1–4
  EXPECT_EQ(VmFlagsAt(bytes).find(" nh"), std::string::npos) << VmFlagsAt(bytes);
  EXPECT_NE(VmFlagsAt(bytes + page).find(" nh"), std::string::npos) << VmFlagsAt(bytes + page);
  EXPECT_EQ(VmFlagsAt(bytes + 5 * page).find(" nh"), std::string::npos)
      << VmFlagsAt(bytes + 5 * page);
  EXPECT_FALSE(PreferSmallPages(bytes + page + 1, bytes + 2 * page + 5));  // no whole page
  ::munmap(map, (kPages + 2) * page);
}

}  // namespace
}  // namespace svokit
