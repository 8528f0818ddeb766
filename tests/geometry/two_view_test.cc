#include "semslam/geometry/two_view.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <numbers>
#include <random>

#include "semslam/core/error.h"
#include "support/draws.h"
#include "support/kitti_camera.h"

namespace semslam {
namespace {

using testing::DrawVector2;

constexpr double kDeg = std::numbers::pi / 180.0;

// camera2_from_camera1 for camera 2 at `center` (in camera 1) rotated by yaw (about y) and pitch (about x).
Rigid3d Motion(const Eigen::Vector3d& center, double yaw_deg, double pitch_deg) {
  const Eigen::Quaterniond rotation = Eigen::AngleAxisd(yaw_deg * kDeg, Eigen::Vector3d::UnitY()) *
                                      Eigen::AngleAxisd(pitch_deg * kDeg, Eigen::Vector3d::UnitX());
  return Rigid3d(rotation, center).Inverse();
}

struct Scene {
  PinholeCamera camera = KittiCamera();
  Rigid3d camera2_from_camera1;
  Points3d points;  // camera 1
  Points2d pixels1, pixels2;
  std::vector<bool> outlier;
};

enum class Structure { kGeneral, kPlanar };

Scene MakeScene(Structure structure, const Rigid3d& motion, int count, double noise_px, double outlier_ratio,
                unsigned seed) {
  Scene scene;
  scene.camera2_from_camera1 = motion;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, scene.camera.width - 1.0), v(0.0, scene.camera.height - 1.0);
  std::uniform_real_distribution<double> depth(5.0, 40.0);
  std::normal_distribution<double> noise(0.0, noise_px);
  // Planar: a facade turned 30 degrees about the vertical, 12 m ahead.
  const Eigen::Vector3d normal(std::sin(30 * kDeg), 0.0, std::cos(30 * kDeg));
  while (static_cast<int>(scene.points.size()) < count) {
    const Eigen::Vector2d pixel = DrawVector2(u, v, rng);
    const Eigen::Vector3d ray = scene.camera.UnprojectDepth(pixel, 1.0);
    const Eigen::Vector3d point =
        structure == Structure::kPlanar ? 12.0 / normal.dot(ray) * ray : depth(rng) * ray;
    const auto pixel2 = scene.camera.ProjectIfVisible(motion * point);
    if (!pixel2) continue;
    scene.points.push_back(point);
    scene.pixels1.push_back(pixel + DrawVector2(noise, rng));
    scene.pixels2.push_back(*pixel2 + DrawVector2(noise, rng));
  }
  scene.outlier.assign(static_cast<size_t>(count), false);
  std::vector<size_t> order(static_cast<size_t>(count));
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::shuffle(order.begin(), order.end(), rng);
  const auto num_outliers = static_cast<size_t>(std::lround(outlier_ratio * count));
  for (size_t k = 0; k < num_outliers; ++k) {
    scene.outlier[order[k]] = true;
    scene.pixels2[order[k]] = DrawVector2(u, v, rng);
  }
  return scene;
}

void ExpectRecovered(const Scene& scene, const TwoViewResult& result) {
  ASSERT_TRUE(result.success) << result.reason;
  const Rigid3d& truth = scene.camera2_from_camera1;
  EXPECT_LT(result.camera2_from_camera1.rotation.angularDistance(truth.rotation) / kDeg, 0.5);
  EXPECT_NEAR(result.camera2_from_camera1.translation.norm(), 1.0, 1e-9);
  const double direction_error = std::acos(
      std::clamp(result.camera2_from_camera1.translation.dot(truth.translation.normalized()), -1.0, 1.0));
  EXPECT_LT(direction_error / kDeg, 2.0);

  // Points up to the common scale 1 / |t|.
  const double scale = 1.0 / truth.translation.norm();
  std::vector<double> relative_errors;
  int triangulated_outliers = 0;
  for (size_t i = 0; i < scene.points.size(); ++i) {
    if (!result.triangulated[i]) {
      EXPECT_EQ(result.points[i], Eigen::Vector3d::Zero());
      continue;
    }
    if (scene.outlier[i]) {
      ++triangulated_outliers;
      continue;
    }
    const Eigen::Vector3d expected = scale * scene.points[i];
    relative_errors.push_back((result.points[i] - expected).norm() / expected.norm());
  }
  const size_t num_inliers =
      static_cast<size_t>(std::count(scene.outlier.begin(), scene.outlier.end(), false));
  EXPECT_GT(relative_errors.size(), 8 * num_inliers / 10);
  EXPECT_LT(triangulated_outliers, static_cast<int>(scene.points.size() / 50));
  std::sort(relative_errors.begin(), relative_errors.end());
  EXPECT_LT(relative_errors[relative_errors.size() / 2], 0.03);
  EXPECT_LT(relative_errors[relative_errors.size() * 9 / 10], 0.10);
}

TEST(TwoView, GeneralSceneSelectsFundamental) {
  const Scene scene = MakeScene(Structure::kGeneral, Motion({1.0, 0.05, 0.4}, 3.0, -1.0), 500, 0.5, 0.2, 1);
  TwoViewOptions options;
  options.seed = 7;
  const TwoViewResult result = InitializeTwoView(scene.pixels1, scene.pixels2, scene.camera, options);
  EXPECT_EQ(result.model, "fundamental");
  EXPECT_LT(result.score_ratio, options.homography_ratio);
  ExpectRecovered(scene, result);
}

TEST(TwoView, PlanarSceneSelectsHomography) {
  const Scene scene = MakeScene(Structure::kPlanar, Motion({1.2, -0.05, 0.3}, -4.0, 1.0), 500, 0.5, 0.2, 2);
  TwoViewOptions options;
  options.seed = 3;
  const TwoViewResult result = InitializeTwoView(scene.pixels1, scene.pixels2, scene.camera, options);
  EXPECT_EQ(result.model, "homography");
  EXPECT_GT(result.score_ratio, options.homography_ratio);
  ExpectRecovered(scene, result);
}

TEST(TwoView, ForwardMotionInGeneralScene) {
  // The driving case: mostly forward, a little turn.
  const Scene scene = MakeScene(Structure::kGeneral, Motion({0.2, 0.0, 1.5}, 2.0, 0.0), 800, 0.5, 0.2, 5);
  TwoViewOptions options;
  options.seed = 11;
  const TwoViewResult result = InitializeTwoView(scene.pixels1, scene.pixels2, scene.camera, options);
  EXPECT_EQ(result.model, "fundamental");
  ExpectRecovered(scene, result);
}

TEST(TwoView, DistortedCamera) {
  Scene scene = MakeScene(Structure::kGeneral, Motion({1.0, 0.0, 0.5}, 2.0, 0.5), 400, 0.0, 0.2, 6);
  // Re-project with a distorted camera: the solver must undistort.
  scene.camera.distortion.k1 = -0.3;
  scene.camera.distortion.k2 = 0.1;
  std::normal_distribution<double> noise(0.0, 0.5);
  std::mt19937 rng(8);
  for (size_t i = 0; i < scene.points.size(); ++i) {
    scene.pixels1[i] = scene.camera.Project(scene.points[i]) + DrawVector2(noise, rng);
    if (!scene.outlier[i]) {
      scene.pixels2[i] =
          scene.camera.Project(scene.camera2_from_camera1 * scene.points[i]) + DrawVector2(noise, rng);
    }
  }
  const TwoViewResult result =
      InitializeTwoView(scene.pixels1, scene.pixels2, scene.camera, TwoViewOptions{});
  ExpectRecovered(scene, result);
}

TEST(TwoView, PureRotationFailsForLowParallax) {
  const Scene scene = MakeScene(Structure::kGeneral, Motion({0, 0, 0}, 4.0, 1.0), 500, 0.5, 0.2, 3);
  const TwoViewResult result =
      InitializeTwoView(scene.pixels1, scene.pixels2, scene.camera, TwoViewOptions{});
  EXPECT_FALSE(result.success);
  EXPECT_NE(result.reason.find("parallax"), std::string::npos) << result.reason;
  EXPECT_EQ(std::count(result.triangulated.begin(), result.triangulated.end(), true), 0);
}

TEST(TwoView, TinyBaselineFailsForLowParallax) {
  const Scene scene = MakeScene(Structure::kGeneral, Motion({0.02, 0.0, 0.01}, 1.0, 0.0), 500, 0.5, 0.2, 4);
  const TwoViewResult result =
      InitializeTwoView(scene.pixels1, scene.pixels2, scene.camera, TwoViewOptions{});
  EXPECT_FALSE(result.success);
  EXPECT_NE(result.reason.find("parallax"), std::string::npos) << result.reason;
}

// A street far ahead (little parallax yet) and one close object in a corner of the image (much): the object
// alone must not pass the parallax test, however many features it has.
TEST(TwoView, OneCloseObjectDoesNotPassTheParallaxTestAlone) {
  Scene scene;
  scene.camera2_from_camera1 = Motion({0.3, 0.0, 0.6}, 1.0, 0.0);
  std::mt19937 rng(21);
  std::normal_distribution<double> noise(0.0, 0.5);
  const auto add = [&](double u_min, double u_max, double v_min, double v_max, double d_min, double d_max,
                       int count) {
    std::uniform_real_distribution<double> u(u_min, u_max), v(v_min, v_max), depth(d_min, d_max);
    for (int added = 0; added < count;) {
      const Eigen::Vector2d pixel = DrawVector2(u, v, rng);
      const Eigen::Vector3d point = depth(rng) * scene.camera.UnprojectDepth(pixel, 1.0);
      const auto pixel2 = scene.camera.ProjectIfVisible(scene.camera2_from_camera1 * point);
      if (!pixel2) continue;
      scene.points.push_back(point);
      scene.pixels1.push_back(pixel + DrawVector2(noise, rng));
      scene.pixels2.push_back(*pixel2 + DrawVector2(noise, rng));
      ++added;
    }
  };
  add(0.0, scene.camera.width - 1.0, 0.0, scene.camera.height - 1.0, 25.0, 60.0, 400);
  add(940.0, 1080.0, 290.0, 370.0, 1.5, 2.0, 80);  // within one cell of the 8 x 4 grid
  TwoViewOptions options;
  options.min_parallax_deg = 2.0;  // as the tracker asks
  const TwoViewResult capped = InitializeTwoView(scene.pixels1, scene.pixels2, scene.camera, options);
  EXPECT_FALSE(capped.success);
  EXPECT_NE(capped.reason.find("low parallax"), std::string::npos) << capped.reason;

  options.parallax_cell_share = 1.0;  // no cap: the object's 50 best points pass
  const TwoViewResult uncapped = InitializeTwoView(scene.pixels1, scene.pixels2, scene.camera, options);
  EXPECT_TRUE(uncapped.success) << uncapped.reason;
  EXPECT_GT(uncapped.parallax_deg, 2.0 * capped.parallax_deg);
}

TEST(TwoView, RandomMatchesFail) {
  Scene scene = MakeScene(Structure::kGeneral, Motion({1.0, 0.0, 0.5}, 2.0, 0.0), 300, 0.5, 1.0, 9);
  const TwoViewResult result =
      InitializeTwoView(scene.pixels1, scene.pixels2, scene.camera, TwoViewOptions{});
  EXPECT_FALSE(result.success);
  EXPECT_FALSE(result.reason.empty());
}

TEST(TwoView, TooFewMatches) {
  const Scene scene = MakeScene(Structure::kGeneral, Motion({1.0, 0.0, 0.5}, 2.0, 0.0), 7, 0.0, 0.0, 9);
  const TwoViewResult result =
      InitializeTwoView(scene.pixels1, scene.pixels2, scene.camera, TwoViewOptions{});
  EXPECT_FALSE(result.success);
  EXPECT_NE(result.reason.find("too few"), std::string::npos);
  EXPECT_EQ(result.points.size(), 7u);
  EXPECT_EQ(result.triangulated.size(), 7u);
}

TEST(TwoView, DeterministicForSeedAndThreading) {
  const Scene scene = MakeScene(Structure::kGeneral, Motion({1.0, 0.05, 0.4}, 3.0, -1.0), 300, 0.8, 0.3, 12);
  TwoViewOptions options;
  options.seed = 42;
  const TwoViewResult a = InitializeTwoView(scene.pixels1, scene.pixels2, scene.camera, options);
  options.parallel = false;
  const TwoViewResult b = InitializeTwoView(scene.pixels1, scene.pixels2, scene.camera, options);
  ASSERT_TRUE(a.success) << a.reason;
  EXPECT_EQ(a.camera2_from_camera1.rotation.coeffs(), b.camera2_from_camera1.rotation.coeffs());
  EXPECT_EQ(a.camera2_from_camera1.translation, b.camera2_from_camera1.translation);
  EXPECT_EQ(a.triangulated, b.triangulated);
  EXPECT_EQ(a.homography_score, b.homography_score);
}

TEST(TwoView, BadInputThrows) {
  const PinholeCamera camera = KittiCamera();
  const Points2d one = {{1, 1}};
  EXPECT_THROW(InitializeTwoView(one, {}, camera, TwoViewOptions{}), InvalidArgument);
  EXPECT_THROW(InitializeTwoView({{std::nan(""), 1.0}}, one, camera, TwoViewOptions{}), InvalidArgument);
  TwoViewOptions options;
  options.homography_ratio = 1.5;
  EXPECT_THROW(InitializeTwoView(one, one, camera, options), InvalidArgument);
  options = {};
  options.parallax_cell_share = 0.0;
  EXPECT_THROW(InitializeTwoView(one, one, camera, options), InvalidArgument);
  options = {};
  options.parallax_grid_rows = 0;
  EXPECT_THROW(InitializeTwoView(one, one, camera, options), InvalidArgument);
  EXPECT_THROW(InitializeTwoView(one, one, PinholeCamera{}, TwoViewOptions{}), InvalidArgument);
}

}  // namespace
}  // namespace semslam
