// Synchronous pacing is the reproducible mode: the same input, options and binary give the same bytes. Each
// case runs one command twice, in two processes (so memory addresses differ too), and compares the outputs:
// trajectory.tum, keyframes.tum, trajectory.kitti, frames.csv, semantic_map.ply, map.semslam (it stores no
// wall-clock time) and run.json but for its times, memory and output paths.
//
// Seed 200's town, 420 frames (356 m): the route's first block ends on the street it began with, and the
// loop closer closes the loop there (then a global BA), with every keyframe and tracked frame segmented
// (truth-noisy:0.25). Then a monocular map that starts after a black-out, and KITTI 07, frames 0-159,
// monocular.
//
// Measured (commit of this test; 2 cores shared with other builds, load 7-10): stereo 97 keyframes, the loop
// at keyframe 95 with keyframe 11, 420 of 420 segmentations fused, 70 s of CPU per run; mono 110 keyframes,
// the loop at keyframe 106 with keyframe 13 (105 with 12 since retrieval ranks by the share of words), 420
// of 420 fused, 45 s; KITTI 07 12 s. Every pair gave the same bytes. Before synchronous pacing waited for the
// loop closer and the segmentation worker, a 900-frame stereo town (seed 2718) gave different trajectories in
// two runs. Cost: the 420-frame town and six runs, about 6 minutes of CPU.

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "support/test_support.h"
#include "system_test_util.h"

