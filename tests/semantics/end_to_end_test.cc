// Simulated end to end: ~2000 map points with known classes in a small analytic street, observed by 15
// keyframes whose segmentations are the true label images through truth-noisy:0.25 (single frames 75 %
// right). Bayesian fusion must label >= 95 % of the points right.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <optional>
#include <random>
#include <vector>

#include "semslam/semantics/label_fusion.h"
#include "semslam/semantics/segmenter.h"
#include "semslam/semantics/semantic_outputs.h"
#include "support/test_support.h"

namespace semslam {
namespace {

struct Box {
  Eigen::Vector3d min, max;
  int label;
};

// A straight street (world = first camera: x right, y down, z forward; the ground at y = 1.65): road,
// sidewalks, terrain, facades on both sides (building / vegetation / fence / wall by stretch), parked cars,
// poles with signs.
class Street {
 public:
  Street() {
    boxes_.push_back({{-3.3, 0.15, 14.0}, {-1.6, 1.65, 18.5}, TrainId(SemanticClass::kCar)});
    boxes_.push_back({{1.8, 0.2, 30.0}, {3.5, 1.65, 34.5}, TrainId(SemanticClass::kCar)});
    boxes_.push_back({{-4.0, -1.6, 40.0}, {-1.4, 1.65, 48.0}, TrainId(SemanticClass::kTruck)});
    for (int k = 0; k < 5; ++k) {
      const double z = 6.0 + 11.0 * k;
      const double side = k % 2 == 0 ? 1.0 : -1.0;
      const double x = side * 6.9;
      boxes_.push_back({{x - 0.1, -3.5, z}, {x + 0.1, 1.65, z + 0.2}, TrainId(SemanticClass::kPole)});
      boxes_.push_back({{x - 0.5, -4.4, z - 0.05}, {x + 0.5, -3.5, z}, TrainId(SemanticClass::kTrafficSign)});
    }
  }

  // Class and distance along the ray of the first surface hit; nullopt for sky.
  std::optional<std::pair<int, double>> Cast(const Eigen::Vector3d& o, const Eigen::Vector3d& d) const {
    double best = INFINITY;
    int label = -1;
    const auto consider = [&](double t, int l) {
      if (t > 1e-6 && t < best) {
        best = t;
        label = l;
      }
    };
    if (d.y() > 0) {
      const double t = (kGround - o.y()) / d.y();
      const double x = std::abs(o.x() + t * d.x());
      consider(t, x < 3.5   ? TrainId(SemanticClass::kRoad)
                  : x < 6.5 ? TrainId(SemanticClass::kSidewalk)
                            : TrainId(SemanticClass::kTerrain));
    }
    for (double side : {-1.0, 1.0}) {
      if (d.x() * side <= 0) continue;
      const double t = (side * kFacade - o.x()) / d.x();
      const Eigen::Vector3d p = o + t * d;
      if (p.y() < kFacadeTop || p.y() > kGround) continue;
      consider(t, FacadeClass(side, p.z()));
    }
    for (const Box& b : boxes_) {
      double t0 = 0, t1 = INFINITY;
      for (int a = 0; a < 3; ++a) {
        if (std::abs(d[a]) < 1e-12) {
          if (o[a] < b.min[a] || o[a] > b.max[a]) t0 = INFINITY;
          continue;
        }
        double ta = (b.min[a] - o[a]) / d[a], tb = (b.max[a] - o[a]) / d[a];
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
      }
      if (t0 <= t1) consider(t0, b.label);
    }
    if (label < 0) return std::nullopt;
    return std::make_pair(label, best);
  }

