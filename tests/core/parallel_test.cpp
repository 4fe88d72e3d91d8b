#include "svokit/core/parallel.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
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

}  // namespace
}  // namespace svokit
