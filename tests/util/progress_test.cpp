#include "neraf/util/progress.h"

#include <gtest/gtest.h>

#include <limits>

#include "neraf/util/error.h"

namespace neraf {
namespace {

TEST(FormatDuration, SecondsMinutesHours) {
  EXPECT_EQ(format_duration(0.0), "0.0s");
  EXPECT_EQ(format_duration(12.34), "12.3s");
  EXPECT_EQ(format_duration(65.0), "1:05");
  EXPECT_EQ(format_duration(3723.0), "1:02:03");
}

TEST(FormatDuration, UnknownForNegativeOrInfinite) {
  EXPECT_EQ(format_duration(-1.0), "?");
  EXPECT_EQ(format_duration(std::numeric_limits<double>::infinity()), "?");
}

TEST(Progress, SilentWhenDisabledAndClampsDone) {
  ProgressOptions options;
  options.enabled = false;
  Progress progress("work", 10, options);
  testing::internal::CaptureStderr();
  progress.update(25, "beyond the end");
  progress.finish();
  EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
}

TEST(Progress, FinalLineReportsTotalAndStatus) {
  testing::internal::CaptureStderr();
  {
    Progress progress("synth", 4);
    progress.update(2);
    progress.finish("done");
  }
  const std::string out = testing::internal::GetCapturedStderr();
  EXPECT_NE(out.find("synth"), std::string::npos);
  EXPECT_NE(out.find("4/4"), std::string::npos);
  EXPECT_NE(out.find("done"), std::string::npos);
}

TEST(Require, ThrowsErrorWithMessage) {
  EXPECT_NO_THROW(require(true, "unused"));
  try {
    require(false, "file.wav: broken; fix it");
    FAIL() << "require(false) did not throw";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "file.wav: broken; fix it");
  }
}

}  // namespace
}  // namespace neraf