 private:
  static int FacadeClass(double side, double z) {
    const double m = std::fmod(std::max(z, 0.0), 24.0);
    if (side < 0) return m < 15 ? TrainId(SemanticClass::kBuilding) : TrainId(SemanticClass::kVegetation);
    return m < 12   ? TrainId(SemanticClass::kBuilding)
           : m < 17 ? TrainId(SemanticClass::kFence)
                    : TrainId(SemanticClass::kWall);
  }
  static constexpr double kGround = 1.65, kFacade = 9.0, kFacadeTop = -10.0;
  std::vector<Box> boxes_;
};

struct Keyframe {
  Rigid3d world_from_camera;
  cv::Mat labels;  // CV_8U trainIds, 255 = sky (no 3D point there)
  cv::Mat depth;   // CV_32F camera depth, 0 = sky
};

TEST(SemanticsEndToEnd, FusedLabelsBeatNoisySingleFrames) {
  PinholeCamera camera;  // KITTI at half resolution
  camera.width = 620;
  camera.height = 188;
  camera.fx = camera.fy = 359.0;
  camera.cx = 309.5;
  camera.cy = 93.5;
  const Street street;
  const int num_keyframes = 15;
  testing::TempDir dir;

  std::vector<Keyframe> keyframes(num_keyframes);
  for (int k = 0; k < num_keyframes; ++k) {
    const double yaw = 0.05 * std::sin(0.7 * k);
    const Eigen::Vector3d center(0.3 * std::sin(0.4 * k), 0.0, 2.0 * k);
    Keyframe& kf = keyframes[static_cast<size_t>(k)];
    kf.world_from_camera =
        Rigid3d(Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY())), center);
    kf.labels = cv::Mat(camera.height, camera.width, CV_8UC1, cv::Scalar(TrainId(SemanticClass::kSky)));
    kf.depth = cv::Mat(camera.height, camera.width, CV_32FC1, cv::Scalar(0.0f));
    const Eigen::Matrix3d r = kf.world_from_camera.rotation.toRotationMatrix();
    for (int v = 0; v < camera.height; ++v) {
      for (int u = 0; u < camera.width; ++u) {
        const Eigen::Vector3d ray((u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy, 1.0);
        if (const auto hit = street.Cast(center, r * ray)) {
          kf.labels.at<std::uint8_t>(v, u) = static_cast<std::uint8_t>(hit->first);
          kf.depth.at<float>(v, u) = static_cast<float>(hit->second);  // ray has z = 1: t is the depth
        }
      }
    }
    ASSERT_TRUE(cv::imwrite((dir / cv::format("%06d.png", k)).string(), kf.labels));
  }

  // Map points where random pixels of random keyframes hit a surface, at most 300 per class.
  struct Point {
    Eigen::Vector3d position;
    int truth;
  };
  std::vector<Point> points;
  std::vector<int> per_class(kNumClasses, 0);
  std::mt19937 rng(42);
  std::uniform_int_distribution<int> pick_kf(0, num_keyframes - 1), pick_u(0, camera.width - 1),
      pick_v(0, camera.height - 1);
  for (int attempt = 0; attempt < 400000 && points.size() < 2000; ++attempt) {
    const Keyframe& kf = keyframes[static_cast<size_t>(pick_kf(rng))];
    const int u = pick_u(rng), v = pick_v(rng);
    const float depth = kf.depth.at<float>(v, u);
    const int label = kf.labels.at<std::uint8_t>(v, u);
    if (depth <= 0.0f || depth > 60.0f || per_class[static_cast<size_t>(label)] >= 300) continue;
    ++per_class[static_cast<size_t>(label)];
    points.push_back({kf.world_from_camera * camera.UnprojectDepth(Eigen::Vector2d(u, v), depth), label});
  }
  ASSERT_GE(points.size(), 1800u);

