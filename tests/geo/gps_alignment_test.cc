#include "semslam/geo/gps_alignment.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "semslam/geometry/alignment.h"
#include "synthetic_drive.h"

namespace semslam {
namespace {

using testing::BlockLoop;
using testing::Noise3;

const Sim3d kEnuFromMap(23.5,
                        Eigen::Quaterniond(Eigen::AngleAxisd(0.8,
                                                             Eigen::Vector3d(0.2, -1.0, 0.3).normalized())),
                        Eigen::Vector3d(-40.0, 12.0, 3.0));

struct Case {
  Points3d truth_enu;
  Points3d map;
  std::vector<GpsSample> samples;
  std::vector<bool> outlier;
};

Case MakeCase(const Sim3d& enu_from_map, double noise_m, double outlier_fraction, unsigned seed) {
  Case c;
  c.truth_enu = BlockLoop();
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const Sim3d map_from_enu = enu_from_map.Inverse();
  for (size_t i = 0; i < c.truth_enu.size(); ++i) {
    c.map.push_back(map_from_enu * c.truth_enu[i]);
    if (i % 30 != 0) continue;
    GpsSample s;
    s.frame_index = i;
    s.timestamp = 0.1 * static_cast<double>(i);
    s.map_position = c.map.back();
    s.enu = c.truth_enu[i] + Noise3(rng, noise_m);
    s.sigma_m = noise_m;
    c.samples.push_back(s);
  }
  // Replace a fraction of the fixes by 50 m horizontal outliers.
  const size_t n_out =
      static_cast<size_t>(std::round(outlier_fraction * static_cast<double>(c.samples.size())));
  c.outlier.assign(c.samples.size(), false);
  std::vector<size_t> order(c.samples.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::shuffle(order.begin(), order.end(), rng);
  for (size_t k = 0; k < n_out; ++k) {
    const double angle = 2 * M_PI * u(rng);
    c.samples[order[k]].enu = c.truth_enu[c.samples[order[k]].frame_index] +
                              Eigen::Vector3d(50 * std::cos(angle), 50 * std::sin(angle), 0.0);
    c.outlier[order[k]] = true;
  }
  return c;
}

double Ate(const Sim3d& enu_from_map, const Case& c) {
  double sum = 0;
  for (size_t i = 0; i < c.map.size(); ++i) sum += (enu_from_map * c.map[i] - c.truth_enu[i]).squaredNorm();
  return std::sqrt(sum / static_cast<double>(c.map.size()));
}

TEST(GpsAlignment, RecoversKnownSim3With1mNoise) {
  const Case c = MakeCase(kEnuFromMap, 1.0, 0.0, 3);
  ASSERT_GT(c.samples.size(), 50u);
  const auto result = AlignMapToGps(c.samples);
  ASSERT_TRUE(result);
  EXPECT_NEAR(result->enu_from_map.scale / kEnuFromMap.scale, 1.0, 0.005);
  EXPECT_LT(result->enu_from_map.rotation.angularDistance(kEnuFromMap.rotation), 0.2 * M_PI / 180);
  EXPECT_LT(Ate(result->enu_from_map, c), 0.5);
  EXPECT_EQ(result->num_inliers, static_cast<int>(c.samples.size()));
  EXPECT_NEAR(result->inlier_rmse_m, std::sqrt(3.0), 0.4);  // 3D residuals of sigma-1 noise
  ASSERT_EQ(result->residuals_m.size(), c.samples.size());
}

TEST(GpsAlignment, RejectsFivePercentOf50mOutliers) {
  double robust_sum = 0, plain_sum = 0;
  for (const unsigned seed : {1u, 2u, 3u, 4u, 5u, 6u, 7u, 8u}) {
    const Case c = MakeCase(kEnuFromMap, 1.0, 0.05, seed);
    const auto result = AlignMapToGps(c.samples);
    ASSERT_TRUE(result);
    int flagged_outliers = 0, kept_inliers = 0, n_in = 0;
    Points3d src, tgt, inlier_src, inlier_tgt;
    for (size_t i = 0; i < c.samples.size(); ++i) {
      src.push_back(c.samples[i].map_position);
      tgt.push_back(c.samples[i].enu);
      if (c.outlier[i]) {
        flagged_outliers += result->inliers[i] ? 0 : 1;
      } else {
        ++n_in;
        kept_inliers += result->inliers[i] ? 1 : 0;
        inlier_src.push_back(c.samples[i].map_position);
        inlier_tgt.push_back(c.samples[i].enu);
      }
    }
    EXPECT_EQ(flagged_outliers, static_cast<int>(std::count(c.outlier.begin(), c.outlier.end(), true)))
        << seed;
    EXPECT_GE(kept_inliers, n_in - 1) << seed;
    const double robust = Ate(result->enu_from_map, c);
    EXPECT_LT(robust, 0.5) << seed;
    EXPECT_NEAR(result->enu_from_map.scale / kEnuFromMap.scale, 1.0, 0.005) << seed;
    // As good as least squares on the true inliers (an oracle that knows the outliers).
    const double oracle = Ate(*AlignSim3(inlier_src, inlier_tgt), c);
    EXPECT_LT(robust, oracle + 0.1) << seed;
    robust_sum += robust;
    plain_sum += Ate(*AlignSim3(src, tgt), c);
  }
  // Plain least squares over all fixes is pulled away by the outliers (on average over the seeds: three 50 m
  // outliers among 59 fixes can happen to cancel out in one draw).
  EXPECT_GT(plain_sum, 1.5 * robust_sum);
}

TEST(GpsAlignment, RigidForMetricMaps) {
  const Sim3d truth(1.0, kEnuFromMap.rotation, kEnuFromMap.translation);
  const Case c = MakeCase(truth, 1.0, 0.05, 9);
  GpsAlignmentOptions options;
  options.estimate_scale = false;
  const auto result = AlignMapToGps(c.samples, options);
  ASSERT_TRUE(result);
  EXPECT_DOUBLE_EQ(result->enu_from_map.scale, 1.0);
  EXPECT_LT(Ate(result->enu_from_map, c), 0.5);
}

TEST(GpsAlignment, DegenerateAndTooFewSamples) {
  std::vector<GpsSample> line;
  for (int i = 0; i < 10; ++i) {
    GpsSample s;
    s.map_position = Eigen::Vector3d(i, 0, 0);
    s.enu = Eigen::Vector3d(10 * i, 5, 0);
    line.push_back(s);
  }
  EXPECT_FALSE(AlignMapToGps(line));  // collinear: roll about the line unknown
  EXPECT_FALSE(AlignMapToGps({line[0], line[1], line[2]}));
  GpsAlignmentOptions bad;
  bad.min_samples = 2;
  EXPECT_THROW(AlignMapToGps(line, bad), InvalidArgument);
}

// A drive along a road 400 m long that bows `bow_m` sideways, cameras looking along it (ENU: north-east,
// climbing 2 %) with level image rows, a fix every 30 m with `sigma_m` of noise, the map placed by
// kEnuFromMap.
std::vector<GpsSample> RoadSamples(double bow_m, double sigma_m, unsigned seed) {
  const Eigen::Vector3d forward = Eigen::Vector3d(std::cos(0.6), std::sin(0.6), 0.0);
  const Eigen::Vector3d left = Eigen::Vector3d::UnitZ().cross(forward);
  Eigen::Matrix3d enu_from_camera;
  enu_from_camera.col(0) = -left;
  enu_from_camera.col(1) = -Eigen::Vector3d::UnitZ();
  enu_from_camera.col(2) = forward;
  const Sim3d map_from_enu = kEnuFromMap.Inverse();
  std::mt19937 rng(seed);
  std::vector<GpsSample> samples;
  for (int i = 0; i < 400; i += 30) {
    const double s = static_cast<double>(i);
    const Eigen::Vector3d enu =
        s * (forward + Eigen::Vector3d(0, 0, 0.02)) + bow_m * std::sin(s / 400.0 * M_PI) * left;
    GpsSample sample;
    sample.frame_index = static_cast<size_t>(i);
    sample.map_position = map_from_enu * enu;
    sample.enu = enu + Noise3(rng, sigma_m);
    sample.sigma_m = sigma_m;
    sample.camera_down = map_from_enu.rotation * (enu_from_camera * Eigen::Vector3d::UnitY());
    samples.push_back(sample);
  }
  return samples;
}

// A straight drive: the fixes fix all but the roll about their line; the cameras' down axis sets it.
TEST(GpsAlignment, AStraightDriveTakesItsRollFromTheCameras) {
  std::vector<GpsSample> samples = RoadSamples(0.0, 0.05, 7);
  samples[5].enu += Eigen::Vector3d(30, -40, 0);  // one outlier
  const auto result = AlignMapToGps(samples);
  ASSERT_TRUE(result);
  EXPECT_TRUE(result->roll_from_camera_down);
  EXPECT_FALSE(result->inliers[5]);
  EXPECT_EQ(result->num_inliers, static_cast<int>(samples.size()) - 1);
  EXPECT_NEAR(result->enu_from_map.scale / kEnuFromMap.scale, 1.0, 0.002);
  EXPECT_LT(result->enu_from_map.rotation.angularDistance(kEnuFromMap.rotation), 0.002);
  EXPECT_LT(result->inlier_rmse_m, 0.15);

  // Stereo: scale 1. Camera axes pointing every way, or the option off: no roll, no estimate.
  std::vector<GpsSample> metric = samples;
  for (GpsSample& s : metric)
    s.map_position = kEnuFromMap.rotation.conjugate() * (s.enu - kEnuFromMap.translation);
  GpsAlignmentOptions stereo;
  stereo.estimate_scale = false;
  const auto rigid = AlignMapToGps(metric, stereo);
  ASSERT_TRUE(rigid);
  EXPECT_DOUBLE_EQ(rigid->enu_from_map.scale, 1.0);
  EXPECT_LT(rigid->enu_from_map.rotation.angularDistance(kEnuFromMap.rotation), 0.002);
  GpsAlignmentOptions off;
  off.roll_from_camera_down = false;
  EXPECT_FALSE(AlignMapToGps(samples, off));
  for (size_t i = 0; i < samples.size(); ++i) samples[i].camera_down *= i % 2 == 0 ? 1.0 : -1.0;
  EXPECT_FALSE(AlignMapToGps(samples));
}

// A road that bows 20 m over 400 m, in fixes of 2 m noise: the bow barely stands out of the noise, and the
// roll Umeyama finds in it is largely the noise's; the cameras' is not. Medians over ten draws of the noise.
TEST(GpsAlignment, ANearlyStraightDriveInNoisyFixesTakesItsRollFromTheCameras) {
  std::vector<double> cameras_deg, positions_deg;
  GpsAlignmentOptions umeyama;
  umeyama.min_roll_spread_sigmas = 0.0;
  for (unsigned seed = 1; seed <= 10; ++seed) {
    const std::vector<GpsSample> samples = RoadSamples(20.0, 2.0, seed);
    const auto by_cameras = AlignMapToGps(samples);
    const auto by_positions = AlignMapToGps(samples, umeyama);
    ASSERT_TRUE(by_cameras && by_positions);
    EXPECT_TRUE(by_cameras->roll_from_camera_down);
    EXPECT_FALSE(by_positions->roll_from_camera_down);
    cameras_deg.push_back(by_cameras->enu_from_map.rotation.angularDistance(kEnuFromMap.rotation) * 180 /
                          M_PI);
    positions_deg.push_back(by_positions->enu_from_map.rotation.angularDistance(kEnuFromMap.rotation) * 180 /
                            M_PI);
  }
  std::sort(cameras_deg.begin(), cameras_deg.end());
  std::sort(positions_deg.begin(), positions_deg.end());
  std::printf(
      "bow 20 m, fixes 2 m: rotation off by %.2f deg median, %.2f worst (cameras' roll); %.2f, %.2f "
      "(Umeyama)\n",
      cameras_deg[5], cameras_deg[9], positions_deg[5], positions_deg[9]);
  EXPECT_LT(cameras_deg[5], 1.0);
  EXPECT_GT(positions_deg[5], 2.0);
  // A bow that stands out of the fixes' noise (60 m against 1 m) leaves the roll to the positions.
  EXPECT_FALSE(AlignMapToGps(RoadSamples(60.0, 1.0, 3))->roll_from_camera_down);
}

TEST(GpsAlignment, IncrementalReestimatesAsSamplesArrive) {
  const Case c = MakeCase(kEnuFromMap, 1.0, 0.05, 11);
  IncrementalGpsAligner aligner;
  int first_estimate = -1;
  for (size_t i = 0; i < c.samples.size(); ++i) {
    const auto& current = aligner.Add(c.samples[i]);
    if (current && first_estimate < 0) first_estimate = static_cast<int>(i);
    if (current) {
      EXPECT_EQ(current->residuals_m.size(), i + 1);
    }
  }
  // The route starts with 400 m straight east: no estimate until the first turn (sample 14, frame 420).
  EXPECT_GE(first_estimate, 13);
  EXPECT_LE(first_estimate, 16);
  ASSERT_TRUE(aligner.current());
  EXPECT_LT(Ate(aligner.current()->enu_from_map, c), 0.5);

  // Positions moved by a map-wide similarity (as after a loop closure): the alignment follows.
  const Sim3d moved(2.0, Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitY())),
                    Eigen::Vector3d(1, 2, 3));
  aligner.UpdateMapPositions(
      [&](size_t frame) -> std::optional<Eigen::Vector3d> { return moved * c.map[frame]; });
  const Sim3d recovered = aligner.current()->enu_from_map * moved;
  EXPECT_LT(Ate(recovered, c), 0.5);
}

TEST(GpsSampling, EveryNFramesWithKeyframesAndDropouts) {
  const EnuFrame frame(Wgs84{49.0, 8.4, 100.0});
  std::vector<GpsFix> fixes;
  for (int i = 0; i < 100; ++i) {
    if (i == 60) continue;  // dropout
    fixes.push_back(GpsFix{0.1 * i, frame.ToWgs84(Eigen::Vector3d(i, 0, 0)), 1.0, {}});
  }
  FramePositions all, keyframes;
  for (size_t i = 0; i < 100; ++i) {
    all.push_back(FramePosition{i, -1, 0.1 * static_cast<double>(i),
                                Eigen::Vector3d(0.1 * static_cast<double>(i), 0, 0)});
  }
  for (const size_t i : {0, 7, 14, 29, 31, 45, 61, 95}) keyframes.push_back(all[i]);
  GpsSamplingOptions options;
  const auto every = SampleGpsPairs(all, fixes, frame, options);
  ASSERT_EQ(every.size(), 4u);
  EXPECT_EQ(every[0].frame_index, 0u);
  EXPECT_EQ(every[1].frame_index, 30u);
  EXPECT_EQ(every[2].frame_index, 61u);  // 60 has no fix
  EXPECT_EQ(every[3].frame_index, 90u);
  EXPECT_NEAR(every[3].enu.x(), 90.0, 1e-6);
  const auto sparse = SampleGpsPairs(keyframes, fixes, frame, options);
  ASSERT_EQ(sparse.size(), 4u);
  EXPECT_EQ(sparse[1].frame_index, 31u);
  EXPECT_EQ(sparse[2].frame_index, 61u);
  EXPECT_EQ(sparse[3].frame_index, 95u);
  options.every_n_frames = 0;
  EXPECT_THROW(SampleGpsPairs(all, fixes, frame, options), InvalidArgument);
}

}  // namespace
}  // namespace semslam
