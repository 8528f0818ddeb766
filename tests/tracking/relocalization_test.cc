// Where a camera lost a moment ago may be relocalized (MotionSinceLoss).

#include "semslam/tracking/relocalization.h"

#include <gtest/gtest.h>

namespace semslam {
namespace {

// Last tracked at the origin, driving along +z at 1 m per step; 20 steps later the motion model puts the
// camera at z = 20. Noise: two steps.
MotionSinceLoss DrivingAlongZ() {
  MotionSinceLoss motion;
  motion.last_center = {0, 0, 0};
  motion.predicted_center = {0, 0, 20};
  motion.radius = 60;
  motion.backward_tolerance = 2;
  return motion;
}

TEST(MotionSinceLoss, AcceptsAPoseAroundThePredictionOrShortOfIt) {
  const MotionSinceLoss motion = DrivingAlongZ();
  EXPECT_FALSE(motion.Refuses({0, 0, 20}));
  EXPECT_FALSE(motion.Refuses({1.5, 0, 35}));  // sped up, changed lane
  EXPECT_FALSE(motion.Refuses({0, 0, 3}));     // braked hard
  EXPECT_FALSE(motion.Refuses({0, 0, -1.5}));  // stopped: a pose within its noise of where it was
}

TEST(MotionSinceLoss, RefusesAPoseBehindWhereTheCameraWasLastTracked) {
  const MotionSinceLoss motion = DrivingAlongZ();
  // A block back: a street of repeating fronts matches there as well as where the car is.
  const auto refused = motion.Refuses({0.5, 0, -3});
  ASSERT_TRUE(refused);
  EXPECT_NE(refused->find("behind where the camera was last tracked"), std::string::npos) << *refused;
  // Going back across the road is not going back along it.
  EXPECT_FALSE(motion.Refuses({10, 0, 0}));
}

TEST(MotionSinceLoss, RefusesAPoseBeyondTheRadius) {
  const MotionSinceLoss motion = DrivingAlongZ();
  const auto refused = motion.Refuses({0, 0, 81});
  ASSERT_TRUE(refused);
  EXPECT_NE(refused->find("from where the camera can be"), std::string::npos) << *refused;
  EXPECT_TRUE(motion.Refuses({61, 0, 20}));
}

TEST(MotionSinceLoss, ACameraStandingStillHasNoWayBack) {
  MotionSinceLoss motion = DrivingAlongZ();
  motion.predicted_center = {0, 0, 1};  // moved less than its noise: no direction to go back along
  EXPECT_FALSE(motion.Refuses({0, 0, -10}));
  EXPECT_TRUE(motion.Refuses({0, 0, -70}));  // still within the radius only
}

}  // namespace
}  // namespace semslam
