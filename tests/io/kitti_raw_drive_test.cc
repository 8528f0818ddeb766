// The cameras and the OXTS ground truth of the real KITTI raw drive 2011_09_26_drive_0005 (and the OXTS
// readings of drive 0001), read in place from ../shared/data.

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/core.hpp>

#include "semslam/core/error.h"
#include "semslam/io/kitti_raw.h"
#include "semslam/io/sequence.h"
#include "support/test_support.h"
#include "test_files.h"

namespace semslam {
namespace {

namespace fs = std::filesystem;

constexpr char kDrive0005[] = "kitti_raw_2011_09_26_drive_0005/2011_09_26/2011_09_26_drive_0005_sync";
constexpr char kDrive0001[] = "kitti_raw_2011_09_26_drive_0001_oxts/2011_09_26_drive_0001_sync";

// The forward speed vf integrated over readings [first, end) (trapezoid rule on the OXTS timestamps).
double IntegratedForwardSpeed(const std::vector<StampedOxts>& readings, size_t first, size_t end) {
  double distance = 0.0;
  for (size_t i = first + 1; i < end; ++i) {
    distance += 0.5 * (readings[i].record.vf + readings[i - 1].record.vf) *
                (readings[i].timestamp - readings[i - 1].timestamp);
  }
  return distance;
}

double PathLength(const std::vector<Rigid3d>& poses) {
  double length = 0.0;
  for (size_t i = 1; i < poses.size(); ++i)
    length += (poses[i].translation - poses[i - 1].translation).norm();
  return length;
}

double AngleDeg(const Eigen::Quaterniond& q) { return Eigen::AngleAxisd(q).angle() * 180.0 / M_PI; }

TEST(KittiRawCameras, DefaultIsTheGreyStereoPair) {
  SEMSLAM_REQUIRE_SHARED_DATA(drive, kDrive0005);
  const auto seq = OpenSequence(drive);
  EXPECT_EQ(seq->camera_name(), "image_00");
  EXPECT_EQ(seq->size(), 80u);  // image_00/01 hold frames 0-79 only
  EXPECT_FALSE(seq->IsColor());
  EXPECT_TRUE(seq->LoadColorImage(0).empty());
  ASSERT_TRUE(seq->stereo().has_value());
  EXPECT_NEAR(seq->stereo()->baseline, 387.5744 / 721.5377, 1e-6);  // -P_rect_01(0,3) / fx
  EXPECT_DOUBLE_EQ(seq->camera().fx, 721.5377);
  EXPECT_EQ(seq->camera().width, 1242);
  EXPECT_EQ(seq->camera().height, 375);
  EXPECT_EQ(seq->LoadImage(0, 1).type(), CV_8UC1);
}

TEST(KittiRawCameras, ColourCameraReadsGreyForFeaturesAndBgrForTheSegmenter) {
  SEMSLAM_REQUIRE_SHARED_DATA(drive, kDrive0005);
  const auto seq = OpenSequence(drive, {"image_02", false});
  EXPECT_EQ(seq->camera_name(), "image_02");
  ASSERT_EQ(seq->size(), 154u);
  EXPECT_TRUE(seq->IsColor());
  EXPECT_FALSE(seq->stereo().has_value());  // image_03 is not in the shared copy
  // Its own timestamps (image_02 starts 6 ms before image_00).
  EXPECT_NEAR(seq->Timestamp(0) - OpenSequence(drive)->Timestamp(0), -0.006142, 1e-5);
  const cv::Mat color = seq->LoadColorImage(100);
  ASSERT_EQ(color.type(), CV_8UC3);
  EXPECT_EQ(color.cols, 1242);
  EXPECT_EQ(color.rows, 375);
  // A colour image: the channels differ somewhere.
  std::vector<cv::Mat> channels;
  cv::split(color, channels);
  EXPECT_GT(cv::norm(channels[0], channels[2], cv::NORM_L1) / color.total(), 2.0);
  const cv::Mat grey = seq->LoadImage(100, 0);
  ASSERT_EQ(grey.type(), CV_8UC1);
  EXPECT_EQ(cv::norm(grey, GreyFromColor(color), cv::NORM_INF), 0.0);
  // P_rect_02 = K [I | t]: the colour camera's principal point and focal length are camera 0's.
  EXPECT_DOUBLE_EQ(seq->camera().fx, 721.5377);
  EXPECT_DOUBLE_EQ(seq->camera().cx, 609.5593);
}

TEST(KittiRawCameras, BadChoicesNameTheFolder) {
  SEMSLAM_REQUIRE_SHARED_DATA(drive, kDrive0005);
  EXPECT_INPUT_ERROR(OpenSequence(drive, {"image_02", true}), "image_03/data", "stereo with camera image_02");
  EXPECT_INPUT_ERROR(OpenSequence(drive, {"image_01", true}), "image_01", "right camera", "image_00");
  EXPECT_INPUT_ERROR(OpenSequence(drive, {"image_03", false}), "image_03/data", "not found",
                     "image_00, image_01, image_02");
  EXPECT_INPUT_ERROR(OpenSequence(drive, {"image_2", false}), "drive_0005_sync", "image_00..image_03");
  EXPECT_INPUT_ERROR(OpenSequence(drive, {"cam0", false}), "image_00..image_03");
  // The right camera alone is a monocular camera.
  const auto right = OpenSequence(drive, {"image_01", false});
  EXPECT_EQ(right->size(), 80u);
  EXPECT_FALSE(right->stereo().has_value());
  EXPECT_EQ(cv::norm(right->LoadImage(7, 0), OpenSequence(drive)->LoadImage(7, 1), cv::NORM_INF), 0.0);
}

TEST(KittiRawTruth, DevkitPoseOfSyntheticReadings) {
  OxtsRecord a;
  a.lat = 49.0;
  a.lon = 8.4;
  a.alt = 110.0;
  OxtsRecord b = a;
  b.lat += 1e-4;  // 11.132 m north: the Mercator scale cos(lat0) makes metres at the first latitude
  b.lon += 2e-4;  // 14.607 m east (cos 49 deg * 6378137 m * 2e-4 deg in radians)
  b.alt += 1.5;
  b.yaw = M_PI / 2;  // heading north
  b.roll = 0.1;
  const double scale = OxtsMercatorScale(a.lat);
  const Rigid3d wa = OxtsWorldFromImu(a, scale), wb = OxtsWorldFromImu(b, scale);
  const Eigen::Vector3d delta = wb.translation - wa.translation;
  EXPECT_NEAR(delta.y(), 6378137.0 * 1e-4 * M_PI / 180.0, 2e-3);
  EXPECT_NEAR(delta.x(), std::cos(49.0 * M_PI / 180.0) * 6378137.0 * 2e-4 * M_PI / 180.0, 1e-6);
  EXPECT_DOUBLE_EQ(delta.z(), 1.5);
  // R = Rz(yaw) Ry(pitch) Rx(roll): IMU forward (x) points north, and the roll tilts IMU left (y) up.
  EXPECT_NEAR((wb.rotation * Eigen::Vector3d::UnitX() - Eigen::Vector3d::UnitY()).norm(), 0.0, 1e-12);
  EXPECT_NEAR((wb.rotation * Eigen::Vector3d::UnitY()).z(), std::sin(0.1), 1e-12);

  // Camera poses: the first is the identity; a camera looking along IMU x (z forward, y down) moves along
  // its z axis when the IMU moves forward.
  const Rigid3d camera_from_imu((Eigen::Matrix3d() << 0, -1, 0, 0, 0, -1, 1, 0, 0).finished(),
                                Eigen::Vector3d(0.3, 0.7, -1.1));
  OxtsRecord c = a;
  c.lat += 1e-5;  // 1.11 m north
  a.yaw = c.yaw = M_PI / 2;
  const std::vector<Rigid3d> poses = OxtsCameraPoses({a, c}, camera_from_imu);
  ASSERT_EQ(poses.size(), 2u);
  EXPECT_LT(poses[0].translation.norm(), 1e-9);
  EXPECT_LT(AngleDeg(poses[0].rotation), 1e-9);
  EXPECT_NEAR(poses[1].translation.z(), 6378137.0 * 1e-5 * M_PI / 180.0, 1e-3);
  EXPECT_NEAR(poses[1].translation.head<2>().norm(), 0.0, 1e-6);
}

// Drive 0001 has RTK-grade positions (pos_accuracy 3 cm): the devkit poses' path agrees with the integrated
// forward speed to 0.6 % (measured 106.97 m against 107.56 m).
TEST(KittiRawTruth, PathAgreesWithForwardSpeedOnAnRtkDrive) {
  SEMSLAM_REQUIRE_SHARED_DATA(drive, kDrive0001);
  const std::vector<StampedOxts> readings = ReadOxtsFolder(drive / "oxts");
  ASSERT_EQ(readings.size(), 108u);
  std::vector<OxtsRecord> records;
  for (const StampedOxts& r : readings) records.push_back(r.record);
  const double path = PathLength(OxtsCameraPoses(records, Rigid3d()));  // the IMU's own path
  const double integrated = IntegratedForwardSpeed(readings, 0, readings.size());
  RecordProperty("path_m", std::to_string(path));
  RecordProperty("integrated_vf_m", std::to_string(integrated));
  EXPECT_NEAR(path / integrated, 1.0, 0.01) << path << " m against " << integrated << " m";
}

TEST(KittiRawTruth, Drive0005GroundTruthFollowsTheOxts) {
  SEMSLAM_REQUIRE_SHARED_DATA(drive, kDrive0005);
  const std::vector<StampedOxts> readings = ReadOxtsFolder(drive / "oxts");
  ASSERT_EQ(readings.size(), 154u);
  const auto seq = OpenSequence(drive, {"image_02", false});
  const std::optional<Trajectory> truth = seq->GroundTruth();
  ASSERT_TRUE(truth.has_value());
  ASSERT_EQ(truth->size(), 154u);
  EXPECT_DOUBLE_EQ(truth->at(5).timestamp, seq->Timestamp(5));
  EXPECT_LT(truth->front().world_from_camera.translation.norm(), 1e-9);
  EXPECT_LT(AngleDeg(truth->front().world_from_camera.rotation), 1e-9);

  std::vector<Rigid3d> poses;
  for (const StampedPose& p : *truth) poses.push_back(p.world_from_camera);
  // The GPS positions of this drive are float-grade (pos_accuracy 0.3-0.5 m, posmode 4-5): their path is
  // 2.7 % shorter than the integrated forward speed (69.4 m against 71.3 m), which stereo agrees with (see
  // tests/system). The truth is good to a few decimetres, not to a percent of path.
  const double path = PathLength(poses);
  const double integrated = IntegratedForwardSpeed(readings, 0, readings.size());
  RecordProperty("path_m", std::to_string(path));
  RecordProperty("integrated_vf_m", std::to_string(integrated));
  EXPECT_NEAR(path / integrated, 1.0, 0.04) << path << " m against " << integrated << " m";

  // The camera moves along its own z axis (forward) and about level (within the GPS altitude noise: up to
  // 3.2 deg over 1 s steps of 3-4 m): the IMU-to-camera chain is right.
  for (size_t i = 10; i < poses.size(); i += 10) {
    const Eigen::Vector3d step = (poses[i - 10].Inverse() * poses[i].translation).normalized();
    EXPECT_GT(step.z(), 0.98) << "frame " << i << ": direction " << step.transpose();
    EXPECT_LT(std::abs(step.y()), 0.07) << "frame " << i << ": direction " << step.transpose();
  }
  // The heading change over frames 0-79 (the 37 deg left turn) is the OXTS yaw change, about the camera's
  // vertical (-y) axis.
  const double yaw_change = (readings[79].record.yaw - readings[0].record.yaw) * 180.0 / M_PI;
  EXPECT_NEAR(yaw_change, 37.0, 0.5);
  const Eigen::Vector3d forward = poses[79].rotation * Eigen::Vector3d::UnitZ();
  const double turned = std::atan2(forward.x(), forward.z()) * 180.0 / M_PI;  // + to the right (x)
  EXPECT_NEAR(-turned, yaw_change, 0.5);
}

TEST(KittiRawTruth, CamerasDifferByTheirRigOffsets) {
  SEMSLAM_REQUIRE_SHARED_DATA(drive, kDrive0005);
  const Trajectory grey = *OpenSequence(drive)->GroundTruth();
  const Trajectory color = *OpenSequence(drive, {"image_02", false})->GroundTruth();
  ASSERT_EQ(grey.size(), 80u);
  // The same OXTS readings: camera 2 sits 6 cm to the left of camera 0 (P_rect_02 offset), so its positions
  // in its own first frame are camera 0's moved by the rotation of that offset.
  const Eigen::Vector3d offset(0.059849, -0.000358, 0.002746);  // camera_2 from rectified camera_0
  for (size_t i = 0; i < grey.size(); i += 13) {
    const Rigid3d& g = grey[i].world_from_camera;
    const Eigen::Vector3d expected = offset + g.translation - g.rotation * offset;
    EXPECT_LT((color[i].world_from_camera.translation - expected).norm(), 1e-4) << "frame " << i;
    EXPECT_LT(AngleDeg(color[i].world_from_camera.rotation.inverse() * g.rotation), 1e-6);
  }
}

}  // namespace
}  // namespace semslam
