// The render options' command-line spelling: views, shadings and sizes read, bad text refused.

#include "svokit/inspect/render_options.hpp"

#include <gtest/gtest.h>

#include <array>

namespace svokit {
namespace {

TEST(Render, OptionsAreParsedAndCheckedAsBadInput) {
  EXPECT_EQ(ParseView("iso").value(), View::kIso);
  EXPECT_EQ(ParseView("bottom").value(), View::kBottom);
  EXPECT_EQ(ParseView("side").status().code(), StatusCode::kBadInput);
  EXPECT_EQ(ParseShade("normal").value(), Shade::kNormal);
  EXPECT_EQ(ParseShade("phong").status().code(), StatusCode::kBadInput);
  EXPECT_EQ(ParseImageSize("640x480").value(), (std::array<int, 2>{640, 480}));
  for (const char* bad : {"0x0", "10x0", "x10", "10x", "10", "10x10x", "-5x5", "20000x10", ""}) {
    EXPECT_EQ(ParseImageSize(bad).status().code(), StatusCode::kBadInput) << bad;
  }
}

}  // namespace
}  // namespace svokit
