#include "semslam/features/stereo_matching.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "semslam/core/error.h"
#include "semslam/features/orb_extractor.h"
#include "support/test_support.h"
#include "test_images.h"

namespace semslam {
namespace {

StereoRig KittiRig(int width = 1241, int height = 376) {
  StereoRig rig;
  rig.left.width = width;
  rig.left.height = height;
  rig.left.fx = rig.left.fy = 718.856;
  rig.left.cx = 607.1928;
  rig.left.cy = 185.2157;
  rig.baseline = 386.1448 / 718.856;  // 0.537 m
  return rig;
}

template <typename T>
T Median(std::vector<T> v) {
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

// Right image whose pixel (u, v) shows the left image at (u + disparity(v), v).
cv::Mat ShiftedRight(const cv::Mat& left, const std::function<float(int)>& disparity) {
  cv::Mat map_x(left.size(), CV_32FC1), map_y(left.size(), CV_32FC1);
  for (int v = 0; v < left.rows; ++v) {
    for (int u = 0; u < left.cols; ++u) {
      map_x.at<float>(v, u) = static_cast<float>(u) + disparity(v);
      map_y.at<float>(v, u) = static_cast<float>(v);
    }
  }
  cv::Mat right;
  cv::remap(left, right, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_REFLECT_101);
  return right;
}

struct DisparityErrors {
  int matched = 0;
  float median_error = 0;
  float p90_error = 0;
};

DisparityErrors CheckDisparities(const cv::Mat& left, const cv::Mat& right,
                                 const std::function<float(int)>& disparity) {
  const OrbExtractor extractor;
  ImagePyramid pl, pr;
  const FeatureSet fl = extractor.Extract(left, {}, &pl);
  const FeatureSet fr = extractor.Extract(right, {}, &pr);
  const StereoRig rig = KittiRig(left.cols, left.rows);
  const StereoMatches m = MatchStereo(fl, fr, pl, pr, rig);
  // The image overload gives the same answer.
  const StereoMatches m2 = MatchStereo(fl, fr, left, right, rig);
  EXPECT_EQ(m.right_u, m2.right_u);
  EXPECT_EQ(m.right_u.size(), fl.size());
  EXPECT_EQ(m.depth.size(), fl.size());
  std::vector<float> errors;
  for (size_t i = 0; i < fl.size(); ++i) {
    if (m.right_u[i] < 0) {
      EXPECT_LT(m.depth[i], 0);
      continue;
    }
    const float d = fl.keypoints[i].pixel.x() - m.right_u[i];
    EXPECT_NEAR(m.depth[i], rig.FocalBaseline() / d, 1e-3 * m.depth[i]);
    errors.push_back(std::abs(d - disparity(static_cast<int>(std::lround(fl.keypoints[i].pixel.y())))));
  }
  DisparityErrors out;
  out.matched = m.num_matched;
  EXPECT_EQ(static_cast<size_t>(m.num_matched), errors.size());
  if (errors.empty()) return out;
  std::sort(errors.begin(), errors.end());
  out.median_error = errors[errors.size() / 2];
  out.p90_error = errors[errors.size() * 9 / 10];
  return out;
}

TEST(MatchStereo, ConstantSubpixelShiftOfASyntheticImage) {
  const cv::Mat left = testing::SyntheticStreetSizedImage(17);
  const auto disparity = [](int) { return 23.4f; };
  const DisparityErrors e = CheckDisparities(left, ShiftedRight(left, disparity), disparity);
  EXPECT_GT(e.matched, 850);
  EXPECT_LT(e.median_error, 0.1f);
  EXPECT_LT(e.p90_error, 0.3f);
}

TEST(MatchStereo, GroundPlaneDisparityGrowingDownTheImage) {
  const cv::Mat left = testing::SyntheticStreetSizedImage(19);
  // A plane: disparity 0.5 px at the horizon (row 150), growing 0.25 px per row below, constant above.
  const auto disparity = [](int v) { return v <= 150 ? 0.5f : 0.5f + 0.25f * static_cast<float>(v - 150); };
  const DisparityErrors e = CheckDisparities(left, ShiftedRight(left, disparity), disparity);
  // Patches on a slanted surface see several disparities: less exact than a constant shift, most at the
  // coarse levels where a patch spans 40 rows of the original.
  EXPECT_GT(e.matched, 800);
  EXPECT_LT(e.median_error, 0.2f);
  EXPECT_LT(e.p90_error, 1.0f);
}

TEST(MatchStereo, KnownShiftOfARealKittiImage) {
  SEMSLAM_REQUIRE_SHARED_DATA(root, "kitti_odom_07_3dv");
  const cv::Mat left = testing::Kitti07Frame(root, 40);
  ASSERT_FALSE(left.empty());
  const auto disparity = [](int) { return 17.3f; };
  const DisparityErrors e = CheckDisparities(left, ShiftedRight(left, disparity), disparity);
  EXPECT_GT(e.matched, 900);
  EXPECT_LT(e.median_error, 0.1f);
  EXPECT_LT(e.p90_error, 0.3f);
}

TEST(MatchStereo, NothingIsMatchedWithoutTextureOrAcrossTheDisparityLimit) {
  const cv::Mat left = testing::SyntheticStreetSizedImage(23);
  const OrbExtractor extractor;
  ImagePyramid pl, pr;
  const FeatureSet fl = extractor.Extract(left, {}, &pl);
  // The right image is the left one shifted the wrong way (negative disparity): no valid match.
  const cv::Mat wrong = ShiftedRight(left, [](int) { return -15.0f; });
  const FeatureSet fr = extractor.Extract(wrong, {}, &pr);
  const StereoMatches m = MatchStereo(fl, fr, pl, pr, KittiRig());
  // A right shift for comparison.
  const cv::Mat right = ShiftedRight(left, [](int) { return 20.0f; });
  const FeatureSet fr2 = extractor.Extract(right, {}, &pr);
  const int good = MatchStereo(fl, fr2, pl, pr, KittiRig()).num_matched;
  EXPECT_GT(good, 900);
  // Only repeated structure (the image has grids of identical windows) still finds a partner.
  EXPECT_LT(m.num_matched, good / 6);
  // A minimum depth beyond every point: hardly anything.
  StereoMatchOptions options;
  options.min_depth = 100.0;  // disparity limit 3.9 px
  EXPECT_LT(MatchStereo(fl, fr2, pl, pr, KittiRig(), options).num_matched, good / 6);
  // Empty sets.
  EXPECT_EQ(MatchStereo(FeatureSet{}, fr2, pl, pr, KittiRig()).num_matched, 0);
  options = {};
  options.patch_half_size = 0;
  EXPECT_THROW(options.Check(), InvalidArgument);
}

// KITTI ground-truth pose (camera-to-world 3x4) of `frame`.
Eigen::Matrix4d KittiPose(const std::filesystem::path& file, int frame) {
  std::ifstream in(file);
  std::string line;
  for (int i = 0; i <= frame; ++i) std::getline(in, line);
  std::istringstream ss(line);
  Eigen::Matrix4d t = Eigen::Matrix4d::Identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) ss >> t(r, c);
  }
  return t;
}

cv::Mat Read(const std::filesystem::path& p) { return cv::imread(p.string(), cv::IMREAD_GRAYSCALE); }

TEST(MatchStereo, RealKitti00PairsGivePlausibleDepthsConsistentWithTheMotion) {
  SEMSLAM_REQUIRE_SHARED_DATA(root, "kitti_odom_00_pyslam");
  const auto seq = root / "sequences" / "00";
  const cv::Mat l0 = Read(seq / "image_0" / "000000.png"), r0 = Read(seq / "image_1" / "000000.png");
  const cv::Mat l1 = Read(seq / "image_0" / "000001.png"), r1 = Read(seq / "image_1" / "000001.png");
  ASSERT_FALSE(l0.empty() || r0.empty() || l1.empty() || r1.empty());
  if (cv::norm(l0, r0, cv::NORM_L1) == 0.0) {
    GTEST_SKIP()
        << "kitti_odom_00_pyslam: image_1 is byte-identical to image_0 (the folder holds no real right "
           "images), so there is no real stereo pair to test";
  }
  const StereoRig rig = KittiRig();
  const OrbExtractor extractor;
  ImagePyramid p[4];
  const FeatureSet fl0 = extractor.Extract(l0, {}, &p[0]), fr0 = extractor.Extract(r0, {}, &p[1]);
  const FeatureSet fl1 = extractor.Extract(l1, {}, &p[2]), fr1 = extractor.Extract(r1, {}, &p[3]);
  const StereoMatches s0 = MatchStereo(fl0, fr0, p[0], p[1], rig);
  const StereoMatches s1 = MatchStereo(fl1, fr1, p[2], p[3], rig);
  EXPECT_GT(s0.num_matched, 600);
  std::vector<float> depths;
  for (const float d : s0.depth) {
    if (d > 0) depths.push_back(d);
  }
  const float median_depth = Median(depths);
  EXPECT_GT(median_depth, 5.0f);
  EXPECT_LT(median_depth, 40.0f);
  const auto plausible =
      std::count_if(depths.begin(), depths.end(), [](float d) { return d > 1.0f && d < 200.0f; });
  EXPECT_GT(static_cast<double>(plausible), 0.95 * static_cast<double>(depths.size()));
  // Move frame-0 points with the true motion into frame 1: their depth there agrees with frame 1's stereo.
  const Eigen::Matrix4d world_from_0 = KittiPose(root / "poses" / "00.txt", 0);
  const Eigen::Matrix4d world_from_1 = KittiPose(root / "poses" / "00.txt", 1);
  const Eigen::Matrix4d c1_from_c0 = world_from_1.inverse() * world_from_0;
  const auto matches = MatchBruteForce(fl0, fl1, {});
  std::vector<double> relative_error, reprojection;
  for (size_t i = 0; i < fl0.size(); ++i) {
    const int j = matches[i];
    if (j < 0 || s0.depth[i] <= 0 || s0.depth[i] > 30 || s1.depth[static_cast<size_t>(j)] <= 0) continue;
    const Eigen::Vector3d x0 =
        rig.Triangulate(fl0.keypoints[i].pixel.cast<double>(), fl0.keypoints[i].pixel.x() - s0.right_u[i]);
    const Eigen::Vector3d x1 = (c1_from_c0 * x0.homogeneous()).head<3>();
    relative_error.push_back(std::abs(x1.z() - s1.depth[static_cast<size_t>(j)]) / x1.z());
    reprojection.push_back(
        (rig.left.Project(x1) - fl1.keypoints[static_cast<size_t>(j)].pixel.cast<double>()).norm());
  }
  ASSERT_GT(relative_error.size(), 200u);
  EXPECT_LT(Median(relative_error), 0.05);
  EXPECT_LT(Median(reprojection), 2.0);
}

}  // namespace
}  // namespace semslam
