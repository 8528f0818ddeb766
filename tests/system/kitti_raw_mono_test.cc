// Real monocular start on KITTI raw drive 2011_09_26_drive_0005, grey camera image_00, frames 0-79 (30 m with a
// 37 deg left turn), synchronous pacing.

#include <gtest/gtest.h>

#include "support/test_support.h"
#include "system_test_util.h"

namespace semslam::system_test {
namespace {

constexpr char kDrive[] = "kitti_raw_2011_09_26_drive_0005/2011_09_26/2011_09_26_drive_0005_sync";

// Frames 0 and 2 pass the two-view test with the wrong motion (1.8 deg of rotation against 0.7 true, the camera
// travelling 50 deg right of its heading) and frame 3 fails it; a map started there is 1.74 m off (ATE). The map
// starts once two frames in a row pass.
TEST(KittiRawMono, GreyCameraStartsFromAMotionTheNextFrameRepeats) {
  SEMSLAM_REQUIRE_BINARY();
  SEMSLAM_REQUIRE_SHARED_DATA(drive, kDrive);
  testing::TempDir dir;
  const CommandResult r =
      RunSemslam({"run", "--sequence", drive.string(), "--camera", "image_00", "--mode", "mono", "--frames", "0:80",
                  "--pacing", "synchronous", "--out", (dir / "out").string(), "-q"});
  ASSERT_TRUE(r.Succeeded()) << r.Describe();
  const nlohmann::json run = ReadJson(dir / "out/run.json");
  ASSERT_TRUE(run.contains("ate_rmse")) << run.dump(2);
  EXPECT_EQ(run.value("with_pose", 0), 80);
  EXPECT_EQ(run.value("ate_matched", 0), 80);
  // Within 5 % of the reproducible value, 0.3356 m (colour camera image_02, same drive: 0.31 m).
  EXPECT_LE(run["ate_rmse"].get<double>(), 0.352);
}

}  // namespace
}  // namespace semslam::system_test
