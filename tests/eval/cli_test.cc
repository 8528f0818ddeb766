// `semslam eval` end to end through the built binary.

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "semslam/eval/trajectory_metrics.h"
#include "semslam/io/trajectory_io.h"
#include "support/test_support.h"

namespace semslam {
namespace {

using testing::CommandResult;
using testing::RunSemslam;

Trajectory Drive(int n) {
  Trajectory t;
  for (int i = 0; i < n; ++i) {
    const double s = 1.5 * i;
    t.push_back({0.1 * i, Rigid3d(Eigen::Quaterniond(Eigen::AngleAxisd(0.01 * i, Eigen::Vector3d::UnitY())),
                                  Eigen::Vector3d(10 * std::sin(s / 30), 0.2 * std::cos(s / 7), s))});
  }
  return t;
}

class EvalCli : public ::testing::Test {
 protected:
  void SetUp() override { SEMSLAM_REQUIRE_BINARY(); }
  testing::TempDir dir_;
};

TEST_F(EvalCli, PrintsJsonWithTheMetrics) {
  const Trajectory truth = Drive(120);  // ~178 m
  Trajectory estimate = truth;
  for (auto& p : estimate) p.world_from_camera.translation += Eigen::Vector3d(0.3, 0.0, 0.4);
  WriteTumTrajectory(dir_ / "truth.tum", truth);
  WriteTumTrajectory(dir_ / "estimate.tum", estimate);
  const CommandResult r = RunSemslam({"eval", "--estimate", (dir_ / "estimate.tum").string(), "--truth",
                                      (dir_ / "truth.tum").string(), "--align", "none"});
  ASSERT_EQ(r.exit_code, 0) << r.Describe();
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_NEAR(j.at("ate_rmse").get<double>(), 0.5, 1e-6);
  EXPECT_NEAR(j.at("ate_max").get<double>(), 0.5, 1e-6);
  EXPECT_EQ(j.at("alignment"), "none");
  EXPECT_EQ(j.at("matched"), 120);
  EXPECT_EQ(j.at("estimate_poses"), 120);
  EXPECT_EQ(j.at("truth_poses"), 120);
  EXPECT_DOUBLE_EQ(j.at("scale").get<double>(), 1.0);
  EXPECT_GT(j.at("path_length_m").get<double>(), 150.0);
  EXPECT_NEAR(j.at("rpe_trans_rmse_m").get<double>(), 0.0, 1e-6);
  EXPECT_NEAR(j.at("kitti_trans_pct").get<double>(), 0.0, 1e-6);
  ASSERT_TRUE(j.at("kitti_segments").is_array());
  ASSERT_EQ(j.at("kitti_segments").size(), 1u);  // only 100 m fits
  EXPECT_EQ(j.at("kitti_segments")[0].at("length_m"), 100.0);
  for (const char* key : {"ate_mean", "ate_median", "ate_std", "rpe_rot_rmse_deg", "kitti_rot_deg_per_100m",
                          "rpe_100m_trans_rmse_m"}) {
    EXPECT_TRUE(j.contains(key)) << key;
  }

  // Sim(3) by default: a scaled copy has zero error and scale 1 / 2.
  Trajectory scaled = truth;
  for (auto& p : scaled) p.world_from_camera.translation *= 2.0;
  WriteTumTrajectory(dir_ / "scaled.tum", scaled);
  const CommandResult rs = RunSemslam(
      {"eval", "--estimate", (dir_ / "scaled.tum").string(), "--truth", (dir_ / "truth.tum").string()});
  ASSERT_EQ(rs.exit_code, 0) << rs.Describe();
  const nlohmann::json s = nlohmann::json::parse(rs.out);
  EXPECT_NEAR(s.at("ate_rmse").get<double>(), 0.0, 1e-6);
  EXPECT_NEAR(s.at("scale").get<double>(), 0.5, 1e-9);
}

TEST_F(EvalCli, KittiPosesWithTimesAndShortPathsGiveNullKittiErrors) {
  const Trajectory truth = Drive(40);  // ~58 m
  WriteKittiPoses(dir_ / "truth.txt", truth);
  WriteTumTrajectory(dir_ / "estimate.tum", truth);
  std::vector<double> times;
  for (int i = 0; i < 60; ++i) times.push_back(0.1 * i);
  WriteTimes(dir_ / "times.txt", times);
  const CommandResult r = RunSemslam({"eval", "--estimate", (dir_ / "estimate.tum").string(), "--truth",
                                      (dir_ / "truth.txt").string(), "--times", (dir_ / "times.txt").string(),
                                      "--align", "se3", "--max-dt", "0.001"});
  ASSERT_EQ(r.exit_code, 0) << r.Describe();
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j.at("matched"), 40);
  EXPECT_TRUE(j.at("kitti_trans_pct").is_null());
  EXPECT_TRUE(j.at("kitti_rot_deg_per_100m").is_null());
  EXPECT_TRUE(j.at("rpe_100m_trans_rmse_m").is_null());
  EXPECT_EQ(j.at("kitti_segments").size(), 0u);
}

TEST_F(EvalCli, ErrorsExitNonZeroWithOneLine) {
  WriteTumTrajectory(dir_ / "truth.tum", Drive(10));
  std::ofstream(dir_ / "bad.tum") << "# header\n0.0 0 0 0 0 0 0 1\n0.1 0 0 0 0 0 1\n";
  const std::string truth = (dir_ / "truth.tum").string();
  CommandResult r = RunSemslam({"eval", "--estimate", (dir_ / "bad.tum").string(), "--truth", truth});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("bad.tum:3"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;

  r = RunSemslam({"eval", "--estimate", (dir_ / "missing.tum").string(), "--truth", truth});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("missing.tum"), std::string::npos) << r.err;

  Trajectory late = Drive(10);
  for (auto& p : late) p.timestamp += 500;
  WriteTumTrajectory(dir_ / "late.tum", late);
  r = RunSemslam({"eval", "--estimate", (dir_ / "late.tum").string(), "--truth", truth});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("no estimated pose matched"), std::string::npos) << r.err;
  EXPECT_TRUE(r.out.empty());

