#include "svokit/core/default_init.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <string>

namespace svokit {
namespace {

// Only the zero fill is skipped: values given are kept, class types are still constructed, and
// the vector behaves as a std::vector otherwise.
TEST(DefaultInitVector, KeepsGivenValuesAndConstructsClassTypes) {
  DefaultInitVector<std::uint64_t> filled(5, 7);
  EXPECT_EQ(filled, DefaultInitVector<std::uint64_t>({7, 7, 7, 7, 7}));
  filled.resize(8);  // the new three are unspecified; the first five stay
  filled[5] = filled[6] = filled[7] = 1;
  EXPECT_EQ(filled, DefaultInitVector<std::uint64_t>({7, 7, 7, 7, 7, 1, 1, 1}));
  filled.insert(filled.end(), {2, 3});
  EXPECT_EQ(filled.size(), 10u);
  EXPECT_EQ(filled.back(), 3u);

  DefaultInitVector<std::string> names(3);
  for (const std::string& s : names) EXPECT_TRUE(s.empty());
  names.emplace_back(4, 'x');
  EXPECT_EQ(names.back(), "xxxx");
  DefaultInitVector<std::string> copy = names;
  EXPECT_EQ(copy, names);
}

}  // namespace
}  // namespace svokit
