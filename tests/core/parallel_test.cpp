#include "svokit/core/parallel.hpp"
#include "svokit/core/thread_limit.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <memory>
#include <mutex>
#include <set>
#include <stdexcept>
#include <thread>
#include <vector>

namespace svokit {
namespace {

// A float sum whose value depends on the order of additions: the reduction must not.
double SumOfTerms(std::size_t threads) {
  ThreadLimit limit(threads);
  return OrderedReduce(
      1000003, 4096, 0.0,
      [](std::size_t b, std::size_t e) {
        double s = 0;
        for (std::size_t i = b; i < e; ++i) s += 1.0 / (1.0 + static_cast<double>(i % 977)) * 1e-3;
        return s;
      },
      [](double& acc, double part) { acc += part; });
}

TEST(OrderedReduce, BitIdenticalForAnyThreadCount) {
  const double one = SumOfTerms(1);
  EXPECT_EQ(SumOfTerms(2), one);
  EXPECT_EQ(SumOfTerms(4), one);
  EXPECT_EQ(SumOfTerms(0), one);
  EXPECT_GT(one, 0.0);
}

TEST(ParallelChunks, CoversEveryIndexOnce) {
  std::vector<std::atomic<int>> hits(100001);
  ParallelChunks(hits.size(), 999, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) hits[i]++;
  });
  for (const auto& h : hits) ASSERT_EQ(h.load(), 1);
  int calls = 0;
  ParallelChunks(0, 10, [&](std::size_t, std::size_t) { ++calls; });
  EXPECT_EQ(calls, 0);
}

TEST(ParallelChunks, NestedRunsFinish) {
  std::atomic<int> inner{0};
  ParallelChunks(64, 1, [&](std::size_t, std::size_t) {
    ParallelChunks(100, 7, [&](std::size_t b, std::size_t e) { inner += static_cast<int>(e - b); });
  });
  EXPECT_EQ(inner.load(), 64 * 100);
}

TEST(ParallelChunks, ATaskExceptionReachesTheCaller) {
  for (const std::size_t threads : {1, 2, 4}) {
    PoolThreadLimit limit(threads);
    std::atomic<int> ran{0};
    EXPECT_THROW(ParallelChunks(1000, 1,
                                [&](std::size_t b, std::size_t) {
                                  ++ran;
                                  if (b == 500) throw std::runtime_error("task 500");
                                }),
                 std::runtime_error);
    EXPECT_GT(ran.load(), 0);
    // The pool is whole again afterwards.
    EXPECT_EQ(OrderedReduce(
                  100, 3, 0, [](std::size_t b, std::size_t e) { return static_cast<int>(e - b); },
                  [](int& acc, int part) { acc += part; }),
              100);
  }
}

TEST(PoolThreadLimit, OneThreadRunsEverythingOnTheCaller) {
  PoolThreadLimit limit(1);
  EXPECT_EQ(Concurrency(), 1u);
  EXPECT_EQ(MostInFlight(), 2u);
  std::mutex m;
  std::set<std::thread::id> ids;
  ParallelChunks(1000, 1, [&](std::size_t, std::size_t) {
    const std::lock_guard lock(m);
    ids.insert(std::this_thread::get_id());
  });
  EXPECT_EQ(ids, std::set<std::thread::id>{std::this_thread::get_id()});
  {
    PoolThreadLimit looser(3);  // the most restrictive limit alive wins
    EXPECT_EQ(Concurrency(), 1u);
  }
}

// Items made in parallel are taken in order, never more than `in_flight` at a time, and the run
// stops at the first error take returns.
TEST(ParallelInOrder, TakesInOrderWithinTheBound) {
  for (const std::size_t threads : {1, 2, 4}) {
    PoolThreadLimit limit(threads);
    for (const std::size_t in_flight : {1, 3, 16}) {
      std::atomic<int> alive{0}, most{0};
      struct Item {
        std::size_t i = 0;
        std::atomic<int>* alive = nullptr;
      };
      std::vector<std::size_t> taken;
      const Status status = ParallelInOrder<std::shared_ptr<Item>>(
          5, 205, in_flight,
          [&](std::size_t i) {
            const int now = ++alive;
            for (int m = most.load(); now > m && !most.compare_exchange_weak(m, now);) {
            }
            return std::shared_ptr<Item>(new Item{i, &alive}, [](Item* item) {
              --*item->alive;
              delete item;
            });
          },
          [&](std::shared_ptr<Item> item) {
            taken.push_back(item->i);
            return Status();
          });
      ASSERT_TRUE(status.ok());
      ASSERT_EQ(taken.size(), 200u);
      for (std::size_t k = 0; k < taken.size(); ++k) ASSERT_EQ(taken[k], k + 5);
      EXPECT_LE(most.load(), static_cast<int>(in_flight));
      EXPECT_EQ(alive.load(), 0);
    }
    std::vector<std::size_t> taken;
    const Status failed = ParallelInOrder<std::size_t>(
        0, 1000, 8, [](std::size_t i) { return i; },
        [&](std::size_t i) {
          taken.push_back(i);
          return i == 17 ? Status::BadInput("item {}", i) : Status();
        });
    EXPECT_EQ(failed.message(), "item 17");
    EXPECT_EQ(taken.size(), 18u);
  }
}

}  // namespace
}  // namespace svokit
