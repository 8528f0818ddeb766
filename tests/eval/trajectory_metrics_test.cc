#include "semslam/eval/trajectory_metrics.h"

#include <gtest/gtest.h>

#include <cmath>

#include "semslam/core/error.h"
#include "semslam/io/trajectory_io.h"
#include "support/test_support.h"
#include "../io/test_files.h"

namespace semslam {
namespace {

Rigid3d At(double x, double y, double z) {
  return Rigid3d(Eigen::Quaterniond::Identity(), Eigen::Vector3d(x, y, z));
}

// A winding 3D drive: not collinear, turning and climbing, rotations following the heading.
Trajectory WindingDrive(int n, double step_m = 1.0) {
  Trajectory t;
  for (int i = 0; i < n; ++i) {
    const double s = step_m * i;
    const double heading = 0.3 * std::sin(s / 40.0);
    const Eigen::Quaterniond q(Eigen::AngleAxisd(heading, Eigen::Vector3d::UnitY()));
    t.push_back(
        {0.1 * i, Rigid3d(q, Eigen::Vector3d(20.0 * std::sin(s / 50.0), 0.5 * std::sin(s / 13.0), s))});
  }
  return t;
}

// Straight along the camera's z axis, one pose per metre.
Trajectory StraightDrive(int n) {
  Trajectory t;
  for (int i = 0; i < n; ++i) t.push_back({0.1 * i, At(0, 0, i)});
  return t;
}

TEST(Association, NearestWithinMaxDtEachTruthPoseOnce) {
  Trajectory truth, estimate;
  for (double t : {0.0, 0.1, 0.2, 0.3, 0.4}) truth.push_back({t, Rigid3d()});
  // 0.005 -> 0; 0.095 and 0.104 both nearest to 0.1 (0.104 is closer); 0.25 is 0.05 from both neighbours;
  // 0.41 -> 0.4; 9.0 -> nothing.
  for (double t : {0.005, 0.095, 0.104, 0.25, 0.41, 9.0}) estimate.push_back({t, Rigid3d()});
  const auto pairs = AssociateByTimestamp(estimate, truth, 0.02);
  ASSERT_EQ(pairs.size(), 3u);
  EXPECT_EQ(pairs[0].estimate, 0u);
  EXPECT_EQ(pairs[0].truth, 0u);
  EXPECT_EQ(pairs[1].estimate, 2u);
  EXPECT_EQ(pairs[1].truth, 1u);
  EXPECT_EQ(pairs[2].estimate, 4u);
  EXPECT_EQ(pairs[2].truth, 4u);
  EXPECT_EQ(AssociateByTimestamp(estimate, truth, 0.0).size(), 0u);
  Trajectory unsorted = {{1.0, Rigid3d()}, {0.5, Rigid3d()}};
  EXPECT_THROW(AssociateByTimestamp(unsorted, truth, 0.02), InvalidArgument);
}

TEST(Ate, KnownSim3GivesZeroErrorAndRecoversTheScale) {
  const Trajectory truth = WindingDrive(200);
  const Sim3d estimate_from_truth(
      2.5, Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized())),
      Eigen::Vector3d(10, -4, 7));
  Trajectory estimate = truth;
  for (auto& p : estimate) p.world_from_camera = estimate_from_truth.TransformPose(p.world_from_camera);

  const TrajectoryEvaluation e = EvaluateTrajectory(estimate, truth, {});
  EXPECT_EQ(e.matched, 200u);
  EXPECT_FALSE(e.ate.alignment_fallback);
  EXPECT_LT(e.ate.rmse, 1e-9);
  EXPECT_LT(e.ate.max, 1e-9);
  EXPECT_NEAR(e.ate.scale, 1.0 / 2.5, 1e-12);
  ASSERT_TRUE(e.rpe.has_value());
  EXPECT_LT(e.rpe->trans_rmse_m, 1e-9);
  EXPECT_LT(e.rpe->rot_rmse_deg, 1e-6);
  ASSERT_TRUE(e.kitti.trans_pct.has_value());  // 199 m of path
  EXPECT_LT(*e.kitti.trans_pct, 1e-9);

  // SE(3) cannot undo the scale: the error is large, and the scale reported is 1.
  const AteResult se3 = ComputeAte(estimate, truth, Alignment::kSe3);
  EXPECT_GT(se3.rmse, 10.0);
  EXPECT_DOUBLE_EQ(se3.scale, 1.0);
}