  r = RunSemslam({"eval", "--estimate", (dir_ / "late.tum").string(), "--truth", truth, "--align", "affine"});
  EXPECT_NE(r.exit_code, 0);
}

// A KITTI raw drive as the truth: its OXTS poses for the chosen camera (io/kitti_raw.h).
TEST_F(EvalCli, RawDriveFolderAsTheTruth) {
  SEMSLAM_REQUIRE_SHARED_DATA(drive, "kitti_raw_2011_09_26_drive_0005/2011_09_26/2011_09_26_drive_0005_sync");
  const Trajectory truth = ReadSequenceGroundTruth(drive, "image_02");
  ASSERT_EQ(truth.size(), 154u);
  Trajectory scaled = truth;
  for (auto& p : scaled) p.world_from_camera.translation *= 2.0;
  WriteTumTrajectory(dir_ / "scaled.tum", scaled);
  CommandResult r = RunSemslam({"eval", "--estimate", (dir_ / "scaled.tum").string(), "--truth",
                                drive.string(), "--camera", "image_02"});
  ASSERT_EQ(r.exit_code, 0) << r.Describe();
  nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j.at("matched"), 154);
  EXPECT_NEAR(j.at("ate_rmse").get<double>(), 0.0, 1e-6);
  EXPECT_NEAR(j.at("scale").get<double>(), 0.5, 1e-9);
  EXPECT_NEAR(j.at("path_length_m").get<double>(), 69.4, 0.1);

  // The same as a KITTI pose file (what `semslam run` writes as trajectory.kitti): line i is frame i of the
  // drive, stamped from the drive itself; a line missing is refused, naming the drive.
  std::vector<Rigid3d> lines;
  for (const StampedPose& p : scaled) lines.push_back(p.world_from_camera);
  WriteKittiPoses(dir_ / "scaled.kitti", lines);
  r = RunSemslam({"eval", "--estimate", (dir_ / "scaled.kitti").string(), "--truth", drive.string(),
                  "--camera", "image_02"});
  ASSERT_EQ(r.exit_code, 0) << r.Describe();
  j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j.at("matched"), 154);
  EXPECT_NEAR(j.at("ate_rmse").get<double>(), 0.0, 1e-6);
  lines.pop_back();
  WriteKittiPoses(dir_ / "short.kitti", lines);
  r = RunSemslam({"eval", "--estimate", (dir_ / "short.kitti").string(), "--truth", drive.string(),
                  "--camera", "image_02"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("holds 153 poses but the sequence"), std::string::npos) << r.err;

  // Against camera 0's truth (frames 0-79, 6 ms later, 6 cm to the right): 80 matches, centimetres apart.
  r = RunSemslam({"eval", "--estimate", (dir_ / "scaled.tum").string(), "--truth", drive.string()});
  ASSERT_EQ(r.exit_code, 0) << r.Describe();
  j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j.at("matched"), 80);
  EXPECT_LT(j.at("ate_rmse").get<double>(), 0.05);

  // A camera that is not there, a camera with a file as the truth, a folder without a truth: one line each.
  r = RunSemslam({"eval", "--estimate", (dir_ / "scaled.tum").string(), "--truth", drive.string(), "--camera",
                  "image_03"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("image_03/data"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  r = RunSemslam({"eval", "--estimate", (dir_ / "scaled.tum").string(), "--truth",
                  (dir_ / "scaled.tum").string(), "--camera", "image_02"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("sequence folder"), std::string::npos) << r.err;
  testing::TempDir no_truth;
  std::filesystem::copy(drive.parent_path() / "calib_cam_to_cam.txt", no_truth / "calib_cam_to_cam.txt");
  std::filesystem::create_directories(no_truth / "drive/image_02");
  std::filesystem::copy(drive / "image_02/timestamps.txt", no_truth / "drive/image_02/timestamps.txt");
  std::filesystem::create_directories(no_truth / "drive/image_02/data");
  std::filesystem::copy(drive / "image_02/data/0000000000.png", no_truth / "drive/image_02/data");
  r = RunSemslam({"eval", "--estimate", (dir_ / "scaled.tum").string(), "--truth",
                  (no_truth / "drive").string(), "--camera", "image_02"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("no ground truth"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace semslam
