// The end-to-end runs on towns no other test uses (issue 9: the synthetic tests must not depend on one seed).
// Each town is driven for 200 frames and SLAM runs over frames 100-199 (~80 m): the street before the town's
// first intersection, then a 90-degree turn taken at the route's limits (40 deg/s; 3.5-4.0 deg per frame on
// these seeds, sim/route.h), then the street after it. Mono and stereo, synchronous pacing, no segmenter.
//
// Measured (commit of this test): mono tracked 98-99 of 100 frames (every frame from 101-102 on), ATE 0.019,
// 0.038, 0.029 m over 85.5, 85.5, 77.7 m (seeds 8191, 27183, 61001): 0.02-0.05 % of the path; stereo 100 of
// 100, ATE 0.040, 0.040, 0.019 m (0.02-0.05 %). The bounds are issue 9's bars for towns the tests never use
// (mono 0.3 %, stereo 0.2 % of the path), 4-6x above what was measured. Cost: three 200-frame towns and six
// 100-frame runs, 33 s with ctest -j2. The asan test preset leaves the mono runs out, as it does the other
// synthetic mono accuracy tests (the clang build initializes later); they were not run under clang.

#include <gtest/gtest.h>

#include <cstdint>
#include <ostream>
#include <set>
#include <string>
#include <vector>

#include "semslam/eval/trajectory_metrics.h"
#include "semslam/io/trajectory_io.h"
#include "support/test_support.h"
#include "system_test_util.h"

namespace semslam::system_test {
namespace {

constexpr int kTownFrames = 200;
constexpr int kFirstFrame = 100;  // the run covers kFirstFrame..kTownFrames-1, the first turn among them
constexpr int kRunFrames = kTownFrames - kFirstFrame;
constexpr double kMonoAteFractionOfPath = 0.003;
constexpr double kStereoAteFractionOfPath = 0.002;
// Mono: the map starts within 10 frames of the first (measured: tracked from the second or third frame on).
constexpr int kMonoInitFrames = 10;

struct SeedRun {
  std::uint64_t seed;
  const char* mode;
};

void PrintTo(const SeedRun& p, std::ostream* os) { *os << p.mode << " on seed " << p.seed; }

std::string Name(const ::testing::TestParamInfo<SeedRun>& info) {
  return std::string(info.param.mode) + "_seed" + std::to_string(info.param.seed);
}

// `semslam synth` of the town.
Artifact Town(std::uint64_t seed) { return SyntheticTown("town" + std::to_string(seed), kTownFrames, seed); }

Artifact SeedRunOf(const SeedRun& p, const fs::path& dataset) {
  const std::vector<std::string> args = {
      "run",    SequenceDir(dataset).string(),
      "--mode", p.mode,
      "--frames", std::to_string(kFirstFrame) + ":" + std::to_string(kTownFrames),
      "--pacing", "synchronous",
      "--segmenter", "none",
      "-q"};
  Artifact run = SharedArtifact(std::string(p.mode) + "_town" + std::to_string(p.seed), args,
                                [&](const fs::path& dir) -> std::string {
                                  std::vector<std::string> full = args;
                                  full.insert(full.begin() + 1, "--sequence");
                                  full.insert(full.end(), {"--out", (dir / "out").string()});
                                  const CommandResult r = RunSemslam(full);
                                  return r.Succeeded() ? "" : r.Describe();
                                });
  if (run.ok()) run.dir /= "out";
  return run;
}

class SyntheticSeeds : public ::testing::TestWithParam<SeedRun> {
 protected:
  void SetUp() override { SEMSLAM_REQUIRE_BINARY(); }
};

TEST_P(SyntheticSeeds, TracksThroughTheTurnWithinTheDriftBound) {
  const SeedRun p = GetParam();
  const bool mono = std::string(p.mode) == "mono";
  SEMSLAM_ASSERT_ARTIFACT(data, Town(p.seed));
  SEMSLAM_ASSERT_ARTIFACT(run, SeedRunOf(p, data));
  const nlohmann::json j = ReadJson(run / "run.json");
  ASSERT_TRUE(j.is_object());
  EXPECT_EQ(j.value("status", ""), "complete");
  EXPECT_EQ(j.value("frames", -1), kRunFrames);
  // Never lost, never reset: a failure here names the frame (tracking.csv of the run holds the states).
  EXPECT_EQ(j.value("relocalizations", -1), 0);
  EXPECT_EQ(j.value("resets", -1), 0);

  // Continuity: from a frame early in the run to its end, every frame has a pose (a monocular map starts from
  // two frames: the first of them has a pose, those between may not).
  const Trajectory trajectory = ReadTumTrajectory(run / "trajectory.tum");
  std::vector<double> stamps;
  for (const StampedPose& pose : trajectory) stamps.push_back(pose.timestamp);
  const std::vector<int> frames = FrameIndices(stamps, ReadTimes(SequenceDir(data) / "times.txt"));
  const std::set<int> tracked(frames.begin(), frames.end());
  ASSERT_EQ(tracked.count(-1), 0u) << "a pose whose timestamp is not a frame's";
  int tracked_from = kTownFrames;
  while (tracked_from > kFirstFrame && tracked.count(tracked_from - 1)) --tracked_from;
  EXPECT_LE(tracked_from, kFirstFrame + (mono ? kMonoInitFrames : 0))
      << "frame " << tracked_from - 1 << " has no pose; tracking.csv of " << run.string() << " says why";

  // Drift: ATE after alignment (Sim(3) mono, SE(3) stereo) and the worst frame, against the true poses.
  EvalOptions options;
  options.alignment = mono ? Alignment::kSim3 : Alignment::kSe3;
  const TrajectoryEvaluation e = EvaluateTrajectoryFiles(run / "trajectory.tum", data / "poses" / "00.txt",
                                                         SequenceDir(data) / "times.txt", options);
  const double path = j.value("path_length_m", 0.0);
  EXPECT_GT(path, 60.0);
  const double bound = (mono ? kMonoAteFractionOfPath : kStereoAteFractionOfPath) * path;
  EXPECT_LE(e.ate.rmse, bound) << "ATE " << e.ate.rmse << " m over " << path << " m";
  EXPECT_LE(e.ate.max, 3 * bound) << "worst frame " << e.ate.max << " m";
  EXPECT_NEAR(e.ate.rmse, j.value("ate_rmse", -1.0), 1e-4);
}

INSTANTIATE_TEST_SUITE_P(HeldOutTowns, SyntheticSeeds,
                         ::testing::Values(SeedRun{8191, "mono"}, SeedRun{8191, "stereo"},
                                           SeedRun{27183, "mono"}, SeedRun{27183, "stereo"},
                                           SeedRun{61001, "mono"}, SeedRun{61001, "stereo"}),
                         Name);

}  // namespace
}  // namespace semslam::system_test
