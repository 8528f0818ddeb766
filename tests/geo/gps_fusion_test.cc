#include "semslam/geo/gps_fusion.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "synthetic_drive.h"

namespace semslam {
namespace {

using testing::Drive;
using testing::EnuFromCamera;
using testing::MakeDrive;

GpsFusionInput Input(const Drive& d, int keyframe_every) {
  GpsFusionInput input;
  input.frames = d.frames;
  for (size_t i = 0; i < d.frames.size(); i += static_cast<size_t>(keyframe_every)) {
    FramePose k = d.frames[i];
    k.keyframe_id = static_cast<long long>(input.keyframes.size());
    input.keyframes.push_back(k);
  }
  input.fixes = d.fixes;
  return input;
}

// RMSE over every frame of the ENU positions given by a georeference, without any further alignment.
double AteEnu(const Drive& d, const Georeference& g) {
  double sum = 0.0;
  for (size_t i = 0; i < d.frames.size(); ++i) {
    sum += (g.FrameToEnu(i, d.frames[i].world_from_camera.translation) - d.truth_enu[i]).squaredNorm();
  }
  return std::sqrt(sum / static_cast<double>(d.frames.size()));
}

double AteGlobal(const Drive& d, const Sim3d& enu_from_map) {
  return AteEnu(d, Georeference(d.enu, enu_from_map));
}

TEST(GpsFusion, CorrectsMonocularScaleDrift) {
  const Drive d = MakeDrive(0.01, 0.0, 0.05, 1.0, 30, 0.0, 1);
  const auto result = FuseGps(Input(d, 5), d.enu);
  ASSERT_TRUE(result);
  const double single = AteGlobal(d, result->prealignment.enu_from_map);
  const double fused = AteEnu(d, result->georeference);
  RecordProperty("ate_single_sim3_m", std::to_string(single));
  RecordProperty("ate_fused_m", std::to_string(fused));
  std::printf("scale drift 1 %%/100 m, sigma 1 m every 30 frames: ATE single Sim(3) %.2f m, fused %.2f m\n",
              single, fused);
  EXPECT_GT(single, 3.0);  // one similarity cannot follow a 19 % scale change
  EXPECT_LT(fused, 1.0);
  EXPECT_EQ(result->num_inliers, static_cast<int>(result->samples.size()));
  EXPECT_EQ(result->samples.size(), d.fixes.size());
  EXPECT_LT(result->inlier_rmse_m, 2.0);  // 3D residuals of sigma-1 noise: about sqrt(3)
  ASSERT_EQ(result->keyframe_enu_from_camera.size(), Input(d, 5).keyframes.size());
  // The fused keyframe centres are the frames' ENU positions.
  EXPECT_NEAR((result->keyframe_enu_from_camera[40].translation - d.truth_enu[200]).norm(), 0.0, 1.5);
  // Metres per map unit near the start and the end follow the drift (20 units per metre at the start).
  const double start_scale = result->keyframe_enu_from_camera.front().scale;
  const double end_scale = result->keyframe_enu_from_camera.back().scale;
  EXPECT_NEAR(start_scale, 20.0, 1.0);
  EXPECT_NEAR(end_scale / start_scale, 1.0 / std::pow(1.01, 17.5), 0.02);
}

TEST(GpsFusion, RejectsOutlierFixes) {
  for (const unsigned seed : {2u, 3u, 4u}) {
    const Drive d = MakeDrive(0.01, 0.2, 0.05, 1.0, 30, 0.05, seed);
    const auto result = FuseGps(Input(d, 7), d.enu);  // sampled frames mostly not keyframes
    ASSERT_TRUE(result);
    const double single = AteGlobal(d, result->prealignment.enu_from_map);
    const double fused = AteEnu(d, result->georeference);
    std::printf(
        "seed %u, 5 %% outliers of 50 m, yaw drift 0.2 deg/100 m: ATE single Sim(3) %.2f m, fused %.2f m\n",
        seed, single, fused);
    EXPECT_LT(fused, 1.0) << seed;
    EXPECT_LT(fused, single) << seed;
    int missed = 0, dropped = 0;
    for (size_t s = 0; s < result->samples.size(); ++s) {
      const bool bad = d.outlier[result->samples[s].fix_index];
      missed += bad && result->inliers[s] ? 1 : 0;
      dropped += !bad && !result->inliers[s] ? 1 : 0;
    }
    EXPECT_EQ(missed, 0) << seed;
    EXPECT_LE(dropped, 1) << seed;
  }
}

// A monocular map whose scale grows 2.3 times over the 1.75 km drive (as KITTI 00's first 1.26 km drift
// without a loop): one similarity leaves the fixes tens of metres away, but they are real, and the fusion
// keeps every one.
TEST(GpsFusion, KeepsTheRealFixesOfAStronglyDriftingMap) {
  const Drive d = MakeDrive(0.05, 0.5, 0.05, 1.0, 30, 0.0, 7);
  const auto result = FuseGps(Input(d, 5), d.enu);
  ASSERT_TRUE(result);
  const int samples = static_cast<int>(result->samples.size());
  const double single = AteGlobal(d, result->prealignment.enu_from_map);
  const double fused = AteEnu(d, result->georeference);
  std::printf(
      "scale drift 5 %%/100 m, yaw 0.5 deg/100 m: the fusion keeps %d of %d fixes; ATE single Sim(3) %.2f "
      "m, fused %.2f m, fix RMSE %.2f m\n",
      result->num_inliers, samples, single, fused, result->inlier_rmse_m);
  EXPECT_GT(single, 20.0);
  EXPECT_EQ(result->num_inliers, samples);
  EXPECT_LT(fused, 1.0);
  EXPECT_LT(result->inlier_rmse_m, 2.0);

  // The same drift with 5 % of the fixes 50 m off: those, and only those, lose their pull.
  for (const unsigned seed : {8u, 9u, 10u}) {
    const Drive o = MakeDrive(0.05, 0.5, 0.05, 1.0, 30, 0.05, seed);
    const auto r = FuseGps(Input(o, 5), o.enu);
    ASSERT_TRUE(r);
    int missed = 0, dropped = 0;
    for (size_t s = 0; s < r->samples.size(); ++s) {
      const bool bad = o.outlier[r->samples[s].fix_index];
      missed += bad && r->inliers[s] ? 1 : 0;
      dropped += !bad && !r->inliers[s] ? 1 : 0;
    }
    EXPECT_EQ(missed, 0) << seed;
    EXPECT_LE(dropped, 1) << seed;
    EXPECT_LT(AteEnu(o, r->georeference), 1.0) << seed;
  }
}

// The fixes are the antenna's, a metre beside the camera: the fused camera centres are where the camera was.
TEST(GpsFusion, MovesTheFixesByTheLeverArm) {
  Drive d = MakeDrive(0.01, 0.0, 0.05, 0.05, 30, 0.0, 11);
  const Eigen::Vector3d antenna(0.3, -0.9, -0.5);  // right, up and behind the camera
  for (size_t k = 0; k < d.fixes.size(); ++k) {
    const Rigid3d& enu_from_camera = d.truth[k * 30];
    d.fixes[k].position = d.enu.ToWgs84(enu_from_camera * antenna);
  }
  GpsFusionOptions options;
  const auto plain = FuseGps(Input(d, 5), d.enu, options);
  options.antenna_in_camera_m = antenna;
  const auto moved = FuseGps(Input(d, 5), d.enu, options);
  ASSERT_TRUE(plain && moved);
  const double plain_ate = AteEnu(d, plain->georeference), moved_ate = AteEnu(d, moved->georeference);
  std::printf("antenna 1.07 m from the camera: ATE %.3f m without the lever arm, %.3f m with it\n", plain_ate,
              moved_ate);
  EXPECT_GT(plain_ate, 0.8);
  EXPECT_LT(moved_ate, 0.1);
  EXPECT_LT(moved->inlier_rmse_m, 0.1);
}

// Fixes on one line leave the roll about it free: the cameras' down axis sets it, and the graph holds it
// there. Free, only the lever arm (here 15 cm off sideways) and the map's attitude noise (half a degree) bear
// on it, and the graph turns about the line.
TEST(GpsFusion, AStraightDriveTakesItsRollFromTheCameras) {
  Drive d = MakeDrive(0.01, 0.0, 0.05, 0.05, 30, 0.0, 13, testing::StraightRoad());
  const Eigen::Vector3d antenna(-0.3, 0.7, -1.1);  // left of, below and behind the camera (KITTI's)
  const Eigen::Vector3d sideways(-std::sin(0.6), std::cos(0.6), 0.0);
  std::mt19937 rng(5);
  for (size_t k = 0; k < d.fixes.size(); ++k) {
    d.fixes[k].position =
        d.enu.ToWgs84(d.truth[k * 30] * antenna + 0.15 * sideways + testing::Noise3(rng, 0.05));
  }
  for (FramePose& f : d.frames) {  // the map's attitude noise: half a degree
    const Eigen::Vector3d w = testing::Noise3(rng, 0.5 * std::numbers::pi / 180.0);
    f.world_from_camera.rotation *= Eigen::Quaterniond(Eigen::AngleAxisd(w.norm(), w.normalized()));
  }
  GpsFusionOptions options;
  options.antenna_in_camera_m = antenna;
  // The angle between the keyframes' mean down axis in ENU and the true one.
  const auto tilt_deg = [&](const GpsFusionResult& r, const GpsFusionInput& input) {
    Eigen::Vector3d down = Eigen::Vector3d::Zero(), truth = Eigen::Vector3d::Zero();
    for (size_t i = 0; i < input.keyframes.size(); ++i) {
      down += r.keyframe_enu_from_camera[i].rotation * Eigen::Vector3d::UnitY();
      truth += d.truth[input.keyframes[i].frame_index].rotation * Eigen::Vector3d::UnitY();
    }
    return std::acos(std::min(1.0, down.normalized().dot(truth.normalized()))) * 180.0 / std::numbers::pi;
  };
  const GpsFusionInput input = Input(d, 5);
  const auto held = FuseGps(input, d.enu, options);
  options.line_roll_sigma_rad = 1e3;
  const auto free = FuseGps(input, d.enu, options);
  ASSERT_TRUE(held && free);
  EXPECT_TRUE(held->prealignment.roll_from_camera_down);
  const double held_roll = tilt_deg(*held, input), free_roll = tilt_deg(*free, input);
  std::printf("straight 400 m: cameras tilted %.2f deg held, %.2f deg free; ATE %.3f m\n", held_roll,
              free_roll, AteEnu(d, held->georeference));
  EXPECT_LT(held_roll, 0.5);
  EXPECT_GT(free_roll, 5.0);
  EXPECT_LT(AteEnu(d, held->georeference), 0.2);

  options.alignment.roll_from_camera_down = false;
  EXPECT_FALSE(FuseGps(input, d.enu, options));
}

// A monocular map's covisibility within one pass is measured from the map's own, drifted poses: counted
// with its scale at every edge, it holds the drift against the fixes; as shape alone, the fixes correct it.
TEST(GpsFusion, CovisibilityWithinOnePassLeavesTheScaleToTheChain) {
  const Drive d = MakeDrive(0.03, 0.0, 0.05, 1.0, 30, 0.0, 12);
  GpsFusionInput input = Input(d, 5);
  for (int a = 0; a < static_cast<int>(input.keyframes.size()); ++a) {
    for (int b = a + 2; b < std::min(a + 8, static_cast<int>(input.keyframes.size())); ++b) {
      FusionEdge e;
      e.a = a;
      e.b = b;
      e.a_from_b = Sim3d(input.keyframes[static_cast<size_t>(a)].world_from_camera.Inverse() *
                         input.keyframes[static_cast<size_t>(b)].world_from_camera);
      input.edges.push_back(e);
    }
  }
  GpsFusionOptions options;
  options.one_pass_covisibility_carries_scale = true;
  const auto counted = FuseGps(input, d.enu, options);
  options.one_pass_covisibility_carries_scale = false;
  const auto shape = FuseGps(input, d.enu, options);
  input.edges.clear();
  const auto chain = FuseGps(input, d.enu, options);
  ASSERT_TRUE(counted && shape && chain);
  const double counted_ate = AteEnu(d, counted->georeference), shape_ate = AteEnu(d, shape->georeference),
               chain_ate = AteEnu(d, chain->georeference);
  std::printf(
      "scale drift 3 %%/100 m, covisibility to the 6 next keyframes: ATE %.3f m with its scale, %.3f m as "
      "shape alone, %.3f m with the chain alone\n",
      counted_ate, shape_ate, chain_ate);
  EXPECT_LT(shape_ate, 0.1 * counted_ate);  // measured: 0.62 m against 27.7 m
  EXPECT_LT(shape_ate, 1.05 * chain_ate);   // and 0.64 m with the chain alone
}

TEST(GpsFusion, StereoKeepsTheScale) {
  const Drive d = MakeDrive(0.0, 0.3, 1.0, 1.0, 30, 0.0, 5);
  GpsFusionOptions options;
  options.alignment.estimate_scale = false;
  const auto result = FuseGps(Input(d, 5), d.enu, options);
  ASSERT_TRUE(result);
  for (const Sim3d& pose : result->keyframe_enu_from_camera) EXPECT_DOUBLE_EQ(pose.scale, 1.0);
  EXPECT_DOUBLE_EQ(result->georeference.enu_from_map.scale, 1.0);
  EXPECT_LT(AteEnu(d, result->georeference), 1.0);
}

TEST(GpsFusion, LoopEdgesAndBadInputs) {
  const Drive d = MakeDrive(0.01, 0.0, 0.05, 1.0, 30, 0.0, 6);
  GpsFusionInput input = Input(d, 5);
  // The last street passes the first one's place again: a loop between keyframes 40 (frame 200) and the
  // keyframe of the last lap nearest to it, measured as a loop closure's Sim(3) would (true relative pose at
  // frame 200's map scale, and the ratio of the two map scales).
  size_t a = 200, b = 1500;
  for (size_t f = 1500; f < d.frames.size(); f += 5) {
    if ((d.truth_enu[f] - d.truth_enu[a]).head<2>().norm() <
        (d.truth_enu[b] - d.truth_enu[a]).head<2>().norm()) {
      b = f;
    }
  }
  ASSERT_LT((d.truth_enu[b] - d.truth_enu[a]).head<2>().norm(), 3.0);  // the road's grade differs by metres
  const Rigid3d relative = d.truth[a].Inverse() * d.truth[b];
  FusionEdge loop;
  loop.a = static_cast<int>(a / 5);
  loop.b = static_cast<int>(b / 5);
  loop.kind = FusionEdgeKind::kLoop;
  loop.a_from_b =
      Sim3d(d.map_scale[a] / d.map_scale[b], relative.rotation, d.map_scale[a] * relative.translation);
  input.edges.push_back(loop);
  const auto result = FuseGps(input, d.enu);
  ASSERT_TRUE(result);
  EXPECT_LT(AteEnu(d, result->georeference), 1.0);

  input.edges.back().b = 100000;
  EXPECT_THROW(FuseGps(input, d.enu), InvalidArgument);
  input = Input(d, 5);
  std::swap(input.keyframes[3], input.keyframes[4]);
  EXPECT_THROW(FuseGps(input, d.enu), InvalidArgument);
  input = Input(d, 5);
  input.fixes.resize(3);
  EXPECT_FALSE(FuseGps(input, d.enu));  // three fixes are too few
  GpsFusionOptions bad;
  bad.outlier_sigma = 0;
  EXPECT_THROW(FuseGps(Input(d, 5), d.enu, bad), InvalidArgument);
}

}  // namespace
}  // namespace semslam
