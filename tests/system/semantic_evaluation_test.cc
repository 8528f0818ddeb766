// The 3D label measure against a scene whose truth is known exactly: a car (depth 10 m) in front of a building
// (depth 20 m) under the sky, seen by three keyframes at the same true pose.

#include "semslam/system/semantic_evaluation.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>

#include "semslam/core/error.h"
#include "semslam/map/map.h"
#include "support/kitti_camera.h"
#include "support/test_support.h"

namespace semslam {
namespace {

constexpr int kBuilding = 2, kSky = 10, kCar = 13;
constexpr int kCarRight = 600;  // pixels u < 600 (below the sky) are the car
constexpr int kSkyBottom = 50;  // rows v < 50 are sky

std::shared_ptr<const FrameData> Keypoints(int n) {
  FeatureSet features;
  features.pyramid = PyramidGeometry::Make(8, 1.2f);
  features.image_width = 1241;
  features.image_height = 376;
  for (int i = 0; i < n; ++i) {
    Keypoint kp;
    kp.pixel = Eigen::Vector2f(20.0f + 30.0f * static_cast<float>(i), 200.0f);
    features.keypoints.push_back(kp);
    features.descriptors.push_back({});
  }
  return MakeFrameData(KittiCamera(), std::nullopt, std::move(features), {}, {});
}

// The map point that projects to pixel (u, v) at `depth` metres in front of the camera at the origin.
Eigen::Vector3d At(double u, double v, double depth) {
  const PinholeCamera c = KittiCamera();
  return {(u - c.cx) / c.fx * depth, (v - c.cy) / c.fy * depth, depth};
}

class SurfaceEvaluation3d : public ::testing::Test {
 protected:
  void SetUp() override {
    const PinholeCamera camera = KittiCamera();
    cv::Mat labels(camera.height, camera.width, CV_8UC1, cv::Scalar(kBuilding));
    cv::Mat depth(camera.height, camera.width, CV_16UC1, cv::Scalar(20 * 256));
    labels.colRange(0, kCarRight).setTo(kCar);
    depth.colRange(0, kCarRight).setTo(10 * 256);
    labels.rowRange(0, kSkyBottom).setTo(kSky);
    depth.rowRange(0, kSkyBottom).setTo(0);
    std::filesystem::create_directories(dir_ / "label_0");
    std::filesystem::create_directories(dir_ / "depth_0");
    auto lock = map_.WriteLock();
    for (std::uint64_t id = 0; id < 3; ++id) {
      ASSERT_TRUE(cv::imwrite((dir_ / "label_0" / fmt::format("{:06d}.png", id)).string(), labels));
      ASSERT_TRUE(cv::imwrite((dir_ / "depth_0" / fmt::format("{:06d}.png", id)).string(), depth));
      Frame frame(id, 0.1 * static_cast<double>(id), Keypoints(10));
      frame.SetPose(Rigid3d());
      keyframes_.push_back(map_.AddKeyFrame(frame));
      truth_.push_back({0.1 * static_cast<double>(id), Rigid3d()});
    }
  }

  // A point at pixel (u, v), `depth` metres away, seen by the first two keyframes, labelled `label` (or not).
  void AddPoint(double u, double v, double depth, int label) {
    auto lock = map_.WriteLock();
    const int index = static_cast<int>(map_.NumMapPoints());
    MapPoint* p = map_.AddMapPoint(At(u, v, depth), keyframes_[0]);
    for (int k = 0; k < 2; ++k) {
      p->AddObservation(keyframes_[static_cast<size_t>(k)], index);
      keyframes_[static_cast<size_t>(k)]->SetMapPoint(index, p);
    }
    if (label >= 0) p->labels().FuseLabel(label, 0.9f);
  }

  SurfaceTruth Truth(const Sim3d& truth_from_map = Sim3d()) const {
    return {dir_ / "label_0", dir_ / "depth_0", truth_, truth_from_map, true};
  }

