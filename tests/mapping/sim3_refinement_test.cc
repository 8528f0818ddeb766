// The Sim(3) between two monocular keyframes refined by reprojection, with its scale checked against the two
// keyframes' own points. Reprojection sees the scale only through the translation between the cameras, once
// divided by it (points of keyframe 2 into image 1) and once not (points of keyframe 1 into image 2): where
// the cameras stand close together, both are small and noisy, and the refined scale can land far from the
// one the two structures give.

#include "semslam/mapping/sim3_refinement.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "semslam/core/error.h"
#include "semslam/map/map.h"
#include "support/draws.h"
#include "support/kitti_camera.h"

namespace semslam {
namespace {

using testing::DrawVector2;

// Two keyframes `baseline` metres apart sideways, each of its own map: keyframe 2's map is kMap2Scale times
// the world. Both see the same 300 points 10-40 m ahead; keypoints carry `pixel_noise` pixels of noise and
// each map's points `depth_noise` of their depth along the ray (a monocular map's triangulation).
// `keypoints2_baseline`, when given, is where keyframe 2's keypoints were seen from instead: its points and
// its image then disagree on where it stands.
class TwoMonocularKeyframes : public ::testing::Test {
 protected:
  static constexpr double kMap2Scale = 0.75;

  void Build(double baseline, double pixel_noise, double depth_noise, std::uint32_t seed,
             double keypoints2_baseline = -1.0) {
    const PinholeCamera camera = KittiCamera();
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    std::normal_distribution<double> gauss(0.0, 1.0);
    const Eigen::Vector3d center1 = Eigen::Vector3d::Zero();
    const Eigen::Vector3d center2(baseline, 0.0, 0.0);
    std::vector<Eigen::Vector3d> world;
    while (world.size() < 300) {
      const double depth = 10.0 + 30.0 * unit(rng);
      const Eigen::Vector2d xy = DrawVector2(unit, rng);
      const Eigen::Vector3d p((xy.x() - 0.5) * depth * 1.4, (xy.y() - 0.6) * depth * 0.4, depth);
      if (camera.InImage(camera.Project(p - center1)) && camera.InImage(camera.Project(p - center2)))
        world.push_back(p);
    }
    auto lock = map_.WriteLock();
    kf1_ = AddKeyFrame(0, camera, Rigid3d(Eigen::Quaterniond::Identity(), -center1), world, center1,
                       pixel_noise, rng);
    const Eigen::Vector3d seen_from2(keypoints2_baseline < 0 ? baseline : keypoints2_baseline, 0.0, 0.0);
    kf2_ = AddKeyFrame(1, camera, Rigid3d(Eigen::Quaterniond::Identity(), -kMap2Scale * center2), world,
                       seen_from2, pixel_noise, rng);
    matches12_.clear();
    for (size_t j = 0; j < world.size(); ++j) {
      AddPoint(kf1_, static_cast<int>(j), world[j], center1, 1.0, depth_noise * gauss(rng));
      matches12_.push_back(
          AddPoint(kf2_, static_cast<int>(j), world[j], center2, kMap2Scale, depth_noise * gauss(rng)));
    }
    // kf1_from_kf2: camera 2's frame of map 2, scaled up to the world, then into camera 1's.
    truth_ = Sim3d(1.0 / kMap2Scale, Eigen::Quaterniond::Identity(), center2 - center1);
  }

  KeyFrame* AddKeyFrame(std::uint64_t id, const PinholeCamera& camera, const Rigid3d& camera_from_world,
                        const std::vector<Eigen::Vector3d>& world, const Eigen::Vector3d& center,
                        double pixel_noise, std::mt19937& rng) {
    std::normal_distribution<double> gauss(0.0, pixel_noise);
    FeatureSet features;
    features.pyramid = PyramidGeometry::Make(8, 1.2f);
    features.image_width = camera.width;
    features.image_height = camera.height;
    for (const Eigen::Vector3d& p : world) {
      const Eigen::Vector2d pixel = camera.Project(p - center);
      Keypoint kp;
      const Eigen::Vector2d noise = DrawVector2(gauss, rng);
      kp.pixel = Eigen::Vector2f(static_cast<float>(pixel.x() + noise.x()),
                                 static_cast<float>(pixel.y() + noise.y()));
      features.keypoints.push_back(kp);
      features.descriptors.push_back({});
    }
    Frame frame(id, 0.1 * static_cast<double>(id),
                MakeFrameData(camera, std::nullopt, std::move(features), {}, {}));
    frame.SetPose(camera_from_world);
    return map_.AddKeyFrame(frame);
  }

