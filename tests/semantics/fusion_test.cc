// Label fusion math against hand-computed posteriors (paper eqs. 1-6).

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <vector>

#include "semslam/core/error.h"
#include "semslam/semantics/label_fusion.h"

namespace semslam {
namespace {

// 19 log-probabilities: `p` for the listed classes, the rest sharing what is left evenly.
ClassLogProbs Observation(std::initializer_list<std::pair<int, double>> given) {
  double used = 0.0;
  for (const auto& [c, p] : given) used += p;
  const double rest = (1.0 - used) / static_cast<double>(kNumClasses - given.size());
  ClassLogProbs o;
  o.fill(static_cast<float>(std::log(rest)));
  for (const auto& [c, p] : given) o[static_cast<size_t>(c)] = static_cast<float>(std::log(p));
  return o;
}

TEST(LabelDistribution, StartsUniformWithoutLabel) {
  const LabelDistribution d;
  EXPECT_EQ(d.Label(), kNoLabel);
  EXPECT_EQ(d.NumObservations(), 0);
  EXPECT_FALSE(d.HasObservations());
  EXPECT_NEAR(d.Confidence(), 1.0 / 19.0, 1e-7);
  for (float p : d.Probabilities()) EXPECT_NEAR(p, 1.0 / 19.0, 1e-7);
}

TEST(LabelDistribution, OneObservationIsThePosterior) {
  LabelDistribution d;
  d.Fuse(Observation({{2, 0.7}}));
  EXPECT_EQ(d.Label(), 2);
  EXPECT_NEAR(d.Confidence(), 0.7, 1e-6);
  EXPECT_NEAR(d.Probabilities()[5], 0.3 / 18.0, 1e-7);
  EXPECT_EQ(d.NumObservations(), 1);
}

// Observations (road, sidewalk, the 17 others): (0.6, 0.3, 0.1/17 each) and (0.2, 0.7, 0.1/17 each).
// Products: road 0.12, sidewalk 0.21, others (0.1/17)^2 = 3.4602e-5 each; Z = 0.33 + 17 * 3.4602e-5 =
// 0.3305882. Posterior: road 0.3629893, sidewalk 0.6352313, each other 1.0466820e-4.
TEST(LabelDistribution, TwoObservationsMatchHandComputedPosterior) {
  LabelDistribution d;
  d.Fuse(Observation({{0, 0.6}, {1, 0.3}}));
  d.Fuse(Observation({{0, 0.2}, {1, 0.7}}));
  const auto p = d.Probabilities();
  EXPECT_NEAR(p[0], 0.3629893, 1e-6);
  EXPECT_NEAR(p[1], 0.6352313, 1e-6);
  EXPECT_NEAR(p[7], 1.0466820e-4, 1e-9);
  EXPECT_EQ(d.Label(), 1);
  EXPECT_NEAR(d.Confidence(), 0.6352313, 1e-6);
  EXPECT_EQ(d.NumObservations(), 2);
  const auto log_p = d.NormalizedLogProbabilities();
  EXPECT_NEAR(log_p[1], std::log(0.6352313), 1e-5);
}

// Confusion model alpha = 0.8 (others 0.2/18 = 0.011111): labels road, road, car.
// Products: road 0.8^2 * 0.011111 = 7.11111e-3, car 0.011111^2 * 0.8 = 9.87654e-5, others 0.011111^3
// = 1.37174e-6; Z = 7.11111e-3 + 9.87654e-5 + 17 * 1.37174e-6 = 7.23320e-3. Posterior: road 0.9831216, car
// 0.0136545, each other 1.896454e-4.
TEST(LabelDistribution, ThreeLabelObservationsWithConfusionModel) {
  LabelDistribution d;
  d.FuseLabel(0, 0.8f);
  d.FuseLabel(0, 0.8f);
  d.FuseLabel(13, 0.8f);
  d.FuseLabel(kNoLabel, 0.8f);  // ignored
  const auto p = d.Probabilities();
  EXPECT_NEAR(p[0], 0.9831216, 1e-6);
  EXPECT_NEAR(p[13], 0.0136545, 1e-6);
  EXPECT_NEAR(p[5], 1.896454e-4, 1e-9);
  EXPECT_EQ(d.Label(), 0);
  EXPECT_NEAR(d.Confidence(), 0.9831216, 1e-6);
  EXPECT_EQ(d.NumObservations(), 3);
}

TEST(LabelDistribution, ConfusionModelRow) {
  const ClassLogProbs row = ConfusionLogProbs(4, 0.9f);
  EXPECT_NEAR(std::exp(row[4]), 0.9, 1e-6);
  EXPECT_NEAR(std::exp(row[0]), 0.1 / 18.0, 1e-7);
  // alpha = 1: the others are floored at 1e-4, not ruled out.
  EXPECT_NEAR(ConfusionLogProbs(4, 1.0f)[0], kMinObservationLogProbability, 1e-6);
  EXPECT_THROW(ConfusionLogProbs(4, 0.01f), InvalidArgument);
  EXPECT_THROW(ConfusionLogProbs(19, 0.9f), InvalidArgument);
}

TEST(LabelDistribution, FloorKeepsEveryClassRecoverable) {
  LabelDistribution d;
  ClassLogProbs certain;
  certain.fill(-INFINITY);
  certain[3] = 0.0f;
  d.Fuse(certain);  // "wall with probability 1": the others are floored at 1e-4, not -inf
  EXPECT_EQ(d.Label(), 3);
  EXPECT_NEAR(d.Probabilities()[0], 1e-4 / (1.0 + 18e-4), 1e-8);
  // Enough contrary evidence overturns it: three observations of road at 0.9.
  for (int i = 0; i < 3; ++i) d.FuseLabel(0, 0.9f);
  EXPECT_EQ(d.Label(), 0);
}

TEST(LabelDistribution, ManyObservationsStayFinite) {
  LabelDistribution d;
  for (int i = 0; i < 100000; ++i) d.FuseLabel(i % 3 == 0 ? 5 : 8, 0.9f);
  EXPECT_EQ(d.Label(), 8);
  EXPECT_NEAR(d.Confidence(), 1.0, 1e-6);
  for (float v : d.RelativeLogProbabilities()) {
    EXPECT_TRUE(std::isfinite(v));
    EXPECT_GE(v, LabelDistribution::kMinRelativeLogProbability);
  }
}

// Merging two points' posteriors (uniform prior, independent observations) equals fusing all observations
// into one.
TEST(LabelDistribution, MergeEqualsFusingAllObservations) {
  const ClassLogProbs o1 = Observation({{0, 0.6}, {1, 0.3}});
  const ClassLogProbs o2 = Observation({{0, 0.2}, {1, 0.7}});
  const ClassLogProbs o3 = Observation({{1, 0.5}, {9, 0.4}});
  LabelDistribution a, b, all;
  a.Fuse(o1);
  b.Fuse(o2);
  b.Fuse(o3);
  all.Fuse(o1);
  all.Fuse(o2);
  all.Fuse(o3);
  a.Merge(b);
  EXPECT_EQ(a.NumObservations(), 3);
  EXPECT_EQ(a.Label(), all.Label());
  for (int c = 0; c < kNumClasses; ++c) EXPECT_NEAR(a.Probabilities()[c], all.Probabilities()[c], 1e-6);
  // Merging an unobserved point changes nothing.
  LabelDistribution before = a;
  a.Merge(LabelDistribution());
  EXPECT_EQ(a, before);
}

TEST(LabelDistribution, SerializationRoundTrip) {
  LabelDistribution d;
  d.Fuse(Observation({{0, 0.6}, {1, 0.3}}));
  d.FuseLabel(11, 0.7f);
  const std::string bytes = d.ToBytes();
  EXPECT_EQ(bytes.size(), LabelDistribution::kSerializedBytes);
  EXPECT_EQ(LabelDistribution::FromBytes(bytes), d);
  BinaryWriter writer;
  d.AppendTo(writer);
  LabelDistribution().AppendTo(writer);
  BinaryReader reader(writer.bytes(), "memory");
  EXPECT_EQ(LabelDistribution::ReadFrom(reader), d);
  EXPECT_EQ(LabelDistribution::ReadFrom(reader), LabelDistribution());
  EXPECT_TRUE(reader.AtEnd());
  EXPECT_THROW(LabelDistribution::FromBytes(bytes.substr(1)), InvalidArgument);
  std::string bad = bytes;
  const float nan = NAN;
  std::memcpy(bad.data(), &nan, sizeof(float));
  EXPECT_THROW(LabelDistribution::FromBytes(bad), InvalidArgument);
  const std::string truncated = bytes.substr(0, 10);
  BinaryReader short_reader(truncated, "truncated");
  EXPECT_THROW(LabelDistribution::ReadFrom(short_reader), InputError);
}

// A 100x50 camera looking down +z; the segmentation says road on the left half and car on the right half,
// stored at half resolution (50x25) to exercise the mapping back to input pixels.
class KeyframeFusion : public ::testing::Test {
 protected:
  void SetUp() override {
    camera.width = 100;
    camera.height = 50;
    camera.fx = camera.fy = 50.0;
    camera.cx = 49.5;
    camera.cy = 24.5;
    cv::Mat labels(25, 50, CV_8UC1, cv::Scalar(0));
    labels.colRange(25, 50).setTo(13);
    labels.at<std::uint8_t>(0, 0) = kNoLabel;
    segmentation = Segmentation::FromLabels(labels, cv::Size(100, 50), 0.9f);
  }
  PinholeCamera camera;
  Segmentation segmentation;
};

TEST_F(KeyframeFusion, ProjectsSamplesAndFuses) {
  // The camera sits at world (0, 0, -10) looking along +z: camera_from_world translates by +10 in z.
  const Rigid3d camera_from_world(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0, 0, 10));
  std::vector<LabelDistribution> d(6);
  const std::vector<PointObservation> points = {
      {Eigen::Vector3d(-2, 0, 0), &d[0]},        // u = 50 * -2/10 + 49.5 = 39.5: road
      {Eigen::Vector3d(3, 1, 0), &d[1]},         // u = 64.5: car
      {Eigen::Vector3d(0, 0, -20), &d[2]},       // behind the camera
      {Eigen::Vector3d(30, 0, 0), &d[3]},        // u = 199.5: outside
      {Eigen::Vector3d(-9.8, -4.85, 0), &d[4]},  // pixel (0.5, 0.25): the unlabeled corner
      {Eigen::Vector3d(1, 1, 0), nullptr},       // skipped
  };
  const FusionStats stats = FuseKeyframeObservations(segmentation, camera_from_world, camera, points);
  EXPECT_EQ(stats.fused, 2);
  EXPECT_EQ(stats.behind, 1);
  EXPECT_EQ(stats.outside, 1);
  EXPECT_EQ(stats.unlabeled, 1);
  EXPECT_EQ(d[0].Label(), 0);
  EXPECT_NEAR(d[0].Confidence(), 0.9, 1e-6);
  EXPECT_EQ(d[1].Label(), 13);
  EXPECT_EQ(d[2].NumObservations(), 0);
  EXPECT_EQ(d[3].NumObservations(), 0);
  EXPECT_EQ(d[4].NumObservations(), 0);