  testing::TempDir dir_;
  Map map_;
  std::vector<KeyFrame*> keyframes_;
  Trajectory truth_;
};

TEST_F(SurfaceEvaluation3d, EachPointIsJudgedByTheSurfaceItLiesOn) {
  AddPoint(300, 200, 10.0, kCar);       // on the car, labelled car: right
  AddPoint(900, 200, 20.0, kCar);       // on the building, labelled car: wrong
  AddPoint(598.6, 200, 10.0, kCar);     // on the car, 1.4 px from the building: right, on a boundary
  AddPoint(300, 200, 15.0, kBuilding);  // between car and building: on no surface
  AddPoint(300, 20, 30.0, kSky);        // in the sky: no surface either
  AddPoint(900, 250, 20.0, -1);         // on the building, no label
  const SurfaceEvaluation e = EvaluateSemantics3d(map_, Truth());
  EXPECT_EQ(e.keyframes, 3u);
  EXPECT_EQ(e.per_frame.points.total_evaluated, 3u);
  EXPECT_NEAR(e.per_frame.points.Accuracy(), 2.0 / 3.0, 1e-12);
  EXPECT_EQ(e.per_frame.off_boundary.total_evaluated, 2u);
  EXPECT_NEAR(e.per_frame.off_boundary.Accuracy(), 0.5, 1e-12);
  EXPECT_EQ(e.per_frame.on_boundary.total_evaluated, 1u);
  EXPECT_NEAR(e.per_frame.on_boundary.Accuracy(), 1.0, 1e-12);
  EXPECT_EQ(e.per_frame.confusion[kBuilding][kCar], 1u);
  EXPECT_EQ(e.per_frame.confusion[kCar][kCar], 2u);
  EXPECT_EQ(e.per_frame.points_unverified, 2u);
  EXPECT_EQ(e.per_frame.points_unlabeled, 1u);
  // The map aligned with the truth at once: the same here, since the keyframes sit at their true poses.
  EXPECT_EQ(e.global.points.total_evaluated, 3u);
  EXPECT_NEAR(e.global.points.Accuracy(), 2.0 / 3.0, 1e-12);
}

TEST_F(SurfaceEvaluation3d, AGlobalAlignmentErrorMovesPointsOffTheirSurface) {
  AddPoint(300, 200, 10.0, kCar);
  AddPoint(700, 200, 20.0, kBuilding);
  // The map 4.5 m to the right of the truth: the car point now projects 323 px further right, onto the
  // building's columns, where the truth is 20 m and not 10: off every surface. The building point moves 162 px
  // and stays on the building.
  const Sim3d shifted(1.0, Eigen::Quaterniond::Identity(), Eigen::Vector3d(4.5, 0.0, 0.0));
  const SurfaceEvaluation e = EvaluateSemantics3d(map_, Truth(shifted));
  EXPECT_EQ(e.per_frame.points.total_evaluated, 2u);  // per keyframe: untouched
  EXPECT_NEAR(e.per_frame.points.Accuracy(), 1.0, 1e-12);
  EXPECT_EQ(e.global.points.total_evaluated, 1u);
  EXPECT_EQ(e.global.confusion[kBuilding][kBuilding], 1u);
  EXPECT_EQ(e.global.points_unverified, 1u);
}

TEST_F(SurfaceEvaluation3d, AMissingTruthImageIsNamed) {
  AddPoint(300, 200, 10.0, kCar);
  std::filesystem::remove(dir_ / "depth_0" / "000001.png");
  try {
    EvaluateSemantics3d(map_, Truth());
    FAIL() << "no error";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("000001.png"), std::string::npos) << error.what();
  }
  SurfaceEvaluationOptions options;
  options.depth_tolerance = 0.0;
  EXPECT_THROW(options.Check(), InvalidArgument);
}

}  // namespace
}  // namespace semslam
