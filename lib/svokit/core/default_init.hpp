#pragma once
// An allocator for vectors whose elements are written right after they are sized: resize() and
// the size constructor leave trivially constructible elements uninitialized instead of zeroing
// them. On VMs the first touch of fresh pages is the cost of a big array, and a zero fill makes
// it serial; the parallel writes that follow then touch the pages instead.

#include <cstdint>
#include <memory>
#include <new>
#include <utility>
#include <vector>

namespace svokit {

template <class T>
struct DefaultInitAllocator : std::allocator<T> {
  using value_type = T;
  template <class U>
  struct rebind {
    using other = DefaultInitAllocator<U>;
  };
  DefaultInitAllocator() = default;
  template <class U>
  DefaultInitAllocator(const DefaultInitAllocator<U>&) noexcept {}

  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    if constexpr (sizeof...(Args) == 0) {
      ::new (static_cast<void*>(p)) U;  // default-initialized: no write for trivial types
    } else {
      ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
    }
  }
};

/// A std::vector whose resize() leaves new elements of trivial types uninitialized.
template <class T>
using DefaultInitVector = std::vector<T, DefaultInitAllocator<T>>;

}  // namespace svokit

// Compiled once, optimized, in the library (default_init.cpp; half.hpp and octahedral.hpp do the
// same for theirs): a program built without optimization would otherwise free and size the
// reader's arrays with unoptimized copies that call a function per element.
extern template class std::vector<std::uint8_t, svokit::DefaultInitAllocator<std::uint8_t>>;
extern template class std::vector<std::uint16_t, svokit::DefaultInitAllocator<std::uint16_t>>;
extern template class std::vector<std::uint32_t, svokit::DefaultInitAllocator<std::uint32_t>>;
extern template class std::vector<std::uint64_t, svokit::DefaultInitAllocator<std::uint64_t>>;