  // The world point as the keyframe's map holds it: its own scale, moved along the ray by `depth_error`.
  MapPoint* AddPoint(KeyFrame* kf, int slot, const Eigen::Vector3d& world, const Eigen::Vector3d& center,
                     double scale, double depth_error) {
    const Eigen::Vector3d in_map = scale * (center + (1.0 + depth_error) * (world - center));
    MapPoint* p = map_.AddMapPoint(in_map, kf);
    kf->SetMapPoint(slot, p);
    p->AddObservation(kf, slot);
    return p;
  }

  double DepthRatio(const Sim3d& kf1_from_kf2) const {
    return StructureDepthRatio(*kf1_, *kf2_, matches12_, kf1_from_kf2).value();
  }

  Map map_;
  KeyFrame* kf1_ = nullptr;
  KeyFrame* kf2_ = nullptr;
  std::vector<MapPoint*> matches12_;
  Sim3d truth_;
};

TEST_F(TwoMonocularKeyframes, TheTruthAlignsTheTwoStructures) {
  Build(/*baseline=*/0.3, /*pixel_noise=*/0.0, /*depth_noise=*/0.0, 1);
  EXPECT_NEAR(DepthRatio(truth_), 1.0, 1e-9);
  EXPECT_NEAR(DepthRatio(Sim3d(truth_.scale * 1.3, truth_.rotation, truth_.translation)), 1.0 / 1.3, 0.01);
}

TEST_F(TwoMonocularKeyframes, ARefinedScaleTheStructuresRefuseIsHeldAtTheirs) {
  // Keyframe 2's image was taken 0.4 m from camera 1, its points triangulated as if from 0.3 m: reprojection
  // reads the scale from the two translations (into image 1 divided by it, into image 2 not): a third more.
  Build(/*baseline=*/0.3, /*pixel_noise=*/0.5, /*depth_noise=*/0.01, 3, /*keypoints2_baseline=*/0.4);
  std::vector<MapPoint*> free_matches = matches12_;
  Sim3d free = truth_;
  RefineSim3(*kf1_, *kf2_, free_matches, &free, 10.0, /*fix_scale=*/false);
  const double free_ratio = DepthRatio(free);
  ASSERT_LT(free_ratio, 1.0 / 1.15) << "the free refinement's scale " << free.scale;

  Sim3d kept = truth_;
  const MonocularSim3Refinement refined =
      RefineSim3KeepingStructureScale(*kf1_, *kf2_, matches12_, &kept, 10.0, 1.15);
  EXPECT_TRUE(refined.scale_held);
  EXPECT_NEAR(refined.free_scale, free.scale, 1e-9);
  EXPECT_NEAR(refined.free_depth_ratio, free_ratio, 1e-9);
  EXPECT_DOUBLE_EQ(kept.scale, free.scale * free_ratio);  // the structures' scale, held
  EXPECT_NEAR(kept.scale / truth_.scale, 1.0, 0.05);
  EXPECT_NEAR(DepthRatio(kept), 1.0, 0.05);
  EXPECT_GT(refined.inliers, 150);
}

TEST_F(TwoMonocularKeyframes, CamerasApartKeepTheFreeScale) {
  Build(/*baseline=*/4.0, /*pixel_noise=*/1.0, /*depth_noise=*/0.005, 3);
  Sim3d start(truth_.scale * 1.05, truth_.rotation, truth_.translation);
  const MonocularSim3Refinement refined =
      RefineSim3KeepingStructureScale(*kf1_, *kf2_, matches12_, &start, 10.0, 1.15);
  EXPECT_FALSE(refined.scale_held);
  EXPECT_DOUBLE_EQ(start.scale, refined.free_scale);
  EXPECT_NEAR(start.scale / truth_.scale, 1.0, 0.01);
  EXPECT_GT(refined.inliers, 150);
}

TEST_F(TwoMonocularKeyframes, RejectsAToleranceOfOneOrLess) {
  Build(0.3, 0.0, 0.0, 1);
  Sim3d s = truth_;
  EXPECT_THROW(RefineSim3KeepingStructureScale(*kf1_, *kf2_, matches12_, &s, 10.0, 1.0), InvalidArgument);
}

}  // namespace
}  // namespace semslam
