#include "semslam/geo/georeference.h"

#include <gtest/gtest.h>

#include "semslam/core/error.h"

namespace semslam {
namespace {

// Two keyframes whose corrections differ by a shift of 10 m east and a doubled scale.
LocalCorrections MakeCorrections() {
  return LocalCorrections(
      {{20, Eigen::Vector3d(10, 0, 0), Sim3d(2.0, Eigen::Quaterniond::Identity(), Eigen::Vector3d(10, 0, 0))},
       {0, Eigen::Vector3d(0, 0, 0), Sim3d(1.0, Eigen::Quaterniond::Identity(), Eigen::Vector3d::Zero())}});
}

TEST(LocalCorrections, NearestKeyframeAndFrameBlend) {
  const LocalCorrections c = MakeCorrections();
  ASSERT_EQ(c.keyframes().size(), 2u);
  EXPECT_EQ(c.keyframes()[0].frame_index, 0u);  // sorted by frame
  EXPECT_EQ(c.NearestInMap(Eigen::Vector3d(4, 0, 0)), 0u);
  EXPECT_EQ(c.NearestInMap(Eigen::Vector3d(6, 0, 0)), 1u);
  EXPECT_EQ(c.MapToEnu(Eigen::Vector3d(4, 1, 0)), Eigen::Vector3d(4, 1, 0));
  EXPECT_EQ(c.MapToEnu(Eigen::Vector3d(6, 1, 0)), Eigen::Vector3d(22, 2, 0));
  // ENU (30, 0, 0) is keyframe 20's fused position: back to its map position.
  EXPECT_EQ(c.NearestInEnu(Eigen::Vector3d(29, 0, 0)), 1u);
  EXPECT_NEAR((c.EnuToMap(Eigen::Vector3d(30, 0, 0)) - Eigen::Vector3d(10, 0, 0)).norm(), 0.0, 1e-12);
  // Frame 5 is a quarter of the way from keyframe 0 to keyframe 20.
  const Eigen::Vector3d p(2.5, 0, 0);
  EXPECT_NEAR((c.FrameToEnu(5, p) - (0.75 * p + 0.25 * Eigen::Vector3d(15, 0, 0))).norm(), 0.0, 1e-12);
  EXPECT_NEAR((c.FrameToEnu(20, p) - Eigen::Vector3d(15, 0, 0)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((c.FrameToEnu(99, p) - Eigen::Vector3d(15, 0, 0)).norm(), 0.0, 1e-12);
  EXPECT_THROW(LocalCorrections({}), InvalidArgument);
}

TEST(Georeference, GlobalOrLocal) {
  const EnuFrame frame(Wgs84{49.0, 8.4, 100.0});
  const Sim3d global(3.0, Eigen::Quaterniond::Identity(), Eigen::Vector3d(1, 2, 3));
  const Georeference plain(frame, global);
  EXPECT_EQ(plain.MapToEnu(Eigen::Vector3d(1, 0, 0)), Eigen::Vector3d(4, 2, 3));
  EXPECT_NEAR((plain.EnuToMap(Eigen::Vector3d(4, 2, 3)) - Eigen::Vector3d(1, 0, 0)).norm(), 0.0, 1e-12);
  EXPECT_DOUBLE_EQ(plain.MetresPerMapUnit(), 3.0);
  const Georeference warped(frame, global, std::make_shared<const LocalCorrections>(MakeCorrections()));
  EXPECT_EQ(warped.MapToEnu(Eigen::Vector3d(6, 1, 0)), Eigen::Vector3d(22, 2, 0));
  const Wgs84 w = warped.MapToWgs84(Eigen::Vector3d(6, 1, 0));
  EXPECT_NEAR((warped.Wgs84ToMap(w) - Eigen::Vector3d(6, 1, 0)).norm(), 0.0, 1e-6);
  EXPECT_DOUBLE_EQ(warped.MetresPerMapUnit(), 3.0);  // the global scale
}

}  // namespace
}  // namespace semslam
