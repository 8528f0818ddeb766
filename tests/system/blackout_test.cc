// Two seconds of black frames in the 200-frame city (frames 60-79, on a straight street at about 10 m/s):
// tracking is lost, and when the frames come back the camera is 20 m further on. The map it was lost from is
// searched first, where the motion model puts the camera, before a new map may start: the drive goes on in
// one map, as accurate as without the black-out (issue 9: "never lost for good").

#include <gtest/gtest.h>

#include <set>
#include <string>
#include <vector>

#include "semslam/eval/trajectory_metrics.h"
#include "semslam/io/trajectory_io.h"
#include "support/test_support.h"
#include "system_test_util.h"

namespace semslam::system_test {
namespace {

constexpr int kFirstBlack = 60, kEndBlack = 80;

Artifact BlackOutSequence() {
  const Artifact city = SyntheticDataset();
  if (!city.ok()) return city;
  const fs::path sequence = SequenceDir(city.dir);
  const std::vector<std::string> args = {
      "compose",    "--stereo",
      "--sequence", sequence.string(),
      "--frames",   "0-" + std::to_string(kSyntheticFrames - 1),
      "--black",    std::to_string(kFirstBlack) + ":" + std::to_string(kEndBlack),
      "-q"};
  return SharedArtifact("city200_black", args, [&](const fs::path& dir) -> std::string {
    std::vector<std::string> full = args;
    full.insert(full.end(), {"--out", (dir / "sequence").string()});
    const CommandResult r = RunSemslam(full);
    return r.Succeeded() ? "" : r.Describe();
  });
}

Artifact BlackOutRun(const std::string& mode) {
  const Artifact black = BlackOutSequence();
  if (!black.ok()) return black;
  const std::vector<std::string> args = {"run",         "--sequence",  (black.dir / "sequence").string(),
                                         "--mode",      mode,          "--pacing",
                                         "synchronous", "--segmenter", "none",
                                         "-q"};
  Artifact run = SharedArtifact("city200_black_" + mode, args, [&](const fs::path& dir) -> std::string {
    std::vector<std::string> full = args;
    full.insert(full.end(), {"--out", (dir / "out").string()});
    const CommandResult r = RunSemslam(full);
    return r.Succeeded() ? "" : r.Describe();
  });
  if (run.ok()) run.dir /= "out";
  return run;
}

class BlackOut : public ::testing::TestWithParam<std::string> {
 protected:
  void SetUp() override { SEMSLAM_REQUIRE_BINARY(); }
};

TEST_P(BlackOut, TheMapIsFoundAgainAndTheDriveGoesOnInIt) {
  const bool mono = GetParam() == "mono";
  SEMSLAM_ASSERT_ARTIFACT(black, BlackOutSequence());
  SEMSLAM_ASSERT_ARTIFACT(run, BlackOutRun(GetParam()));
  const nlohmann::json j = ReadJson(run / "run.json");
  ASSERT_TRUE(j.is_object());
  EXPECT_EQ(j.value("status", ""), "complete");
  // One map: found again at the first frames after the black-out, no new map started.
  EXPECT_EQ(j["maps"].value("count", -1), 1);
  EXPECT_EQ(j["maps"].value("started", -1), 0);
  EXPECT_GE(j.value("relocalizations", 0), 1);
  EXPECT_EQ(j.value("resets", -1), 0);
  // Every frame has a pose: tracked, or, for the black ones (and at most one lost frame before the
  // relocalization), the motion model's prediction.
  const int predicted = j.value("predicted", -1);
  EXPECT_EQ(j.value("with_pose", -1) + predicted, kSyntheticFrames);
  EXPECT_GE(predicted, kEndBlack - kFirstBlack);
  EXPECT_LE(predicted, kEndBlack - kFirstBlack + 1);

  // Tracked again within two frames of the black-out's end, and to the last frame.
  const Trajectory trajectory = ReadTumTrajectory(run / "trajectory.tum");
  const std::vector<int> frames =
      FrameIndices(Timestamps(trajectory), ReadTimes(black / "sequence" / "times.txt"));
  std::set<int> tracked(frames.begin(), frames.end());
  int tracked_from = kSyntheticFrames;
  while (tracked_from > 0 && tracked.count(tracked_from - 1)) --tracked_from;
  EXPECT_LE(tracked_from, kEndBlack + 2) << "tracking.csv of " << run.string() << " says why";

  // As accurate as the uninterrupted runs' bounds (synthetic_run_test.cc): 0.25 % of the path mono, 0.25 m
  // stereo; measured 0.070 m mono and 0.038 m stereo (the same drive uninterrupted: 0.10 m, 0.07 m).
  EvalOptions options;
  options.alignment = mono ? Alignment::kSim3 : Alignment::kSe3;
  const TrajectoryEvaluation e = EvaluateTrajectoryFiles(
      run / "trajectory.tum", black / "sequence" / "gt.txt", black / "sequence" / "times.txt", options);
  const double path = j.value("path_length_m", 0.0);
  EXPECT_GT(path, 150.0);
  EXPECT_LE(e.ate.rmse, mono ? 0.0025 * path : 0.25) << "ATE " << e.ate.rmse << " m over " << path << " m";
}

std::string ModeName(const ::testing::TestParamInfo<std::string>& mode) { return mode.param; }

INSTANTIATE_TEST_SUITE_P(Modes, BlackOut, ::testing::Values("mono", "stereo"), ModeName);

}  // namespace
}  // namespace semslam::system_test
