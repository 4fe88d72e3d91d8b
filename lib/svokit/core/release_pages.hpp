#pragma once
// Giving memory back as it is consumed. On VMs a fresh page costs far more on first touch than a
// page just freed: the host backs the first lazily, the second is still backed. Arrays released
// piece by piece while they are written out let the file's page cache take their pages, so
// writing a large file touches no fresh memory.

#include <sys/mman.h>
#include <unistd.h>

#include <cstdint>
#include <utility>

namespace svokit {

namespace release_pages_detail {

// The whole pages inside [begin, end), as [lo, hi) (empty when lo >= hi).
inline std::pair<std::uintptr_t, std::uintptr_t> WholePages(const void* begin, const void* end) {
  static const std::uintptr_t page = static_cast<std::uintptr_t>(::sysconf(_SC_PAGESIZE));
  return {(reinterpret_cast<std::uintptr_t>(begin) + page - 1) / page * page,
          reinterpret_cast<std::uintptr_t>(end) / page * page};
}

}  // namespace release_pages_detail

/// Returns the whole pages inside [begin, end) to the kernel (their contents read as zero
/// afterwards): for memory that is no longer read. Partial pages at either end are kept, so the
/// allocator's own bookkeeping next to the range is never touched.
inline void ReleasePages(const void* begin, const void* end) {
  const auto [lo, hi] = release_pages_detail::WholePages(begin, end);
  if (lo < hi) ::madvise(reinterpret_cast<void*>(lo), hi - lo, MADV_DONTNEED);
}

/// Drops the pages of a read-only file mapping that overlap [begin, end) from the process: touched
/// again, they are read back from the file (the page cache), so even pages shared with neighbouring
/// ranges may go.
inline void ReleaseMappedFilePages(const void* begin, const void* end) {
  // WholePages of the swapped range is {end rounded up, begin rounded down}: the pages overlapped.
  const auto [up, down] = release_pages_detail::WholePages(end, begin);
  if (down < up) ::madvise(reinterpret_cast<void*>(down), up - down, MADV_DONTNEED);
}

/// Asks for small pages over the whole pages inside [begin, end), not yet touched: on VMs a fresh
/// 2 MB page is usually one the host has never backed, while small pages come from the ones just
/// freed. For memory of its own mapping only (the advice stays with the pages). Returns whether
/// the kernel took it (not without transparent huge pages).
inline bool PreferSmallPages(const void* begin, const void* end) {
  const auto [lo, hi] = release_pages_detail::WholePages(begin, end);
  return lo < hi && ::madvise(reinterpret_cast<void*>(lo), hi - lo, MADV_NOHUGEPAGE) == 0;
}

}  // namespace svokit
