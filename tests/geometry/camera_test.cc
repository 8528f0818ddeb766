#include "semslam/geometry/camera.h"

#include <gtest/gtest.h>

#include "semslam/core/error.h"
#include "support/kitti_camera.h"

namespace semslam {
namespace {

TEST(PinholeCamera, ProjectsKnownPoint) {
  const PinholeCamera c = KittiCamera();
  // 1 m right, 0.5 m down, 10 m ahead: u = 718.856 * 0.1 + 607.1928, v = 718.856 * 0.05 + 185.2157.
  const Eigen::Vector2d uv = c.Project({1.0, 0.5, 10.0});
  EXPECT_NEAR(uv.x(), 679.0784, 1e-9);
  EXPECT_NEAR(uv.y(), 221.1585, 1e-9);
}

TEST(PinholeCamera, UnprojectInvertsProject) {
  const PinholeCamera c = KittiCamera();
  const Eigen::Vector3d p(-3.0, 1.2, 17.0);
  const Eigen::Vector2d uv = c.Project(p);
  EXPECT_TRUE(c.Unproject(uv).isApprox(p.normalized(), 1e-12));
  EXPECT_TRUE(c.UnprojectDepth(uv, 17.0).isApprox(p, 1e-12));
}

TEST(PinholeCamera, DistortionRoundTrip) {
  PinholeCamera c = KittiCamera();
  c.distortion = {-0.28, 0.07, 0.0002, -0.0001, 0.0};
  const Eigen::Vector3d p(2.0, -1.0, 8.0);
  const Eigen::Vector2d uv = c.Project(p);
  EXPECT_GT((uv - KittiCamera().Project(p)).norm(), 1.0);  // distortion moves the pixel
  EXPECT_TRUE(c.UnprojectDepth(uv, 8.0).isApprox(p, 1e-9));
}

TEST(PinholeCamera, DistortionThatFoldsTheImageIsFound) {
  PinholeCamera c = KittiCamera();
  EXPECT_FALSE(c.PixelNotUndistorted().has_value());
  // KITTI raw's unrectified grey camera (2011_09_26 calib_cam_to_cam.txt, camera 00): strong barrel
  // distortion, still one to one over its image.
  PinholeCamera raw;
  raw.width = 1392;
  raw.height = 512;
  raw.fx = 984.2439;
  raw.fy = 980.8141;
  raw.cx = 690.0;
  raw.cy = 233.1966;
  raw.distortion = {-0.3728755, 0.2037299, 0.002219027, 0.001383707, -0.07233722};
  EXPECT_FALSE(raw.PixelNotUndistorted().has_value());
  // The same lens on the rectified camera's shorter focal length: its corners fold back.
  c.distortion = raw.distortion;
  EXPECT_TRUE(c.PixelNotUndistorted().has_value());
  // Coefficients of another lens or mistyped: the corners fold back (r_d(r) turns) or do not converge.
  for (const Distortion& d : {Distortion{-0.9, 0, 0, 0, 0}, Distortion{0, 3.0, 0, 0, 0},
                              Distortion{-2.0, 0, 0, 0, 0}, Distortion{0, 0, 0.5, 0, 0}}) {
    c.distortion = d;
    EXPECT_TRUE(c.PixelNotUndistorted().has_value()) << d.k1 << " " << d.k2 << " " << d.p1;
  }
}

TEST(PinholeCamera, VisibilityChecksDepthAndBounds) {
  const PinholeCamera c = KittiCamera();
  EXPECT_TRUE(c.ProjectIfVisible({0, 0, 5}).has_value());
  EXPECT_FALSE(c.ProjectIfVisible({0, 0, -5}).has_value());
  EXPECT_FALSE(c.ProjectIfVisible({100, 0, 5}).has_value());
}

TEST(PinholeCamera, CheckRejectsBadIntrinsics) {
  PinholeCamera c = KittiCamera();
  EXPECT_NO_THROW(c.Check());
  c.fx = -1;
  EXPECT_THROW(c.Check(), InvalidArgument);
  c = KittiCamera();
  c.width = 0;
  EXPECT_THROW(c.Check(), InvalidArgument);
}

TEST(PinholeCamera, ScaledKeepsRaysOfPixelCentres) {
  const PinholeCamera c = KittiCamera();
  const PinholeCamera half = c.Scaled(0.5);
  const Eigen::Vector3d p(1.0, 2.0, 20.0);
  // Pixel centres scale about the image corner: (u + 0.5) * s - 0.5.
  const Eigen::Vector2d full = c.Project(p);
  EXPECT_TRUE(half.Project(p).isApprox((full.array() + 0.5).matrix() * 0.5 - Eigen::Vector2d(0.5, 0.5), 1e-9));
}

TEST(StereoRig, DisparityAndDepthAgree) {
  StereoRig rig{KittiCamera(), 0.537};
  const Eigen::Vector3d p(1.5, -0.3, 12.0);
  const Eigen::Vector2d left = rig.left.Project(p);
  const double disparity = left.x() - rig.ProjectRightU(p);
  EXPECT_NEAR(disparity, 718.856 * 0.537 / 12.0, 1e-9);
  EXPECT_TRUE(rig.Triangulate(left, disparity).isApprox(p, 1e-9));
  rig.baseline = 0;
  EXPECT_THROW(rig.Check(), InvalidArgument);
}

}  // namespace
}  // namespace semslam
