// `semslam run --camera`: the colour pair image_2/image_3 of a KITTI odometry folder made from the synthetic
// city (tinted blue), run in stereo with the tiny test network of tests/semantics (red -> road, green -> car,
// blue -> sky). Tracking sees grey and tracks; the segmenter sees colour, so the map's points come out 'sky',
// where the grey camera's come out 'road' (a grey pixel scores road, car and sky alike, and road comes
// first).

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "semslam/io/kitti_odometry.h"
#include "semslam/io/sequence.h"
#include "support/test_support.h"
#include "system_test_util.h"

namespace semslam::system_test {
namespace {

constexpr int kFrames = 30;

// dataset/sequences/00 with image_2/image_3 added: the left and right images tinted (B = g, G = R = 0.6 g).
void AddColorPair(const fs::path& source, const fs::path& target) {
  fs::create_directories(target);
  for (const char* name : {"calib.txt", "times.txt"}) fs::copy_file(source / name, target / name);
  for (const auto& [from, to] : {std::pair{"image_0", "image_2"}, std::pair{"image_1", "image_3"}}) {
    fs::create_directories(target / from);
    fs::create_directories(target / to);
    for (int i = 0; i < kFrames; ++i) {
      const std::string file = fmt::format("{:06d}.png", i);
      const cv::Mat grey = ReadGreyImage(source / from / file);
      cv::Mat scaled;
      grey.convertTo(scaled, CV_8U, 0.6);
      cv::Mat color;
      cv::merge(std::vector<cv::Mat>{grey, scaled, scaled}, color);
      fs::copy_file(source / from / file, target / from / file);
      WritePng(target / to / file, color);
    }
  }
}

nlohmann::json RunCamera(const fs::path& sequence, const fs::path& out, const std::string& camera) {
  const CommandResult r =
      RunSemslam({"run", "--sequence", sequence.string(), "--camera", camera, "--out", out.string(), "--mode",
                  "stereo", "--pacing", "synchronous", "--segmenter",
                  "onnx:" SEMSLAM_SEMANTICS_TEST_DATA "/tiny_segnet.yaml", "-q"});
  EXPECT_TRUE(r.Succeeded()) << r.Describe();
  return ReadJson(out / "run.json");
}

TEST(CameraChoice, ColourPairTracksInGreyAndSegmentsInColour) {
  SEMSLAM_REQUIRE_BINARY();
  SEMSLAM_ASSERT_ARTIFACT(dataset, SyntheticDataset());
  testing::TempDir dir;
  const fs::path sequence = dir / "sequences/00";
  AddColorPair(SequenceDir(dataset), sequence);
  ASSERT_TRUE(OpenSequence(sequence, {"image_2", true})->IsColor());

  const nlohmann::json color = RunCamera(sequence, dir / "color", "image_2");
  const nlohmann::json grey = RunCamera(sequence, dir / "grey", "image_0");
  ASSERT_TRUE(color.is_object() && grey.is_object());
  EXPECT_EQ(color.value("camera", ""), "image_2");
  EXPECT_EQ(grey.value("camera", ""), "image_0");
  EXPECT_EQ(color.value("tracked", 0), kFrames);
  EXPECT_EQ(grey.value("tracked", 0), kFrames);
  const auto count = [](const nlohmann::json& run, const char* label) {
    return run.at("classes").value(label, 0);
  };
  RecordProperty("color_sky", count(color, "sky"));
  RecordProperty("color_road", count(color, "road"));
  RecordProperty("grey_sky", count(grey, "sky"));
  RecordProperty("grey_road", count(grey, "road"));
  EXPECT_GT(count(color, "sky"), 10 * count(color, "road")) << color.at("classes").dump();
  EXPECT_GT(count(grey, "road"), 10 * count(grey, "sky")) << grey.at("classes").dump();
  EXPECT_GT(count(color, "sky"), 100);
}

TEST(CameraChoice, BadChoicesGiveOneLineNamingTheFolder) {
  SEMSLAM_REQUIRE_BINARY();
  SEMSLAM_ASSERT_ARTIFACT(dataset, TinyDataset());
  const fs::path sequence = SequenceDir(dataset);
  testing::TempDir dir;
  const auto run = [&](const std::vector<std::string>& extra) {
    std::vector<std::string> args = {"run",   "--sequence",           sequence.string(),
                                     "--out", (dir / "out").string(), "-q"};
    args.insert(args.end(), extra.begin(), extra.end());
    return RunSemslam(args);
  };
  for (const auto& [extra, expected] : std::vector<std::pair<std::vector<std::string>, std::string>>{
           {{"--camera", "image_2"}, (sequence / "image_2").string()},
           {{"--camera", "image_1", "--mode", "stereo"}, (sequence / "image_1").string()},
           {{"--camera", "image_00"}, "image_0..image_3"}}) {
    const CommandResult r = run(extra);
    EXPECT_EQ(r.exit_code, 1) << r.Describe();
    EXPECT_NE(r.err.find(expected), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
  // The right camera alone runs monocular.
  const CommandResult mono = run({"--camera", "image_1", "--frames", "0:3"});
  EXPECT_TRUE(mono.Succeeded()) << mono.Describe();
  EXPECT_EQ(ReadJson(dir / "out/run.json").value("camera", ""), "image_1");
}

}  // namespace
}  // namespace semslam::system_test
