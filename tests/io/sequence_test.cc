#include "semslam/io/sequence.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <opencv2/core.hpp>

#include "semslam/core/error.h"
#include "semslam/io/image_folder.h"
#include "semslam/io/kitti_odometry.h"
#include "semslam/io/kitti_raw.h"
#include "semslam/io/trajectory_io.h"
#include "support/test_support.h"
#include "test_files.h"

namespace semslam {
namespace {

namespace fs = std::filesystem;
using testing::WriteText;

cv::Mat Pattern(int width, int height, int seed) {
  cv::Mat image(height, width, CV_8UC1);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x)
      image.at<uchar>(y, x) = static_cast<uchar>((x * 3 + y * 5 + seed * 17) % 256);
  }
  return image;
}

StereoRig SmallRig() {
  StereoRig rig;
  rig.left.width = 64;
  rig.left.height = 48;
  rig.left.fx = rig.left.fy = 50.0;
  rig.left.cx = 31.5;
  rig.left.cy = 23.5;
  rig.baseline = 0.5;
  return rig;
}

Trajectory StraightDrive(const std::vector<double>& times) {
  Trajectory t;
  for (size_t i = 0; i < times.size(); ++i)
    t.push_back({times[i], Rigid3d(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0, 0, 1.0 * i))});
  return t;
}

// Writes what the synthetic city writes:
// DIR/sequences/00/{image_0,image_1,label_0,depth_0,calib.txt,times.txt} and DIR/poses/00.txt.
void WriteSyntheticLayout(const fs::path& root, int frames, int extra_times = 0, int extra_poses = 0) {
  const fs::path seq = root / "sequences" / "00";
  const StereoRig rig = SmallRig();
  for (int i = 0; i < frames; ++i) {
    WritePng(seq / "image_0" / fmt::format("{:06d}.png", i), Pattern(64, 48, i));
    WritePng(seq / "image_1" / fmt::format("{:06d}.png", i), Pattern(64, 48, 100 + i));
    WritePng(seq / "label_0" / fmt::format("{:06d}.png", i), cv::Mat(48, 64, CV_8UC1, cv::Scalar(2)));
    WritePng(seq / "depth_0" / fmt::format("{:06d}.png", i), cv::Mat(48, 64, CV_16UC1, cv::Scalar(2560)));
  }
  WriteKittiCalibration(seq / "calib.txt", MakeKittiCalibration(rig));
  std::vector<double> times;
  for (int i = 0; i < frames + extra_times; ++i) times.push_back(0.1 * i);
  WriteTimes(seq / "times.txt", times);
  WriteKittiPoses(root / "poses" / "00.txt",
                  StraightDrive(std::vector<double>(
                      times.begin(), times.begin() + frames + std::min(extra_times, extra_poses))));
}

TEST(KittiOdometrySequence, RealSequence07MonocularWithMoreTimesThanImages) {
  SEMSLAM_REQUIRE_SHARED_DATA(data, "kitti_odom_07_3dv");
  const auto seq = OpenSequence(data / "sequences/07");
  EXPECT_EQ(seq->name(), "07");
  ASSERT_EQ(seq->size(), 160u);  // times.txt lists 1101 stamps
  EXPECT_EQ(seq->camera().width, 1226);
  EXPECT_EQ(seq->camera().height, 370);
  EXPECT_DOUBLE_EQ(seq->camera().fx, 707.0912);
  EXPECT_DOUBLE_EQ(seq->camera().cy, 183.1104);
  EXPECT_FALSE(seq->stereo().has_value());  // P1 is there but image_1/ is not
  EXPECT_DOUBLE_EQ(seq->Timestamp(11), 1.142127);
  const cv::Mat image = seq->LoadImage(159);
  EXPECT_EQ(image.type(), CV_8UC1);
  EXPECT_EQ(image.cols, 1226);
  EXPECT_EQ(image.rows, 370);
  EXPECT_THROW(seq->LoadImage(0, 1), InvalidArgument);
  EXPECT_THROW(seq->LoadImage(160), InvalidArgument);
  const auto truth = seq->GroundTruth();
  ASSERT_TRUE(truth.has_value());
  ASSERT_EQ(truth->size(), 160u);  // poses/07.txt has 1101 lines
  EXPECT_DOUBLE_EQ((*truth)[11].timestamp, 1.142127);
  EXPECT_NEAR((*truth)[159].world_from_camera.translation.x(), -76.96463, 1e-5);
  EXPECT_NEAR(PathLength(*truth), 90.6, 0.1);
  EXPECT_FALSE(seq->LabelDirectory().has_value());

  // The dataset root (holding sequences/07 only) opens the same sequence.
  const auto from_root = OpenSequence(data);
  EXPECT_EQ(from_root->name(), "07");
  EXPECT_EQ(from_root->size(), 160u);
}