  PinholeCamera wrong = camera;
  wrong.width = 200;
  EXPECT_THROW(FuseKeyframeObservations(segmentation, camera_from_world, wrong, points), InvalidArgument);
}

TEST_F(KeyframeFusion, PerKeypointSamplesFuseLater) {
  const std::vector<Eigen::Vector2f> pixels = {{10.0f, 20.0f}, {90.0f, 40.0f}, {0.2f, 0.4f}, {-3.0f, 5.0f}};
  std::vector<float> rows;
  EXPECT_EQ(SampleAtPixels(segmentation, pixels, &rows), 2);
  ASSERT_EQ(rows.size(), 4u * kNumClasses);
  EXPECT_TRUE(IsSampledObservation(&rows[0]));
  EXPECT_FALSE(IsSampledObservation(&rows[2 * kNumClasses]));
  EXPECT_FALSE(IsSampledObservation(&rows[3 * kNumClasses]));
  LabelDistribution road, car, none;
  EXPECT_TRUE(FuseSampledObservation(road, &rows[0]));
  EXPECT_TRUE(FuseSampledObservation(car, &rows[kNumClasses]));
  EXPECT_FALSE(FuseSampledObservation(none, &rows[2 * kNumClasses]));
  EXPECT_EQ(road.Label(), 0);
  EXPECT_EQ(car.Label(), 13);
  EXPECT_EQ(none.NumObservations(), 0);

  // Dynamic-class probability of the samples: car 0.9 + 7 other dynamic classes at 0.1/18 each.
  EXPECT_NEAR(DynamicProbability(&rows[kNumClasses]), 0.9 + 7 * 0.1 / 18, 1e-5);
  EXPECT_NEAR(DynamicProbability(&rows[0]), 8 * 0.1 / 18, 1e-5);
  EXPECT_EQ(DynamicProbability(&rows[2 * kNumClasses]), 0.0f);
  EXPECT_NEAR(car.DynamicProbability(), 0.9 + 7 * 0.1 / 18, 1e-5);
  EXPECT_EQ(none.DynamicProbability(), 0.0f);

  struct FakeKeypoint {
    Eigen::Vector2f pixel;
  };
  const std::vector<FakeKeypoint> keypoints = {{{80.0f, 10.0f}}};
  EXPECT_EQ(SampleAtKeypoints(
                segmentation, keypoints, [](const FakeKeypoint& k) { return k.pixel; }, &rows),
            1);
  EXPECT_NEAR(std::exp(rows[13]), 0.9, 1e-6);
}

}  // namespace
}  // namespace semslam
