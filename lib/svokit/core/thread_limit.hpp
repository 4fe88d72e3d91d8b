#pragma once
// The thread limit of the whole library: svokit's pool (parallel.hpp) and TBB, which the build
// stages use beside it. Needs TBB, so it is for svokit::svokit's users; the reader library's is
// PoolThreadLimit.

#include <cstddef>
#include <memory>

#include <tbb/global_control.h>

#include "svokit/core/parallel.hpp"

namespace svokit {

/// Limits the pool and TBB to `threads` threads for this object's lifetime (0 = all cores).
class ThreadLimit {
 public:
  explicit ThreadLimit(std::size_t threads) : pool_(threads) {
    if (threads > 0) {
      control_ = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                       threads);
    }
  }

 private:
  PoolThreadLimit pool_;
  std::unique_ptr<tbb::global_control> control_;
};

}  // namespace svokit