TEST(KittiOdometrySequence, RealSequence00Stereo) {
  SEMSLAM_REQUIRE_SHARED_DATA(data, "kitti_odom_00_pyslam");
  const auto seq = OpenSequence(data / "sequences/00/");
  EXPECT_EQ(seq->name(), "00");
  ASSERT_EQ(seq->size(), 5u);
  ASSERT_TRUE(seq->stereo().has_value());
  EXPECT_NEAR(seq->stereo()->baseline, 386.1448 / 718.856, 1e-12);
  EXPECT_EQ(seq->camera().width, 1241);
  EXPECT_EQ(seq->camera().height, 376);
  const cv::Mat right = seq->LoadImage(4, 1);
  EXPECT_EQ(right.cols, 1241);
  EXPECT_EQ(right.rows, 376);
  EXPECT_NEAR(seq->Timestamp(4), 0.4146532, 1e-12);
  ASSERT_TRUE(seq->GroundTruth().has_value());
  EXPECT_EQ(seq->GroundTruth()->size(), 5u);
}

TEST(KittiOdometrySequence, SyntheticCityLayoutOpensFromRootOrSequence) {
  testing::TempDir dir;
  WriteSyntheticLayout(dir.path(), 4, 3, 2);
  for (const fs::path& path : {dir.path(), dir / "sequences/00", dir / "sequences/00/."}) {
    const auto seq = OpenSequence(path);
    EXPECT_EQ(seq->name(), "00") << path;
    ASSERT_EQ(seq->size(), 4u);
    ASSERT_TRUE(seq->stereo().has_value());
    EXPECT_DOUBLE_EQ(seq->stereo()->baseline, 0.5);
    EXPECT_EQ(seq->camera().width, 64);
    EXPECT_DOUBLE_EQ(seq->camera().fx, 50.0);
    ASSERT_TRUE(seq->LabelDirectory().has_value());
    EXPECT_EQ(*seq->LabelDirectory(), seq->directory() / "label_0");
    ASSERT_TRUE(seq->DepthDirectory().has_value());
    EXPECT_EQ(*seq->DepthDirectory(), seq->directory() / "depth_0");
    ASSERT_TRUE(seq->GroundTruth().has_value());
    EXPECT_EQ(seq->GroundTruth()->size(), 4u);
    EXPECT_DOUBLE_EQ(seq->GroundTruth()->at(3).world_from_camera.translation.z(), 3.0);
    EXPECT_EQ(cv::norm(seq->LoadImage(2, 0), Pattern(64, 48, 2), cv::NORM_INF), 0.0);
    EXPECT_EQ(cv::norm(seq->LoadImage(3, 1), Pattern(64, 48, 103), cv::NORM_INF), 0.0);
  }
}

