// The CLI's progress bar: drawn only when enabled and after its delay,
// monotone, ending at 100% on a line of its own.
#include "client/common/progress_bar.h"

#include <cstdio>
#include <string>

#include <gtest/gtest.h>

namespace vpm::cli {
namespace {

std::string Contents(std::FILE* f) {
  std::fflush(f);
  std::rewind(f);
  std::string out;
  char buffer[256];
  while (size_t n = std::fread(buffer, 1, sizeof(buffer), f)) out.append(buffer, n);
  return out;
}

TEST(ProgressBar, DrawsMonotoneBarEndingAtHundredPercent) {
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  {
    ProgressBar bar("loading x.nii", true, f, std::chrono::milliseconds(0));
    const ProgressFn report = bar.Reporter();
    report(0.5, "reading");
    report(0.25, "reading");  // never goes back
    EXPECT_EQ(bar.fraction(), 0.5);
    report(1.0, "done");
    bar.Finish();
  }
  const std::string out = Contents(f);
  std::fclose(f);
  EXPECT_NE(out.find("loading x.nii ["), std::string::npos) << out;
  EXPECT_NE(out.find(" 50%"), std::string::npos) << out;
  EXPECT_EQ(out.find(" 25%"), std::string::npos) << out;
  EXPECT_NE(out.find("100%"), std::string::npos) << out;
  EXPECT_EQ(out.back(), '\n');
}

TEST(ProgressBar, QuietWhenDisabledOrQuick) {
  for (bool enabled : {false, true}) {
    std::FILE* f = std::tmpfile();
    ASSERT_NE(f, nullptr);
    {
      // Enabled, but the work ends within the (one-hour) delay: nothing.
      ProgressBar bar("x", enabled, f, std::chrono::hours(1));
      bar.Update(0.5, "reading");
      bar.Update(1.0, "done");
    }
    EXPECT_EQ(Contents(f), "") << enabled;
    std::fclose(f);
  }
}

TEST(ProgressBar, AFailedLoadEndsItsLineShortOfHundred) {
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  {
    ProgressBar bar("loading y", true, f, std::chrono::milliseconds(0));
    bar.Update(0.4, "reading");
  }  // destroyed without reaching 1: the line is ended where it stopped
  const std::string out = Contents(f);
  std::fclose(f);
  EXPECT_NE(out.find(" 40%"), std::string::npos) << out;
  EXPECT_EQ(out.find("100%"), std::string::npos) << out;
  EXPECT_EQ(out.back(), '\n');
}

}  // namespace
}  // namespace vpm::cli
