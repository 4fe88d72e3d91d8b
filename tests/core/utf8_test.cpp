#include "svokit/core/utf8.hpp"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

namespace svokit {
namespace {

TEST(EscapeInvalidUtf8, ValidTextIsUnchanged) {
  for (const std::string s : {"", "plain.obj", "dir/Café.obj", "模型.ply", "\xF0\x9F\x90\x87.stl",
                              "back\\slash \\xFF literal"}) {
    EXPECT_EQ(EscapeInvalidUtf8(s), s);
  }
}

TEST(EscapeInvalidUtf8, InvalidBytesBecomeHexEscapesAndTheResultIsJsonSafe) {
  EXPECT_EQ(EscapeInvalidUtf8("\xFF.obj"), "\\xFF.obj");
  EXPECT_EQ(EscapeInvalidUtf8("a\xC3"), "a\\xC3");                           // truncated sequence
  EXPECT_EQ(EscapeInvalidUtf8("\xC0\xAF"), "\\xC0\\xAF");                    // overlong '/'
  EXPECT_EQ(EscapeInvalidUtf8("\xED\xA0\x80"), "\\xED\\xA0\\x80");           // surrogate
  EXPECT_EQ(EscapeInvalidUtf8("\xF4\x90\x80\x80"), "\\xF4\\x90\\x80\\x80");  // above U+10FFFF
  EXPECT_EQ(EscapeInvalidUtf8("\xE9t\xC3\xA9"), "\\xE9t\xC3\xA9");           // Latin-1 then UTF-8
  for (int b = 0; b < 256; ++b) {
    std::string s = "x";
    s += static_cast<char>(b);
    s += "\x80y";
    EXPECT_NO_THROW((void)nlohmann::json(EscapeInvalidUtf8(s)).dump()) << b;
  }
}

}  // namespace
}  // namespace svokit