TEST(Ate, ConstantOffsetWithoutAlignment) {
  const Trajectory truth = WindingDrive(50);
  Trajectory estimate = truth;
  for (auto& p : estimate) p.world_from_camera.translation += Eigen::Vector3d(0.3, 0.4, 0.0);
  const AteResult none = ComputeAte(estimate, truth, Alignment::kNone);
  EXPECT_NEAR(none.rmse, 0.5, 1e-12);
  EXPECT_NEAR(none.mean, 0.5, 1e-12);
  EXPECT_NEAR(none.median, 0.5, 1e-12);
  EXPECT_NEAR(none.max, 0.5, 1e-12);
  EXPECT_NEAR(none.std, 0.0, 1e-6);
  EXPECT_EQ(none.scale, 1.0);
  // Any alignment removes a pure translation.
  EXPECT_LT(ComputeAte(estimate, truth, Alignment::kSe3).rmse, 1e-9);
}

TEST(Ate, HandComputedCase) {
  // Truth: four poses 1 m apart along x. Estimate: the same times (+10 ms), plus one unmatched pose.
  const Trajectory truth = {{0.0, At(0, 0, 0)}, {1.0, At(1, 0, 0)}, {2.0, At(2, 0, 0)}, {3.0, At(3, 0, 0)}};
  const Trajectory estimate = {
      {0.01, At(0, 1, 0)}, {1.01, At(1, 0, 2)}, {2.01, At(2, 0, 0)}, {3.01, At(3, 3, 4)}, {7.0, At(9, 9, 9)}};
  EvalOptions options;
  options.alignment = Alignment::kNone;
  const TrajectoryEvaluation e = EvaluateTrajectory(estimate, truth, options);
  EXPECT_EQ(e.estimate_poses, 5u);
  EXPECT_EQ(e.truth_poses, 4u);
  EXPECT_EQ(e.matched, 4u);
  EXPECT_DOUBLE_EQ(e.path_length_m, 3.0);
  // Errors 1, 2, 0, 5.
  ASSERT_EQ(e.ate.errors.size(), 4u);
  EXPECT_DOUBLE_EQ(e.ate.errors[3], 5.0);
  EXPECT_NEAR(e.ate.rmse, std::sqrt(30.0 / 4.0), 1e-12);  // 2.7386
  EXPECT_NEAR(e.ate.mean, 2.0, 1e-12);
  EXPECT_NEAR(e.ate.median, 1.5, 1e-12);
  EXPECT_NEAR(e.ate.std, std::sqrt(7.5 - 4.0), 1e-12);  // 1.8708
  EXPECT_NEAR(e.ate.max, 5.0, 1e-12);
  // Consecutive relative translations (1,-1,2), (1,0,-2), (1,3,4) against (1,0,0): errors sqrt(5), 2, 5.
  ASSERT_TRUE(e.rpe.has_value());
  EXPECT_EQ(e.rpe->pairs, 3u);
  EXPECT_NEAR(e.rpe->trans_rmse_m, std::sqrt(34.0 / 3.0), 1e-12);  // 3.3665
  EXPECT_NEAR(e.rpe->rot_rmse_deg, 0.0, 1e-12);
  EXPECT_FALSE(e.rpe_distance.has_value());  // 3 m of path
  EXPECT_FALSE(e.kitti.trans_pct.has_value());
  EXPECT_TRUE(e.kitti.per_length.empty());
}

TEST(KittiErrors, StraightDriveWithOnePercentScaleError) {
  const Trajectory truth = StraightDrive(1001);  // 1000 m
  Trajectory estimate = truth;
  for (auto& p : estimate) p.world_from_camera.translation *= 1.01;

  for (const Alignment alignment : {Alignment::kNone, Alignment::kSe3}) {
    EvalOptions options;
    options.alignment = alignment;
    const TrajectoryEvaluation e = EvaluateTrajectory(estimate, truth, options);
    EXPECT_EQ(e.ate.alignment_fallback, alignment == Alignment::kSe3);  // a straight line is degenerate
    ASSERT_TRUE(e.kitti.trans_pct.has_value());
    EXPECT_NEAR(*e.kitti.trans_pct, 1.0, 1e-9);
    EXPECT_NEAR(*e.kitti.rot_deg_per_100m, 0.0, 1e-9);
    ASSERT_EQ(e.kitti.per_length.size(), 8u);
    EXPECT_EQ(e.kitti.per_length[0].length_m, 100.0);
    EXPECT_EQ(e.kitti.per_length[0].count, 91u);  // starts 0, 10, ..., 900
    EXPECT_EQ(e.kitti.per_length[7].count, 21u);  // starts 0, 10, ..., 200
    EXPECT_NEAR(e.kitti.per_length[7].trans_pct, 1.0, 1e-9);
    EXPECT_EQ(e.kitti.segments, 91u + 81 + 71 + 61 + 51 + 41 + 31 + 21);
    ASSERT_TRUE(e.rpe.has_value());
    EXPECT_NEAR(e.rpe->trans_rmse_m, 0.01, 1e-9);
    ASSERT_TRUE(e.rpe_distance.has_value());
    EXPECT_NEAR(e.rpe_distance->trans_rmse_m, 1.0, 1e-9);
    EXPECT_EQ(e.rpe_distance->pairs, 901u);
  }
  // Sim(3) finds the scale (by path length, the line being degenerate) and the error vanishes.
  const TrajectoryEvaluation sim3 = EvaluateTrajectory(estimate, truth, {});
  EXPECT_TRUE(sim3.ate.alignment_fallback);
  EXPECT_NEAR(sim3.ate.scale, 1.0 / 1.01, 1e-12);
  EXPECT_LT(sim3.ate.rmse, 1e-9);
  EXPECT_LT(*sim3.kitti.trans_pct, 1e-9);
}

