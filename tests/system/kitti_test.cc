// Real data: KITTI odometry 07, frames 0-159 (left camera, ~91 m with a left turn), monocular, synchronous
// pacing. The SPEC bar is ATE <= 0.3 m; the default pacing's figures are in docs/results.md.

#include <gtest/gtest.h>

#include <fstream>
#include <set>
#include <string>

#include "semslam/io/trajectory_io.h"
#include "support/test_support.h"
#include "system_test_util.h"

namespace semslam::system_test {
namespace {

TEST(Kitti07, MonocularInitializesEarlyTracksEveryLaterFrameAndStaysAccurate) {
  SEMSLAM_REQUIRE_BINARY();
  SEMSLAM_REQUIRE_SHARED_DATA(kitti, "kitti_odom_07_3dv");
  const fs::path sequence = kitti / "sequences" / "07";
  testing::TempDir dir;
  const fs::path out = dir / "out";
  const CommandResult r = RunSemslam({"run", "--sequence", sequence.string(), "--out", out.string(), "--mode",
                                      "mono", "--frames", "0:160", "--pacing", "synchronous", "-q"});
  ASSERT_TRUE(r.Succeeded()) << r.Describe();
  const nlohmann::json j = ReadJson(out / "run.json");
  ASSERT_TRUE(j.is_object()) << ReadText(out / "run.json");
  EXPECT_EQ(j.value("frames", -1), 160);
  EXPECT_EQ(j.value("resets", -1), 0);

  // Initialized within the first 20 frames; from then on every frame has a pose (the frames between the two
  // the map started from too).
  const Trajectory trajectory = ReadTumTrajectory(out / "trajectory.tum");
  std::vector<double> stamps;
  for (const StampedPose& p : trajectory) stamps.push_back(p.timestamp);
  const std::vector<int> frames = FrameIndices(stamps, ReadTimes(sequence / "times.txt"));
  std::set<int> tracked;
  for (const int f : frames) {
    ASSERT_GE(f, 0) << "a trajectory.tum timestamp is not in times.txt";
    ASSERT_LT(f, 160);
    tracked.insert(f);
  }
  ASSERT_EQ(tracked.size(), frames.size()) << "a frame appears twice in trajectory.tum";
  int from = 160;
  while (from > 0 && tracked.count(from - 1)) --from;
  EXPECT_LE(from, 20) << "frames " << from << "..159 tracked";
  EXPECT_EQ(j.value("with_pose", 0), static_cast<int>(frames.size()));
  EXPECT_GE(j.value("tracked", 0), 140);

  // Accuracy: ATE after Sim(3) alignment.
  ASSERT_TRUE(j.contains("ate_rmse")) << j.dump(2);
  EXPECT_EQ(j.value("ate_alignment", ""), "sim3");
  // Within 5 % of the reproducible value: 0.1363 m (0.37 m without self-calibration).
  EXPECT_LE(j["ate_rmse"].get<double>(), 0.143);
  EXPECT_NEAR(j.value("path_length_m", 0.0), 90.6, 1.0);
  EXPECT_GE(j.value("ate_matched", 0), 160 - from);

  // `semslam eval` against the official poses (1101 of them, times.txt lists 1101 stamps) agrees.
  const CommandResult e =
      RunSemslam({"eval", "--estimate", (out / "trajectory.tum").string(), "--truth",
                  (kitti / "poses" / "07.txt").string(), "--times", (sequence / "times.txt").string()});
  ASSERT_TRUE(e.Succeeded()) << e.Describe();
  const nlohmann::json ej = nlohmann::json::parse(e.out, nullptr, false);
  ASSERT_TRUE(ej.is_object()) << e.out;
  EXPECT_NEAR(ej["ate_rmse"].get<double>(), j["ate_rmse"].get<double>(), 1e-4);
  EXPECT_EQ(ej["matched"].get<size_t>(), trajectory.size());

  // The published intrinsics are about 1 % off (measured on this drive): the final BA's self-calibration finds a
  // shorter focal length (measured 699-701 px against 707.09), keeps it, and that is what meets the bar.
  ASSERT_EQ(j.value("intrinsics_refinement", nlohmann::json()).size(), 1u) << j.dump(2);
  const nlohmann::json& refinement = j["intrinsics_refinement"][0];
  EXPECT_TRUE(refinement.value("accepted", false)) << refinement.dump(2);
  EXPECT_LT(refinement["refined"]["fx"].get<double>(), 0.995 * refinement["nominal"]["fx"].get<double>());
  const fs::path config = dir / "no_refinement.yaml";
  std::ofstream(config) << "mapping:\n  final_refine_intrinsics: false\n";
  const fs::path plain = dir / "plain";
  const CommandResult p =
      RunSemslam({"run", "--sequence", sequence.string(), "--out", plain.string(), "--mode", "mono",
                  "--frames", "0:160", "--pacing", "synchronous", "--config", config.string(), "-q"});
  ASSERT_TRUE(p.Succeeded()) << p.Describe();
  const nlohmann::json pj = ReadJson(plain / "run.json");
  EXPECT_TRUE(pj.value("intrinsics_refinement", nlohmann::json{1}).empty());
  EXPECT_GT(pj.value("ate_rmse", 0.0), 1.5 * j["ate_rmse"].get<double>());
}

// The same frames at a third of the frame rate (every third frame, 54 in all, about 1.7 m apart): a car at
// three times the speed, or a slower camera. Where the rate of turn or pitch changes between two frames the
// constant-velocity prediction misses by more than the search window; tracked only from it, frame 49 was
// lost and the drive ended with 49 frames with a pose.
TEST(Kitti07, AThirdOfTheFrameRateIsTrackedToTheLastFrame) {
  SEMSLAM_REQUIRE_BINARY();
  SEMSLAM_REQUIRE_SHARED_DATA(kitti, "kitti_odom_07_3dv");
  std::string frames;
  for (int f = 0; f < 160; f += 3) {
    if (!frames.empty()) frames += ',';
    frames.append(std::to_string(f));
  }
  SEMSLAM_ASSERT_ARTIFACT(dir, ComposedRun("kitti07_every_third",
                                           {"compose", "--sequence", (kitti / "sequences" / "07").string(),
                                            "--frames", frames, "-q"},
                                           {"run", "--mode", "mono", "--pacing", "synchronous", "-q"}));
  const nlohmann::json j = ReadJson(dir / "out" / "run.json");
  ASSERT_TRUE(j.is_object()) << ReadText(dir / "out" / "run.json");
  EXPECT_EQ(j.value("frames", -1), 54);
  EXPECT_EQ(j.value("with_pose", -1), 54);
  EXPECT_EQ(j.value("predicted", -1), 0);
  EXPECT_EQ(j["maps"].value("count", -1), 1);
  // 1.05 x the reproducible value, 0.1735 m; the SPEC's bar for the drive is 0.3 m.
  EXPECT_LE(j.value("ate_rmse", 1e9), 1.05 * 0.1735);
  EXPECT_EQ(j.value("ate_matched", -1), 54);
}

}  // namespace
}  // namespace semslam::system_test
