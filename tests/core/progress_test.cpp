#include "svokit/core/progress.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <string>
#include <thread>

namespace svokit {
namespace {

std::string Capture(Progress::Style style) {
  char* buf = nullptr;
  std::size_t size = 0;
  std::FILE* out = open_memstream(&buf, &size);
  {
    Progress progress(style, out);
    Progress::Stage stage(progress, "voxelize", 10);
    for (int i = 0; i < 10; ++i) stage.Advance();
    stage.SetSummary("42 voxels");
  }
  std::fclose(out);
  std::string s(buf, size);
  std::free(buf);
  return s;
}

TEST(Progress, QuietPrintsNothing) {
  EXPECT_EQ(Capture(Progress::Style::kQuiet), "");
}

TEST(Progress, LinesPrintOneLinePerStage) {
  const std::string s = Capture(Progress::Style::kLines);
  EXPECT_EQ(std::count(s.begin(), s.end(), '\n'), 1);
  EXPECT_EQ(s.rfind("voxelize", 0), 0u);
  EXPECT_NE(s.find("42 voxels"), std::string::npos);
  EXPECT_EQ(s.find('\r'), std::string::npos);
}

TEST(Progress, BarRedrawsInPlaceAndEndsWithNewline) {
  const std::string s = Capture(Progress::Style::kBar);
  EXPECT_NE(s.find('\r'), std::string::npos);
  EXPECT_NE(s.find("100%"), std::string::npos);
  EXPECT_EQ(s.back(), '\n');
}

// While a stage runs, the bar shows the units done of all, the bytes written and what is left.
TEST(Progress, ARunningBarShowsCountsBytesAndEta) {
  char* buf = nullptr;
  std::size_t size = 0;
  std::FILE* out = open_memstream(&buf, &size);
  {
    Progress progress(Progress::Style::kBar, out);
    Progress::Stage stage(progress, "pages", 4);
    stage.Advance();
    stage.AddBytes(2500000);
    std::this_thread::sleep_for(std::chrono::milliseconds(150));
    stage.Advance();  // redraws: 100 ms have passed
  }
  std::fclose(out);
  const std::string s(buf, size);
  std::free(buf);
  EXPECT_NE(s.find("50% "), std::string::npos) << s;
  EXPECT_NE(s.find("2/4"), std::string::npos) << s;
  EXPECT_NE(s.find("2.5 MB written"), std::string::npos) << s;
  EXPECT_NE(s.find("ETA "), std::string::npos) << s;
  EXPECT_NE(s.find("100%"), std::string::npos) << s;
}

TEST(Progress, AutoOnAPipeIsLines) {
  std::FILE* pipe = ::popen("cat > /dev/null", "w");
  ASSERT_NE(pipe, nullptr);
  Progress progress(Progress::Style::kAuto, pipe);
  EXPECT_EQ(progress.style(), Progress::Style::kLines);
  ::pclose(pipe);
}

}  // namespace
}  // namespace svokit