TEST(KittiOdometrySequence, BrokenSequencesAreReportedWithTheFile) {
  testing::TempDir dir;
  const fs::path seq = dir / "sequences/00";
  WriteSyntheticLayout(dir.path(), 4);
  // Fewer stamps than images.
  WriteTimes(seq / "times.txt", {0.0, 0.1, 0.2});
  EXPECT_INPUT_ERROR(OpenSequence(seq), "times.txt", "lists 3 timestamps, fewer than the 4 images");
  WriteTimes(seq / "times.txt", {0.0, 0.1, 0.2, 0.3});
  // Fewer poses than images.
  WriteKittiPoses(dir / "poses/00.txt", StraightDrive({0.0, 0.1}));
  EXPECT_INPUT_ERROR(OpenSequence(seq), "00.txt", "holds 2 poses, fewer than the 4 images");
  fs::remove(dir / "poses/00.txt");
  EXPECT_FALSE(OpenSequence(seq)->GroundTruth().has_value());
  // An image of another size, and a corrupt one, are reported when loaded.
  WritePng(seq / "image_0/000002.png", Pattern(60, 48, 2));
  WriteText(seq / "image_1/000001.png", "garbage");
  const auto opened = OpenSequence(seq);
  EXPECT_INPUT_ERROR(opened->LoadImage(2), "000002.png", "60x48", "expected 64x48");
  EXPECT_INPUT_ERROR(opened->LoadImage(1, 1), "image_1/000001.png", "cannot decode");
  // A gap in the numbering.
  fs::remove(seq / "image_0/000001.png");
  EXPECT_INPUT_ERROR(OpenSequence(seq), "image_0/000001.png", "missing");
  // No calibration.
  WritePng(seq / "image_0/000001.png", Pattern(64, 48, 1));
  fs::remove(seq / "calib.txt");
  EXPECT_INPUT_ERROR(OpenSequence(seq), "calib.txt", "not found");
}

// A KITTI odometry folder with all four cameras: the colour pair 2/3 sits 6 cm left of the grey pair and
// 1 cm ahead of it (P2/P3 carry the offset as KITTI's do), with a baseline of 0.48 m.
fs::path WriteFourCameraLayout(const fs::path& root, int frames) {
  WriteSyntheticLayout(root, frames);
  const fs::path seq = root / "sequences" / "00";
  for (int i = 0; i < frames; ++i) {
    cv::Mat color(48, 64, CV_8UC3, cv::Scalar(200, 90, 20));
    color.setTo(cv::Scalar(10, 60, 250), Pattern(64, 48, i) > 128);
    WritePng(seq / "image_2" / fmt::format("{:06d}.png", i), color);
    WritePng(seq / "image_3" / fmt::format("{:06d}.png", i), Pattern(64, 48, 200 + i));
  }
  KittiCalibration calibration = MakeKittiCalibration(SmallRig());
  const Eigen::Vector3d t2(0.06, 0.0, 0.01), t3(0.06 - 0.48, 0.0, 0.01);  // camera_k from camera 0
  calibration.projection[2].col(3) = SmallRig().left.K() * t2;
  calibration.projection[3].col(3) = SmallRig().left.K() * t3;
  WriteKittiCalibration(seq / "calib.txt", calibration);
  return seq;
}

