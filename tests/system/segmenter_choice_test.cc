// `--segmenter auto` on a real drive: the colour camera gets SINet, the grey one ESPNetv2 (SINet reads grey trees
// as persons), each named in run.json. Five frames of KITTI raw drive 0005 each.

#include <gtest/gtest.h>

#include <cstdlib>
#include <optional>
#include <string>

#include "support/test_support.h"
#include "system_test_util.h"

namespace semslam::system_test {
namespace {

constexpr const char* kDrive = "kitti_raw_2011_09_26_drive_0005/2011_09_26/2011_09_26_drive_0005_sync";

std::string SegmenterOf(const fs::path& drive, const fs::path& weights, const fs::path& out,
                        const std::string& camera) {
  const CommandResult r = RunSemslam({"run", "--sequence", drive.string(), "--camera", camera, "--frames", "0:5",
                                      "--mode", "mono", "--pacing", "synchronous", "--segmenter",
                                      "auto:" + weights.string(), "--out", out.string(), "-q"});
  EXPECT_TRUE(r.Succeeded()) << r.Describe();
  const nlohmann::json run = ReadJson(out / "run.json");
  return run.is_object() ? run["segmentation"].value("segmenter", "") : "";
}

TEST(SegmenterChoice, AutoTakesSiNetForTheColourCameraAndEspNetV2ForTheGreyOne) {
  SEMSLAM_REQUIRE_BINARY();
  SEMSLAM_REQUIRE_SHARED_DATA(drive, kDrive);
  SEMSLAM_REQUIRE_SHARED_DATA(weights, "segmentation_weights");
  testing::TempDir dir;
  const std::string colour = SegmenterOf(drive, weights, dir / "colour", "image_02");
  const std::string grey = SegmenterOf(drive, weights, dir / "grey", "image_00");
  EXPECT_NE(colour.find("sinet"), std::string::npos) << colour;
  EXPECT_NE(grey.find("espnetv2"), std::string::npos) << grey;
  EXPECT_NE(grey.find("width 768"), std::string::npos) << grey;
}

// Run from another folder with SEMSLAM_SHARED_DATA unset, a build-tree binary finds the weights beside its
// checkout (where they were taken relative to the working directory only, the run stopped at once).
TEST(SegmenterChoice, AutoFindsItsWeightsWhenRunFromAnotherFolder) {
  SEMSLAM_REQUIRE_BINARY();
  SEMSLAM_REQUIRE_SHARED_DATA(image, "cityscapes_samples/frankfurt_000000_000294_leftImg8bit.png");
  SEMSLAM_REQUIRE_SHARED_DATA(weights, "segmentation_weights");
  const fs::path beside_checkout =
      testing::SemslamBinary().parent_path() / "../../../../shared/data/segmentation_weights";
  if (!fs::exists(beside_checkout) || !fs::equivalent(beside_checkout, weights)) {
    GTEST_SKIP() << "the binary is not a build-tree one beside the data: " << testing::SemslamBinary();
  }
  testing::TempDir dir;
  const fs::path image_path = fs::absolute(image), cwd = fs::current_path();
  const char* shared = std::getenv("SEMSLAM_SHARED_DATA");
  const std::optional<std::string> saved = shared ? std::optional<std::string>(shared) : std::nullopt;
  unsetenv("SEMSLAM_SHARED_DATA");
  fs::current_path(dir.path());
  const CommandResult r = RunSemslam({"segment", "--segmenter", "auto", "--images", image_path.string()});
  fs::current_path(cwd);
  if (saved) setenv("SEMSLAM_SHARED_DATA", saved->c_str(), 1);
  ASSERT_TRUE(r.Succeeded()) << r.Describe();
  EXPECT_NE(r.out.find("sinet"), std::string::npos) << r.out;
}

}  // namespace
}  // namespace semslam::system_test