  SegmenterContext context;
  context.truth_label_dir = dir.path();
  auto segmenter = MakeSegmenter("truth-noisy:0.25", context);
  std::vector<LabelDistribution> fused(points.size());
  std::vector<int> single_total(kNumClasses, 0), single_right(kNumClasses, 0);
  int total_observations = 0;
  for (int k = 0; k < num_keyframes; ++k) {
    const Keyframe& kf = keyframes[static_cast<size_t>(k)];
    const Segmentation segmentation = segmenter->Segment(cv::Mat(), k);
    const Rigid3d camera_from_world = kf.world_from_camera.Inverse();
    // The points this keyframe observes: in the image and not occluded (as feature matches would be).
    std::vector<PointObservation> observed;
    for (size_t i = 0; i < points.size(); ++i) {
      const Eigen::Vector3d c = camera_from_world * points[i].position;
      if (c.z() <= 0.1) continue;
      const auto pixel = camera.ProjectIfVisible(c);
      if (!pixel) continue;
      const float depth = kf.depth.at<float>(static_cast<int>(std::lround(pixel->y())),
                                             static_cast<int>(std::lround(pixel->x())));
      if (std::abs(depth - c.z()) > 0.03 * c.z() + 0.05) continue;
      observed.push_back({points[i].position, &fused[i]});
      const int t = points[i].truth;
      ++single_total[static_cast<size_t>(t)];
      if (segmentation.LabelAt(static_cast<float>(pixel->x()), static_cast<float>(pixel->y())) == t) {
        ++single_right[static_cast<size_t>(t)];
      }
    }
    const FusionStats stats = FuseKeyframeObservations(segmentation, camera_from_world, camera, observed);
    EXPECT_EQ(stats.fused, static_cast<int>(observed.size()));
    total_observations += stats.fused;
  }

  std::vector<SemanticPoint> semantic(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    semantic[i] = {points[i].position, fused[i].Label(), fused[i].Confidence(), fused[i].NumObservations()};
  }
  const LabelAccuracy accuracy =
      EvaluatePointLabels(semantic, [&](const Eigen::Vector3d& p) -> std::optional<int> {
        for (const Point& q : points) {
          if (q.position == p) return q.truth;
        }
        return std::nullopt;
      });
  int single_all = 0, single_all_right = 0;
  std::printf("%-14s %6s %12s %12s\n", "class", "points", "single-frame", "fused");
  for (int c = 0; c < kNumClasses; ++c) {
    if (single_total[static_cast<size_t>(c)] == 0) continue;
    single_all += single_total[static_cast<size_t>(c)];
    single_all_right += single_right[static_cast<size_t>(c)];
    std::printf(
        "%-14s %6llu %12.3f %12.3f\n", std::string(ClassName(c)).c_str(),
        static_cast<unsigned long long>(accuracy.class_evaluated[static_cast<size_t>(c)]),
        static_cast<double>(single_right[static_cast<size_t>(c)]) / single_total[static_cast<size_t>(c)],
        accuracy.ClassAccuracy(c).value_or(0.0));
  }
  const double single = static_cast<double>(single_all_right) / single_all;
  std::printf("%-14s %6llu %12.3f %12.3f   (%.1f observations per point, %llu unobserved)\n", "all",
              static_cast<unsigned long long>(accuracy.evaluated), single, accuracy.Accuracy(),
              static_cast<double>(total_observations) / static_cast<double>(points.size()),
              static_cast<unsigned long long>(accuracy.unlabeled));
  // A SLAM map keeps points seen by at least 3 keyframes; points seen once or twice cannot out-vote a wrong
  // label.
  int kept = 0, kept_right = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    if (fused[i].NumObservations() < 3) continue;
    ++kept;
    kept_right += fused[i].Label() == points[i].truth ? 1 : 0;
  }
  std::printf("points seen by >= 3 keyframes: %d, fused accuracy %.3f\n", kept,
              static_cast<double>(kept_right) / kept);
  EXPECT_NEAR(single, 0.75, 0.04);
  EXPECT_GE(accuracy.Accuracy(), 0.95);
  EXPECT_LE(accuracy.unlabeled, points.size() / 100);
  RecordProperty("single_frame_accuracy", std::to_string(single));
  RecordProperty("fused_accuracy", std::to_string(accuracy.Accuracy()));
}

}  // namespace
}  // namespace semslam
