#pragma once
// Parallel helpers on svokit's own thread pool (parallel.cpp), which needs nothing but the standard
// library: the reader library runs on it without TBB. Work is split into chunks whose boundaries
// depend only on the problem size, never on the thread count, and results are combined in chunk
// order: deterministic output. ThreadLimit (thread_limit.hpp) limits this pool and TBB together.

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string_view>
#include <utility>
#include <vector>

#include "svokit/core/status.hpp"

namespace svokit {

namespace parallel_detail {

/// A callable by reference, for the type-erased entry points below: one body of pool code serves
/// every caller's lambda, and none of it is compiled into the caller.
template <class Signature>
class FunctionRef;
template <class R, class... Args>
class FunctionRef<R(Args...)> {
 public:
  template <class F>
  FunctionRef(const F& f)  // NOLINT: implicit, as a lambda is passed
      : object_(&f), call_([](const void* o, Args... args) -> R {
          return (*static_cast<const F*>(o))(std::forward<Args>(args)...);
        }) {}
  R operator()(Args... args) const { return call_(object_, std::forward<Args>(args)...); }

 private:
  const void* object_;
  R (*call_)(const void*, Args...);
};

/// Runs task(i) for every i in [0, count) on the pool's threads and the caller's; returns when
/// all have, rethrowing the first exception a task threw.
void RunTasks(std::size_t count, FunctionRef<void(std::size_t)> task);

/// ParallelInOrder's engine: make(i, slot) for items [first, end) in parallel, item i into slot
/// i % slots, at most `slots` made and not yet taken; take(slot) in item order on the caller's
/// thread, stopping at its first error.
Status RunInOrder(std::size_t first, std::size_t end, std::size_t slots,
                  FunctionRef<void(std::size_t, std::size_t)> make,
                  FunctionRef<Status(std::size_t)> take);

}  // namespace parallel_detail

/// The threads a parallel run may use, the caller's included: the cores this process may run on,
/// within the most restrictive PoolThreadLimit alive.
std::size_t Concurrency();

/// Limits the pool to `threads` threads, the caller's included, for this object's lifetime (0 =
/// all cores); the most restrictive limit alive wins. ThreadLimit limits TBB as well.
class PoolThreadLimit {
 public:
  explicit PoolThreadLimit(std::size_t threads);
  ~PoolThreadLimit();
  PoolThreadLimit(const PoolThreadLimit&) = delete;
  PoolThreadLimit& operator=(const PoolThreadLimit&) = delete;

 private:
  std::size_t threads_;
};

/// Calls body(begin, end) on fixed chunks of [0, n) in parallel.
template <class Body>
void ParallelChunks(std::size_t n, std::size_t chunk, const Body& body) {
  chunk = std::max<std::size_t>(chunk, 1);
  const std::size_t chunks = (n + chunk - 1) / chunk;
  parallel_detail::RunTasks(chunks,
                            [&](std::size_t c) { body(c * chunk, std::min(n, (c + 1) * chunk)); });
}

/// Deterministic reduction: map(begin, end) → T per fixed chunk in parallel, then
/// combine(acc, part) left to right in chunk order.
template <class T, class Map, class Combine>
T OrderedReduce(std::size_t n, std::size_t chunk, T init, const Map& map, const Combine& combine) {
  chunk = std::max<std::size_t>(chunk, 1);
  const std::size_t chunks = (n + chunk - 1) / chunk;
  std::vector<T> parts(chunks, init);
  parallel_detail::RunTasks(
      chunks, [&](std::size_t c) { parts[c] = map(c * chunk, std::min(n, (c + 1) * chunk)); });
  for (auto& p : parts) combine(init, p);
  return init;
}

/// The most items a streaming run (ParallelInOrder) keeps in flight: twice the threads, so every
/// thread has the next one while the slowest is handed on.
inline std::size_t MostInFlight() {
  return 2 * Concurrency();
}

/// How many items of `item` bytes a streaming run (ParallelInOrder) may have in flight within
/// `limit` bytes (0: no limit), besides `fixed` bytes it holds throughout: as many as fit, at most
/// MostInFlight(). A limit below fixed + `least` (what the run needs at its peak, at
/// least one item) is an error naming the smallest limit that works; `input` says what the run
/// works through ("this mesh and grid"), `needs` what needs it ("its bins and one page").
inline StatusOr<std::size_t> InFlightWithin(std::uint64_t limit, std::uint64_t fixed,
                                            std::uint64_t item, std::uint64_t least,
                                            std::string_view input, std::string_view needs) {
  const std::size_t most = MostInFlight();
  if (limit == 0) return most;
  if (limit < fixed + least) {
    const std::uint64_t mib = (fixed + least + (1 << 20) - 1) >> 20;
    return Status::BadInput(
        "a memory limit of {} MiB is too small for {}: {} need {} MiB (give {}M or more)",
        limit >> 20, input, needs, mib, mib);
  }
  return std::clamp<std::size_t>((limit - fixed) / item, 1, most);
}

/// Items [first, end) made by make(i) → Made in parallel, at most `in_flight` at a time, and handed
/// to take(Made) → Status in order; stops at take's first error and returns it. What streams a
/// file out of parts made in parallel within a memory bound.
template <class Made, class MakeFn, class TakeFn>
Status ParallelInOrder(std::size_t first, std::size_t end, std::size_t in_flight,
                       const MakeFn& make, const TakeFn& take) {
  if (end <= first) return {};
  std::vector<std::optional<Made>> slots(std::clamp<std::size_t>(in_flight, 1, end - first));
  return parallel_detail::RunInOrder(
      first, end, slots.size(), [&](std::size_t i, std::size_t s) { slots[s].emplace(make(i)); },
      [&](std::size_t s) {
        Status taken = take(std::move(*slots[s]));
        slots[s].reset();
        return taken;
      });
}

}  // namespace svokit