namespace semslam::system_test {
namespace {

constexpr int kTownFrames = 420;
constexpr std::uint64_t kTownSeed = 200;

// run.json without what differs between two runs of the same input by design: wall-clock times, memory, and
// the output folder's paths.
nlohmann::json ReproducibleFigures(nlohmann::json run) {
  for (const char* key : {"seconds", "peak_rss_mib", "provenance"}) run.erase(key);
  if (run.contains("config")) run["config"].erase("output");
  if (run.contains("segmentation")) run["segmentation"].erase("median_ms");
  return run;
}

// Runs `args` twice, with --out into two folders, and expects the same bytes in each output; returns the
// first run's run.json.
nlohmann::json ExpectIdenticalRuns(const std::vector<std::string>& args) {
  testing::TempDir dir;
  const fs::path a = dir / "a", b = dir / "b";
  for (const fs::path& out : {a, b}) {
    std::vector<std::string> full = args;
    full.insert(full.end(), {"--out", out.string(), "-q"});
    const CommandResult r = RunSemslam(full);
    EXPECT_TRUE(r.Succeeded()) << r.Describe();
    if (!r.Succeeded()) return {};
  }
  for (const char* file : {"trajectory.tum", "keyframes.tum", "trajectory.kitti", "frames.csv",
                           "semantic_map.ply", "map.semslam"}) {
    EXPECT_TRUE(fs::exists(a / file)) << file;
    EXPECT_TRUE(SameBytes(a / file, b / file)) << file << " differs between two synchronous runs";
  }
  const nlohmann::json ja = ReadJson(a / "run.json"), jb = ReadJson(b / "run.json");
  EXPECT_TRUE(ja.is_object() && jb.is_object());
  const nlohmann::json differences = nlohmann::json::diff(ReproducibleFigures(ja), ReproducibleFigures(jb));
  EXPECT_TRUE(differences.empty()) << "run.json differs: " << differences.dump(1);
  return ja;
}

class SynchronousRuns : public ::testing::TestWithParam<std::string> {
 protected:
  void SetUp() override { SEMSLAM_REQUIRE_BINARY(); }
};

TEST_P(SynchronousRuns, ATownWithALoopAndSegmentationGivesTheSameBytesTwice) {
  const std::string mode = GetParam();
  SEMSLAM_ASSERT_ARTIFACT(town, SyntheticTown("town200_420", kTownFrames, kTownSeed));
  const nlohmann::json run =
      ExpectIdenticalRuns({"run", "--sequence", SequenceDir(town).string(), "--mode", mode, "--pacing",
                           "synchronous", "--segmenter", "truth-noisy:0.25"});
  ASSERT_TRUE(run.is_object());
  // What the comparison covered: a loop closed (with its correction and global BA), and every keyframe and
  // tracked frame segmented and fused, none skipped.
  EXPECT_GE(run.value("loops", 0), 1) << run.dump(1);
  // Accuracy, held within 5 % of the reproducible value (measured: mono 0.0507 m, stereo 0.0692 m over 356 m,
  // every frame with a pose; mono was 0.0482 m before retrieval ranked keyframes by their share of common
  // words, which closes its loop one keyframe earlier).
  const double measured_ate = mode == "mono" ? 0.0507 : 0.0692;
  EXPECT_LE(run.value("ate_rmse", 1e9), 1.05 * measured_ate);
  EXPECT_EQ(run.value("with_pose", 0), kTownFrames);
  // Without GPS a monocular map's objects take their scale from the camera's height above the road, against
  // the trajectory's own (its Sim(3) to the truth); a stereo map is metric.
  const nlohmann::json& geo = run["geo"];
  if (mode == "mono") {
    EXPECT_EQ(geo.value("objects_scale_source", ""), "road");
    // Measured 19.27 against 18.89 m per map unit (+2.0 %; KITTI 00, 07, drive 0005 colour: -0.4, -2.7, +1.6
    // %).
    const double truth_scale = run.value("ate_scale", 0.0);
    EXPECT_NEAR(geo.value("objects_metres_per_map_unit", 0.0), truth_scale, 0.025 * truth_scale);
  } else {
    EXPECT_EQ(geo.value("objects_scale_source", ""), "map");
  }
  const nlohmann::json& segmentation = run["segmentation"];
  EXPECT_EQ(segmentation.value("skipped", -1), 0);
  EXPECT_EQ(segmentation.value("failed", -1), 0);
  EXPECT_GE(segmentation.value("segmented_keyframes", 0), run.value("keyframes", 0));
  EXPECT_EQ(segmentation.value("segmented_keyframes", 0) + segmentation.value("segmented_frames", 0),
            segmentation.value("submitted", -1));
}

std::string ModeName(const ::testing::TestParamInfo<std::string>& param) { return param.param; }

INSTANTIATE_TEST_SUITE_P(Modes, SynchronousRuns, ::testing::Values("mono", "stereo"), ModeName);

// A monocular map that starts after a black-out (seed 2027's town from frame 640, frames 750-769 black, a new
// map at 770). The tracker once handed a frame's new keyframes to the mapper before it took the frame's
// record (and, at an initialization, counted the keyframe's points), and a local BA on the mapper's thread
// could move the keyframe in between: beside two busy processes, 5 of 5 synchronous runs of KITTI 00 every
// 2nd frame differed (first at frame 534, the second map's first keyframes). On this short drive the race
// showed in none of 3 such runs; the test holds a map restart's path to the same bytes.
TEST(SynchronousRunsAfterABlackOut, ANewMonocularMapGivesTheSameBytesTwice) {
  SEMSLAM_REQUIRE_BINARY();
  SEMSLAM_ASSERT_ARTIFACT(dir, LookAlikeBlackOutRun());
  std::vector<std::string> args = LookAlikeBlackOutRunArgs();
  args.insert(args.end(), {"--sequence", (dir / "sequence").string()});
  const nlohmann::json run = ExpectIdenticalRuns(args);
  ASSERT_TRUE(run.is_object());
  EXPECT_GE(run["maps"].value("count", 0), 2) << "no new map started: " << run.dump(1);
}

TEST(SynchronousRunsOnKitti, Kitti07MonocularGivesTheSameBytesTwice) {
  SEMSLAM_REQUIRE_BINARY();
  SEMSLAM_REQUIRE_SHARED_DATA(kitti, "kitti_odom_07_3dv");
  const nlohmann::json run =
      ExpectIdenticalRuns({"run", "--sequence", (kitti / "sequences" / "07").string(), "--mode", "mono",
                           "--frames", "0:160", "--pacing", "synchronous"});
  ASSERT_TRUE(run.is_object());
  EXPECT_EQ(run.value("frames", 0), 160);
}

}  // namespace
}  // namespace semslam::system_test
