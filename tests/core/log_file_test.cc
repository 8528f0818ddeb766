// run.log (core/log_file.h): every message is in the file as soon as it is logged, not when the run ends.

#include "semslam/core/log_file.h"

#include <gtest/gtest.h>
#include <spdlog/spdlog.h>

#include <string>

#include "support/test_support.h"

namespace semslam {
namespace {

TEST(LogFile, EachMessageIsInTheFileWhileTheLogIsOpen) {
  testing::TempDir dir;
  const auto path = dir / "run.log";
  const auto flush_level = spdlog::default_logger()->flush_level();
  {
    const LogFile log(path, {"semslam test"});
    spdlog::info("frame 17 tracked");
    // Read before the log closes, as after a kill.
    const std::string text = testing::ReadText(path);
    EXPECT_NE(text.find("semslam test"), std::string::npos) << text;
    EXPECT_NE(text.find("[info] frame 17 tracked"), std::string::npos) << text;
  }
  EXPECT_EQ(spdlog::default_logger()->flush_level(), flush_level) << "the logger is left as it was";
  spdlog::info("after the log closed");
  EXPECT_EQ(testing::ReadText(path).find("after the log closed"), std::string::npos);
}

}  // namespace
}  // namespace semslam