TEST(KittiErrors, SteadyHeadingDriftGivesItsRatePerHundredMetres) {
  // The estimate turns 1e-4 rad about y per metre driven while the truth does not: every segment of length L
  // ends with a rotation error of 1e-4 * L rad, i.e. 0.573 deg/100 m.
  const Trajectory truth = StraightDrive(501);
  Trajectory estimate = truth;
  for (size_t i = 0; i < estimate.size(); ++i) {
    estimate[i].world_from_camera.rotation =
        Eigen::Quaterniond(Eigen::AngleAxisd(1e-4 * static_cast<double>(i), Eigen::Vector3d::UnitY()));
  }
  EvalOptions options;
  options.alignment = Alignment::kNone;
  const TrajectoryEvaluation e = EvaluateTrajectory(estimate, truth, options);
  ASSERT_TRUE(e.kitti.rot_deg_per_100m.has_value());
  EXPECT_NEAR(*e.kitti.rot_deg_per_100m, 1e-4 * 100.0 * 180.0 / M_PI, 1e-9);
  for (const auto& s : e.kitti.per_length) EXPECT_NEAR(s.rot_deg_per_100m, 0.5729578, 1e-6) << s.length_m;
  EXPECT_EQ(e.kitti.per_length.size(), 5u);  // 100..500 m
  EXPECT_NEAR(e.rpe->rot_rmse_deg, 1e-4 * 180.0 / M_PI, 1e-9);
}

TEST(KittiErrors, Sequence07GroundTruthAgainstItself) {
  SEMSLAM_REQUIRE_SHARED_DATA(data, "kitti_odom_07_3dv");
  const Trajectory truth = ReadTrajectory(data / "poses/07.txt", data / "sequences/07/times.txt");
  ASSERT_EQ(truth.size(), 1101u);
  const TrajectoryEvaluation e = EvaluateTrajectory(truth, truth, {});
  EXPECT_EQ(e.matched, 1101u);
  EXPECT_GT(e.path_length_m, 600.0);
  EXPECT_LT(e.ate.rmse, 1e-9);
  EXPECT_NEAR(e.ate.scale, 1.0, 1e-9);
  ASSERT_TRUE(e.kitti.trans_pct.has_value());
  EXPECT_LT(*e.kitti.trans_pct, 1e-9);
  EXPECT_LT(*e.kitti.rot_deg_per_100m, 1e-6);
  size_t lengths_on_path = 0;
  for (double length = 100; length <= e.path_length_m; length += 100) ++lengths_on_path;
  EXPECT_EQ(e.kitti.per_length.size(), lengths_on_path);  // 07 is ~695 m long: 100..600 m
  EXPECT_GT(e.kitti.segments, 300u);
  // The first 160 frames cover only ~90.6 m: no KITTI segments, no 100 m RPE.
  const Trajectory first160(truth.begin(), truth.begin() + 160);
  const TrajectoryEvaluation short_run = EvaluateTrajectory(first160, truth, {});
  EXPECT_EQ(short_run.matched, 160u);
  EXPECT_NEAR(short_run.path_length_m, 90.6, 0.1);
  EXPECT_FALSE(short_run.kitti.trans_pct.has_value());
  EXPECT_FALSE(short_run.rpe_distance.has_value());
}

