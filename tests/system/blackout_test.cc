// Two seconds of black frames in the 200-frame city (frames 60-79, on a straight street at about 10 m/s):
// tracking is lost, and when the frames come back the camera is 20 m further on. The map it was lost from is
// searched first, where the motion model puts the camera, before a new map may start: the drive goes on in
// one map, as accurate as without the black-out (issue 9: "never lost for good"). Then a black-out on a
// street where a block back looks like the street ahead: no frame may be put there.

#include <gtest/gtest.h>

#include <map>
#include <set>
#include <sstream>
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

  // Within 5 % of the reproducible values (synchronous pacing): 0.2023 m mono, 0.0366 m stereo over 195 m.
  EvalOptions options;
  options.alignment = mono ? Alignment::kSim3 : Alignment::kSe3;
  const TrajectoryEvaluation e = EvaluateTrajectoryFiles(
      run / "trajectory.tum", black / "sequence" / "gt.txt", black / "sequence" / "times.txt", options);
  const double path = j.value("path_length_m", 0.0);
  EXPECT_GT(path, 150.0);
  EXPECT_LE(e.ate.rmse, mono ? 0.2125 : 0.0385) << "ATE " << e.ate.rmse << " m over " << path << " m";
}

std::string ModeName(const ::testing::TestParamInfo<std::string>& mode) { return mode.param; }

INSTANTIATE_TEST_SUITE_P(Modes, BlackOut, ::testing::Values("mono", "stereo"), ModeName);

// frames.csv's tracked poses, by map.
std::map<int, Trajectory> TrackedPosesByMap(const fs::path& frames_csv) {
  std::map<int, Trajectory> maps;
  const std::vector<std::string> rows = Lines(ReadText(frames_csv));
  for (size_t i = 1; i < rows.size(); ++i) {
    std::vector<std::string> cells;
    std::stringstream row(rows[i]);
    for (std::string cell; std::getline(row, cell, ',');) cells.push_back(cell);
    if (cells.size() < 12 || cells[3] != "tracked") continue;
    StampedPose pose;
    pose.timestamp = std::stod(cells[1]);
    pose.world_from_camera.translation = {std::stod(cells[5]), std::stod(cells[6]), std::stod(cells[7])};
    pose.world_from_camera.rotation = Eigen::Quaterniond(std::stod(cells[11]), std::stod(cells[8]),
                                                         std::stod(cells[9]), std::stod(cells[10]));
    maps[std::stoi(cells[2])].push_back(pose);
  }
  return maps;
}

// Seed 2027's town, black frames 750-769 on a street of repeating fronts. The car drives 19 m in the
// black-out, and the street a block back looks like the one ahead: found there by bag of words in the lost
// map, the first frame after the black-out was put about where the camera had been before it, and the drive
// went on from there (2 of 4 runs of the 1500-frame drive at default pacing: 25 m off at worst, ATE 4.0 m;
// this run over frames 640-799: 13.3 m off at frame 770). Lost for more than a second, the camera is now
// searched for in the lost map only around the prediction; here a new map starts at frame 770
// (LookAlikeBlackOutRun).
TEST(BlackOutOnALookAlikeStreet, NoFrameIsPutABlockBackInTheLostMap) {
  SEMSLAM_REQUIRE_BINARY();
  SEMSLAM_ASSERT_ARTIFACT(dir, LookAlikeBlackOutRun());
  const Trajectory truth = ReadSequenceGroundTruth(dir / "sequence");
  const std::map<int, Trajectory> maps = TrackedPosesByMap(dir / "out" / "frames.csv");
  ASSERT_FALSE(maps.empty());
  ASSERT_TRUE(maps.count(0));
  EXPECT_GE(maps.at(0).size(), 100u);  // frames 640-749
  // Each map's tracked poses, Sim(3)-aligned to the truth on their own: none more than 2 m off (issue 9's bar
  // for relocalizations). Measured: 0.15 m in map 0, 0.05 m in map 1; 13.3 m at frame 770 before the fix.
  for (const auto& [map, poses] : maps) {
    const AteResult ate = ComputeAte(poses, truth, Alignment::kSim3);
    EXPECT_LE(ate.max, 2.0) << "map " << map << ": " << poses.size() << " tracked frames, ATE " << ate.rmse
                            << " m, worst " << ate.max << " m (frames.csv of " << (dir / "out").string()
                            << ")";
  }
}

// Seed 31's town, 400 frames, black frames 200-219, stereo: tracking is lost and a new map starts after
// the black-out. At frame 391 the new map meets a block that looks like the one of frame 115, 73 m away; the
// place passed every check of the loop closer (155 matches, 5 neighbours agreeing), the two maps were merged
// there, and the drive's ATE was 30.9 m. A stereo merge now waits for a second place out of sight of the
// first (MergeVerifier): the look-alike stays unmerged. (Seeds 4242 and 5153 merged look-alikes too, 53 m
// and 81 m ATE; 0.12 m and 0.14 m now.)
Artifact StereoLookAlikeRun() {
  const Artifact town = SyntheticTown("town31_400", 400, 31);
  if (!town.ok()) return town;
  const std::vector<std::string> compose = {"compose",  "--sequence", SequenceDir(town.dir).string(),
                                            "--frames", "0-399",      "--black",
                                            "200:220",  "--stereo",   "-q"};
  const std::vector<std::string> run = {"run",         "--mode",      "stereo", "--pacing",
                                        "synchronous", "--segmenter", "none",   "-q"};
  return ComposedRun("town31_400_black200_stereo", compose, run);
}

TEST(BlackOutInALookAlikeTown, AStereoMapIsNotMergedAtOnePlaceThatOnlyLooksTheSame) {
  SEMSLAM_REQUIRE_BINARY();
  SEMSLAM_ASSERT_ARTIFACT(dir, StereoLookAlikeRun());
  const nlohmann::json j = ReadJson(dir / "out" / "run.json");
  ASSERT_TRUE(j.is_object());
  EXPECT_EQ(j["maps"].value("started", -1), 1) << "the black-out's loss";
  EXPECT_EQ(j["maps"].value("merges", -1), 0);
  // Within 5 % of the reproducible value (synchronous pacing): 0.0264 m, each map's frames with a pose.
  EXPECT_LE(j.value("ate_rmse", 1e9), 1.05 * 0.0264);
}

}  // namespace
}  // namespace semslam::system_test
