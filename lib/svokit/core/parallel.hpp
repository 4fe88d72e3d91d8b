#pragma once
// Parallel helpers on TBB. Work is split into chunks whose boundaries depend only on the problem
// size, never on the thread count, and results are combined in chunk order: deterministic output.

#include <algorithm>
#include <cstddef>
#include <memory>
#include <string_view>
#include <vector>

#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_pipeline.h>
#include <tbb/task_arena.h>

#include "svokit/core/status.hpp"

namespace svokit {

/// Limits TBB to `threads` worker threads for this object's lifetime (0 = all cores).
class ThreadLimit {
 public:
  explicit ThreadLimit(std::size_t threads) {
    if (threads > 0) {
      control_ = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                       threads);
    }
  }

 private:
  std::unique_ptr<tbb::global_control> control_;
};

/// Calls body(begin, end) on fixed chunks of [0, n) in parallel.
template <class Body>
void ParallelChunks(std::size_t n, std::size_t chunk, const Body& body) {
  chunk = std::max<std::size_t>(chunk, 1);
  const std::size_t chunks = (n + chunk - 1) / chunk;
  tbb::parallel_for(std::size_t{0}, chunks,
                    [&](std::size_t c) { body(c * chunk, std::min(n, (c + 1) * chunk)); });
}

/// Deterministic reduction: map(begin, end) → T per fixed chunk in parallel, then
/// combine(acc, part) left to right in chunk order.
template <class T, class Map, class Combine>
T OrderedReduce(std::size_t n, std::size_t chunk, T init, const Map& map, const Combine& combine) {
  chunk = std::max<std::size_t>(chunk, 1);
  const std::size_t chunks = (n + chunk - 1) / chunk;
  std::vector<T> parts(chunks, init);
  tbb::parallel_for(std::size_t{0}, chunks, [&](std::size_t c) {
    parts[c] = map(c * chunk, std::min(n, (c + 1) * chunk));
  });
  for (auto& p : parts) combine(init, p);
  return init;
}

/// The most items a streaming run (ParallelInOrder) keeps in flight: twice the worker threads,
/// so every thread has the next one while the slowest is handed on.
inline std::size_t MostInFlight() {
  return 2 * static_cast<std::size_t>(tbb::this_task_arena::max_concurrency());
}

/// How many items of `item` bytes a streaming run (ParallelInOrder) may have in flight within
/// `limit` bytes (0: no limit), besides `fixed` bytes it holds throughout: as many as fit, at most
/// MostInFlight(). A limit below fixed + `least` (what the run needs at its peak, at
/// least one item) is an error naming the smallest limit that works; `needs` says what needs it
/// ("its bins and one page").
inline StatusOr<std::size_t> InFlightWithin(std::uint64_t limit, std::uint64_t fixed,
                                            std::uint64_t item, std::uint64_t least,
                                            std::string_view needs) {
  const std::size_t most = MostInFlight();
  if (limit == 0) return most;
  if (limit < fixed + least) {
    const std::uint64_t mib = (fixed + least + (1 << 20) - 1) >> 20;
    return Status::BadInput(
        "a memory limit of {} MiB is too small for this mesh and grid: {} need {} MiB (give "
        "{}M or more)",
        limit >> 20, needs, mib, mib);
  }
  return std::clamp<std::size_t>((limit - fixed) / item, 1, most);
}

/// Items [first, end) made by make(i) → Made in parallel, at most `in_flight` at a time, and handed
/// to take(Made) → Status in order; stops at take's first error and returns it. What streams a
/// file out of parts made in parallel within a memory bound.
template <class Made, class MakeFn, class TakeFn>
Status ParallelInOrder(std::size_t first, std::size_t end, std::size_t in_flight,
                       const MakeFn& make, const TakeFn& take) {
  Status failed;
  std::size_t next = first;
  tbb::parallel_pipeline(
      std::max<std::size_t>(in_flight, 1),
      tbb::make_filter<void, std::size_t>(tbb::filter_mode::serial_in_order,
                                          [&](tbb::flow_control& fc) -> std::size_t {
                                            if (next == end || !failed.ok()) fc.stop();
                                            return next++;
                                          }) &
          tbb::make_filter<std::size_t, Made>(tbb::filter_mode::parallel, make) &
          tbb::make_filter<Made, void>(tbb::filter_mode::serial_in_order, [&](Made made) {
            if (failed.ok()) failed = take(std::move(made));
          }));
  return failed;
}

}  // namespace svokit