TEST(EvaluateTrajectoryFiles, FormatsTimesAndErrors) {
  testing::TempDir dir;
  const Trajectory truth = WindingDrive(30);
  WriteTumTrajectory(dir / "truth.tum", truth);
  WriteKittiPoses(dir / "estimate.txt", truth);
  std::vector<double> times;
  for (const auto& p : truth) times.push_back(p.timestamp);
  WriteTimes(dir / "times.txt", times);

  const TrajectoryEvaluation evaluation =
      EvaluateTrajectoryFiles(dir / "estimate.txt", dir / "truth.tum", dir / "times.txt");
  EXPECT_EQ(evaluation.matched, 30u);
  EXPECT_LT(evaluation.ate.rmse, 1e-6);
  // A KITTI estimate over part of the frames says which (line i is frame first + i).
  times.push_back(99.0);
  WriteTimes(dir / "longer_times.txt", times);
  EXPECT_INPUT_ERROR(EvaluateTrajectoryFiles(dir / "estimate.txt", dir / "truth.tum", dir / "longer_times.txt"),
                     "estimate.txt", "holds 30 poses", "31 stamps", "--frames");
  EXPECT_EQ(EvaluateTrajectoryFiles(dir / "estimate.txt", dir / "truth.tum", dir / "longer_times.txt", {},
                                    FrameRange{0, 30})
                .matched,
            30u);
  // KITTI against KITTI, by index.
  EXPECT_EQ(EvaluateTrajectoryFiles(dir / "estimate.txt", dir / "estimate.txt", std::nullopt).matched, 30u);

  try {
    EvaluateTrajectoryFiles(dir / "estimate.txt", dir / "truth.tum", std::nullopt);
    ADD_FAILURE() << "expected InputError";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("--times"), std::string::npos) << error.what();
  }
  Trajectory late = truth;
  for (auto& p : late) p.timestamp += 1000.0;
  WriteTumTrajectory(dir / "late.tum", late);
  try {
    EvaluateTrajectoryFiles(dir / "late.tum", dir / "truth.tum", std::nullopt);
    ADD_FAILURE() << "expected InputError";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("late.tum"), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("no estimated pose matched"), std::string::npos) << error.what();
  }
  EXPECT_THROW(ComputeAte(late, truth, Alignment::kSim3), EvaluationError);
}

// evo and the KITTI devkit pair line i of a KITTI file with frame i: a file with a frame left out must be
// refused, not silently shifted by one frame from the gap on.
TEST(EvaluateTrajectoryFiles, KittiLineCountMustMatchTheFrames) {
  testing::TempDir dir;
  const Trajectory truth = WindingDrive(40);
  WriteKittiPoses(dir / "truth.txt", truth);
  std::vector<double> times;
  for (const auto& p : truth) times.push_back(p.timestamp);
  WriteTimes(dir / "times.txt", times);
  Trajectory gap = truth;
  gap.erase(gap.begin() + 1);  // frame 1 left out, as trajectory.kitti did for an untracked frame
  WriteKittiPoses(dir / "gap.txt", gap);
  EXPECT_INPUT_ERROR(EvaluateTrajectoryFiles(dir / "gap.txt", dir / "truth.txt", std::nullopt), "gap.txt",
                     "holds 39 poses", "truth.txt has 40", "line i is frame i");
  EXPECT_INPUT_ERROR(EvaluateTrajectoryFiles(dir / "gap.txt", dir / "truth.txt", dir / "times.txt"),
                     "holds 39 poses");
  // The frames of a partial run: lines 0..9 are frames 10..19 of the ground truth.
  const Trajectory partial(truth.begin() + 10, truth.begin() + 20);
  WriteKittiPoses(dir / "part.txt", partial);
  EXPECT_INPUT_ERROR(EvaluateTrajectoryFiles(dir / "part.txt", dir / "truth.txt", std::nullopt), "holds 10 poses");
  const TrajectoryEvaluation result =
      EvaluateTrajectoryFiles(dir / "part.txt", dir / "truth.txt", std::nullopt, {}, FrameRange{10, 20});
  EXPECT_EQ(result.matched, 10u);
  EXPECT_LT(result.ate.rmse, 1e-6);
  const TrajectoryEvaluation timed =
      EvaluateTrajectoryFiles(dir / "part.txt", dir / "truth.txt", dir / "times.txt", {}, FrameRange{10, 20});
  EXPECT_EQ(timed.matched, 10u);
  EXPECT_LT(timed.ate.rmse, 1e-6);
  EXPECT_INPUT_ERROR(
      EvaluateTrajectoryFiles(dir / "part.txt", dir / "truth.txt", std::nullopt, {}, FrameRange{35, 45}),
      "truth.txt", "frames 35:45", "only 40 frames");
}

TEST(EvalOptions, Check) {
  EvalOptions options;
  EXPECT_NO_THROW(options.Check());
  options.max_dt = -1;
  EXPECT_THROW(options.Check(), InvalidArgument);
  options = {};
  options.kitti_step = 0;
  EXPECT_THROW(options.Check(), InvalidArgument);
  EXPECT_EQ(ParseAlignment("se3"), Alignment::kSe3);
  EXPECT_EQ(AlignmentName(Alignment::kSim3), "sim3");
  EXPECT_THROW(ParseAlignment("affine"), InvalidArgument);
}

}  // namespace
}  // namespace semslam