TEST(KittiOdometrySequence, CameraChoice) {
  testing::TempDir dir;
  const fs::path seq = WriteFourCameraLayout(dir.path(), 3);
  const auto grey = OpenSequence(seq);
  EXPECT_EQ(grey->camera_name(), "image_0");
  EXPECT_FALSE(grey->IsColor());
  EXPECT_DOUBLE_EQ(grey->stereo()->baseline, 0.5);

  const auto color = OpenSequence(dir.path(), {"image_2", true});
  EXPECT_EQ(color->camera_name(), "image_2");
  EXPECT_TRUE(color->IsColor());
  ASSERT_TRUE(color->stereo().has_value());
  EXPECT_NEAR(color->stereo()->baseline, 0.48, 1e-12);
  EXPECT_EQ(color->LoadColorImage(1).type(), CV_8UC3);
  EXPECT_EQ(cv::norm(color->LoadImage(1, 0), GreyFromColor(color->LoadColorImage(1)), cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(color->LoadImage(2, 1), Pattern(64, 48, 202), cv::NORM_INF), 0.0);
  EXPECT_FALSE(color->LabelDirectory().has_value());  // the labels are camera 0's
  // The poses are camera 0's (straight ahead, 1 m a frame): camera 2's in its own first frame are the same
  // here, the offset cancelling on a straight drive without rotation.
  ASSERT_TRUE(color->GroundTruth().has_value());
  EXPECT_LT((color->GroundTruth()->at(2).world_from_camera.translation - Eigen::Vector3d(0, 0, 2)).norm(),
            1e-12);

  const auto right = OpenSequence(seq, {"image_3", false});
  EXPECT_FALSE(right->stereo().has_value());
  EXPECT_FALSE(right->IsColor());
  EXPECT_INPUT_ERROR(OpenSequence(seq, {"image_3", true}), "image_3", "right camera", "image_2");
  EXPECT_INPUT_ERROR(OpenSequence(seq, {"image_02", false}), "no camera 'image_02'", "image_0..image_3");
  fs::remove_all(seq / "image_3");
  EXPECT_FALSE(OpenSequence(seq, {"image_2", false})->stereo().has_value());
  EXPECT_INPUT_ERROR(OpenSequence(seq, {"image_2", true}), "image_3", "folder not found", "stereo");
  fs::remove_all(seq / "image_2");
  EXPECT_INPUT_ERROR(OpenSequence(seq, {"image_2", false}), "image_2", "folder not found");
}

TEST(KittiOdometrySequence, CameraOffsetMovesTheGroundTruth) {
  testing::TempDir dir;
  const fs::path seq = WriteFourCameraLayout(dir.path(), 2);
  // Camera 0 turns 90 deg left (about -y) while it moves 1 m ahead.
  Trajectory turn = StraightDrive({0.0, 0.1});
  turn[1].world_from_camera.rotation = Eigen::AngleAxisd(-M_PI / 2, Eigen::Vector3d::UnitY());
  WriteKittiPoses(dir / "poses/00.txt", turn);
  const Trajectory truth = *OpenSequence(seq, {"image_2", false})->GroundTruth();
  // Camera 2 is at (-0.06, 0, -0.01) in camera 0's frame; after the turn at (0.01, 0, 1 - 0.06) in the first
  // camera 0's frame, that is (0.07, 0, 0.95) from where it started.
  const Eigen::Vector3d camera2_in_camera0(-0.06, 0.0, -0.01);
  const Eigen::Vector3d after = turn[1].world_from_camera * camera2_in_camera0 - camera2_in_camera0;
  EXPECT_LT((truth[1].world_from_camera.translation - after).norm(), 1e-9);
  EXPECT_NEAR(after.x(), 0.07, 1e-9);
  EXPECT_NEAR(after.z(), 0.95, 1e-9);
}

TEST(OpenSequence, ImageFoldersHaveNoCameraChoice) {
  testing::TempDir dir;
  WritePng(dir / "0.png", Pattern(40, 20, 0));
  WriteText(dir / "camera.yaml", "fx: 30\nfy: 30\ncx: 19.5\ncy: 9.5\n");
  EXPECT_EQ(OpenSequence(dir.path())->camera_name(), "");
  EXPECT_INPUT_ERROR(OpenSequence(dir.path(), {"image_02", false}), "camera.yaml", "one camera", "image_02");
}

TEST(OpenSequence, ExplainsWhatWasExpected) {
  testing::TempDir dir;
  EXPECT_INPUT_ERROR(OpenSequence(dir / "nowhere"), "nowhere", "not found", "KITTI odometry", "camera.yaml");
  fs::create_directories(dir / "empty");
  EXPECT_INPUT_ERROR(OpenSequence(dir / "empty"), "empty", "not a sequence folder", "image_0/",
                     "image_00/data/", "camera.yaml");
  WriteText(dir / "notes.txt", "hello");
  EXPECT_INPUT_ERROR(OpenSequence(dir / "notes.txt"), "notes.txt", "is a file");
  WriteSyntheticLayout(dir / "two", 2);
  fs::create_directories(dir / "two/sequences/01/image_0");
  EXPECT_INPUT_ERROR(OpenSequence(dir / "two"), "holds 2 sequences", "sequences/00", "sequences/01");
}

// A KITTI raw drive with three stereo frames, written by the test: calibration in the date folder.
void WriteTinyRawDrive(const fs::path& date_dir, bool calib_in_drive) {
  const fs::path drive = date_dir / "2011_09_26_drive_0042_sync";
  for (int i = 0; i < 3; ++i) {
    WritePng(drive / "image_00/data" / fmt::format("{:010d}.png", i), Pattern(80, 30, i));
    WritePng(drive / "image_01/data" / fmt::format("{:010d}.png", i), Pattern(80, 30, 50 + i));
  }
  WriteText(drive / "image_00/timestamps.txt",
            "2011-09-26 13:02:25.967790592\n2011-09-26 13:02:26.070920448\n2011-09-26 13:02:26.174361088\n"
            "2011-09-26 13:02:26.277801728\n");
  WriteText((calib_in_drive ? drive : date_dir) / "calib_cam_to_cam.txt",
            "calib_time: 09-Jan-2012 13:57:47\n"
            "S_rect_00: 8.000000e+01 3.000000e+01\n"
            "R_rect_00: 1 0 0 0 1 0 0 0 1\n"
            "P_rect_00: 7.215377e+01 0 4.0e+01 0 0 7.215377e+01 1.5e+01 0 0 0 1 0\n"
            "P_rect_01: 7.215377e+01 0 4.0e+01 -3.875744e+01 0 7.215377e+01 1.5e+01 0 0 0 1 0\n");
}

TEST(KittiRawSequence, TinyStereoDrive) {
  for (const bool calib_in_drive : {false, true}) {
    testing::TempDir dir;
    WriteTinyRawDrive(dir / "2011_09_26", calib_in_drive);
    const auto seq = OpenSequence(dir / "2011_09_26/2011_09_26_drive_0042_sync");
    EXPECT_EQ(seq->name(), "2011_09_26_drive_0042_sync");
    ASSERT_EQ(seq->size(), 3u);  // four stamps, three images
    EXPECT_NEAR(seq->Timestamp(0), 1317042145.967790592, 1e-6);
    EXPECT_NEAR(seq->Timestamp(2) - seq->Timestamp(0), 0.206570496, 1e-6);
    EXPECT_DOUBLE_EQ(seq->camera().fx, 72.15377);
    EXPECT_EQ(seq->camera().width, 80);
    ASSERT_TRUE(seq->stereo().has_value());
    EXPECT_NEAR(seq->stereo()->baseline, 0.5371506, 1e-6);
    EXPECT_EQ(cv::norm(seq->LoadImage(1, 1), Pattern(80, 30, 51), cv::NORM_INF), 0.0);
    EXPECT_FALSE(seq->GroundTruth().has_value());
  }
}

TEST(KittiRawSequence, ErrorsNameTheFile) {
  testing::TempDir dir;
  WriteTinyRawDrive(dir / "d", false);
  const fs::path drive = dir / "d/2011_09_26_drive_0042_sync";
  WriteText(
      dir / "d/calib_cam_to_cam.txt",
      "S_rect_00: 80 31\nP_rect_00: 72 0 40 0 0 72 15 0 0 0 1 0\nP_rect_01: 72 0 40 -36 0 72 15 0 0 0 1 0\n");
  EXPECT_INPUT_ERROR(OpenSequence(drive), "0000000000.png", "80x30", "80x31");
  WriteText(dir / "d/calib_cam_to_cam.txt", "S_rect_00: 80 30\nP_rect_00: 72 0 40 0 0 72 15 0 0 0 1 0\n");
  EXPECT_INPUT_ERROR(OpenSequence(drive), "calib_cam_to_cam.txt", "P_rect_01", "missing");
  fs::remove(dir / "d/calib_cam_to_cam.txt");
  EXPECT_INPUT_ERROR(OpenSequence(drive), "calib_cam_to_cam.txt", "not found", "parent");
}

TEST(KittiRawSequence, RealDriveWithoutImages) {
  SEMSLAM_REQUIRE_SHARED_DATA(data, "kitti_raw_2011_09_26_drive_0001_oxts");
  const fs::path drive = data / "2011_09_26_drive_0001_sync";
  EXPECT_INPUT_ERROR(OpenSequence(drive), "image_00/data", "not found");
  EXPECT_TRUE(
      fs::equivalent(FindKittiRawCalibFile(drive, "calib_velo_to_cam.txt"), data / "calib_velo_to_cam.txt"));
  // IMU x (forward) is the camera's z (forward), IMU z (up) its -y. The IMU sits 1.08 m behind the camera and
  // 0.72 m below it (KITTI's setup drawing: camera 1.65 m, OXTS 0.93 m above the ground).
  const Rigid3d cam_from_imu = ReadKittiRawRectifiedCam0FromImu(drive);
  EXPECT_NEAR((cam_from_imu.rotation * Eigen::Vector3d::UnitX()).z(), 1.0, 0.01);
  EXPECT_NEAR((cam_from_imu.rotation * Eigen::Vector3d::UnitZ()).y(), -1.0, 0.01);
  const Eigen::Vector3d imu_in_cam = cam_from_imu.translation;
  EXPECT_NEAR(imu_in_cam.z(), -1.08, 0.03);  // 0.27 m (camera to Velodyne) + 0.81 m (Velodyne to OXTS)
  EXPECT_NEAR(imu_in_cam.y(), 0.72, 0.03);
}

TEST(ImageFolderSequence, NaturalOrderTimesAndStereo) {
  testing::TempDir dir;
  const std::vector<std::string> names = {"img10.png", "img2.png", "img1.jpg"};
  for (size_t i = 0; i < names.size(); ++i) {
    WritePng(dir / "left" / names[i], Pattern(40, 20, static_cast<int>(i)));
    WritePng(dir / "right" / names[i], Pattern(40, 20, 10 + static_cast<int>(i)));
  }
  WriteText(dir / "left/notes.txt", "not an image");
  WriteTimes(dir / "times.txt", {5.0, 5.5, 6.0, 6.5});
  WriteText(dir / "camera.yaml",
            "# a test camera\nfx: 30\nfy: 31\ncx: 19.5\ncy: 9.5\nwidth: 40\nheight: 20\n"
            "baseline: 0.25\nright_images: right\nimages: left\ntimes: times.txt\nname: tiny\n");
  const auto seq = OpenSequence(dir.path());
  EXPECT_EQ(seq->name(), "tiny");
  ASSERT_EQ(seq->size(), 3u);
  // img1 (written third), img2 (second), img10 (first).
  EXPECT_EQ(cv::norm(seq->LoadImage(0), Pattern(40, 20, 2), cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(seq->LoadImage(1), Pattern(40, 20, 1), cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(seq->LoadImage(2, 1), Pattern(40, 20, 10), cv::NORM_INF), 0.0);
  EXPECT_DOUBLE_EQ(seq->Timestamp(2), 6.0);
  EXPECT_DOUBLE_EQ(seq->camera().fy, 31.0);
  ASSERT_TRUE(seq->stereo().has_value());
  EXPECT_DOUBLE_EQ(seq->stereo()->baseline, 0.25);

  // The YAML file itself opens the same folder; written back by WriteCameraYaml it reads the same.
  const CameraYaml config = ReadCameraYaml(dir / "camera.yaml");
  WriteCameraYaml(dir / "copy.yaml", config);
  const CameraYaml again = ReadCameraYaml(dir / "copy.yaml");
  EXPECT_EQ(again.images, config.images);
  EXPECT_EQ(again.right_images, config.right_images);
  EXPECT_EQ(again.times, config.times);
  EXPECT_EQ(again.name, config.name);
  EXPECT_EQ(again.camera.width, 40);
  EXPECT_EQ(OpenSequence(dir / "copy.yaml")->size(), 3u);
}

TEST(ImageFolderSequence, ImagesBesideTheYamlWithFpsAndDistortion) {
  testing::TempDir dir;
  for (int i = 0; i < 3; ++i) WritePng(dir / fmt::format("{:04d}.png", i), Pattern(40, 20, i));
  WriteText(dir / "camera.yaml", "fx: 30\nfy: 30\ncx: 20\ncy: 10\nfps: 4\nk1: -0.1\np2: 0.001\n");
  const auto seq = OpenSequence(dir / "camera.yaml");
  ASSERT_EQ(seq->size(), 3u);
  EXPECT_DOUBLE_EQ(seq->Timestamp(2), 0.5);
  EXPECT_DOUBLE_EQ(seq->camera().distortion.k1, -0.1);
  EXPECT_DOUBLE_EQ(seq->camera().distortion.p2, 0.001);
  EXPECT_EQ(seq->camera().width, 40);  // from the first image
  EXPECT_FALSE(seq->stereo().has_value());
  WriteText(dir / "camera.yaml", "fx: 30\nfy: 30\ncx: 20\ncy: 10\n");
  EXPECT_DOUBLE_EQ(OpenSequence(dir.path())->Timestamp(2), 0.2);  // 10 Hz by default
}

TEST(ImageFolderSequence, AFirstImageOfAnotherSizeThanTheRestIsRefused) {
  testing::TempDir dir;
  WritePng(dir / "0000.png", Pattern(51, 37, 0));
  for (int i = 1; i < 4; ++i) WritePng(dir / fmt::format("{:04d}.png", i), Pattern(40, 20, i));
  WriteText(dir / "camera.yaml", "fx: 30\nfy: 30\ncx: 20\ncy: 10\n");
  EXPECT_INPUT_ERROR(OpenSequence(dir.path()), "0000.png", "51x37", "0001.png and 0003.png", "40x20");
  // One odd frame later on is a bad frame of the run, not a bad sequence.
  WritePng(dir / "0000.png", Pattern(40, 20, 0));
  WritePng(dir / "0003.png", Pattern(51, 37, 3));
  EXPECT_EQ(OpenSequence(dir.path())->camera().width, 40);
}

TEST(ImageFolderSequence, MalformedCameraFilesNameFileLineAndKey) {
  testing::TempDir dir;
  WritePng(dir / "0.png", Pattern(40, 20, 0));
  const fs::path yaml = dir / "camera.yaml";
  WriteText(yaml, "fx: 30\nfy: [30\ncx: 20\n");
  EXPECT_INPUT_ERROR(ReadCameraYaml(yaml), "camera.yaml:", "malformed YAML");
  WriteText(yaml, "fx: 30\nfy: 30\ncx: 20\ncy: 10\nfocal: 3\n");
  EXPECT_INPUT_ERROR(ReadCameraYaml(yaml), "camera.yaml:5", "'focal'", "unknown key");
  WriteText(yaml, "fx: 30\nfy: thirty\ncx: 20\ncy: 10\n");
  EXPECT_INPUT_ERROR(ReadCameraYaml(yaml), "camera.yaml:2", "'fy'", "expected a number");
  WriteText(yaml, "fx: 30\nfy: 30\ncx: 20\n");
  EXPECT_INPUT_ERROR(ReadCameraYaml(yaml), "camera.yaml", "'cy'", "missing");
  WriteText(yaml, "fx: 30\nfy: 30\ncx: 20\ncy: 10\nbaseline: 0.5\n");
  EXPECT_INPUT_ERROR(ReadCameraYaml(yaml), "camera.yaml:5", "'baseline'", "right_images");
  WriteText(yaml, "fx: 30\nfy: 30\ncx: 20\ncy: 10\nwidth: 40\nheight: 21\n");
  EXPECT_INPUT_ERROR(OpenSequence(dir.path()), "0.png", "40x20", "40x21");
  WriteText(yaml, "fx: 30\nfy: 30\ncx: 20\ncy: 10\nwidth: 40.5\nheight: 20\n");
  EXPECT_INPUT_ERROR(ReadCameraYaml(yaml), "camera.yaml:5", "'width'", "integer");
  WriteText(yaml, "- fx\n- fy\n");
  EXPECT_INPUT_ERROR(ReadCameraYaml(yaml), "camera.yaml", "mapping");
  WriteText(yaml, "fx: 30\nfy: 30\ncx: 20\ncy: 10\ntimes: missing.txt\n");
  EXPECT_INPUT_ERROR(OpenSequence(dir.path()), "missing.txt", "not found");
  // Distortion that folds the image's corners back: the file and the coefficients, not an internal error.
  WriteText(yaml, "fx: 30\nfy: 30\ncx: 20\ncy: 10\nk1: -0.9\n");
  EXPECT_INPUT_ERROR(OpenSequence(dir.path()), "camera.yaml", "'k1, k2, p1, p2, k3'",
                     "does not map the 40x20");
}

}  // namespace
}  // namespace semslam
