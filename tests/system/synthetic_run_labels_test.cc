// The labels of the synthetic runs' maps (synthetic_run_test.cc), judged against the city's label images
// and its surfaces: fusion over frames, the semantic PLY against run.json, and each point's class against
// the surface it lies on.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <set>

#include "semslam/eval/trajectory_metrics.h"
#include "semslam/io/sequence.h"
#include "semslam/io/trajectory_io.h"
#include "semslam/semantics/class_table.h"
#include "semslam/semantics/semantic_outputs.h"
#include "semslam/sim/scene_file.h"
#include "semslam/sim/synthetic_city.h"
#include "support/test_support.h"
#include "system_test_util.h"

namespace semslam::system_test {
namespace {

using ::testing::HasSubstr;

class SyntheticRunLabels : public ::testing::Test {
 protected:
  void SetUp() override { SEMSLAM_REQUIRE_BINARY(); }
};

TEST_F(SyntheticRunLabels, FusedLabelsAreRightWhereSingleFramesAreNot) {
  SEMSLAM_ASSERT_ARTIFACT(run, MonoRun());
  const nlohmann::json j = ReadJson(run / "run.json");
  ASSERT_TRUE(j.contains("label_evaluation")) << j.dump(2);
  const nlohmann::json& le = j["label_evaluation"];
  const double fused = le["fused_points"]["accuracy"].get<double>();
  const double single = le["single_frame_keypoints"]["accuracy"].get<double>();
  EXPECT_GE(fused, 0.95);           // measured 0.966
  EXPECT_NEAR(single, 0.75, 0.02);  // measured 0.749
  EXPECT_GE(le["fused_points"]["evaluated"].get<double>(), 0.9 * j["points"].get<double>());
  EXPECT_GE(le["keyframes"].get<int>(), j["keyframes"].get<int>() * 9 / 10);
  EXPECT_EQ(j["segmentation"].value("failed", -1), 0);
  EXPECT_THAT(j["segmentation"].value("segmenter", ""), HasSubstr("truth-noisy"));
  EXPECT_NEAR(j.value("label_accuracy_2d", -1.0), fused, 1e-12);
  // The headline is the user's measure: the surface each point lies on, the whole map placed by one alignment
  // (semantic_evaluation.h).
  EXPECT_NEAR(j.value("label_accuracy", -1.0), j.value("label_accuracy_3d_global", -2.0), 1e-12);
  // By the 3D measure, most labelled points are checked against a surface; points near a class boundary are
  // the hard ones; the whole map aligned at once reads lower (the trajectory's error moves each projection).
  ASSERT_TRUE(le.contains("surface_points")) << le.dump(2);
  const nlohmann::json& surface = le["surface_points"];
  EXPECT_GE(j.value("label_accuracy_3d", -1.0), 0.93);  // measured 0.960 (2D 0.970, global alignment 0.933)
  EXPECT_GE(surface["evaluated"].get<double>(), 0.6 * j["points"].get<double>());
  EXPECT_GT(surface["off_boundary"]["accuracy"].get<double>(),
            surface["on_boundary"]["accuracy"].get<double>());
  EXPECT_EQ(surface["off_boundary"]["evaluated"].get<int>() + surface["on_boundary"]["evaluated"].get<int>(),
            surface["evaluated"].get<int>());
  EXPECT_LT(j.value("label_accuracy_3d_global", 2.0), j.value("label_accuracy_3d", -1.0));
  EXPECT_GE(surface["labelled_as"]["road"]["road"].get<int>(), 20);
  // The classes the street is made of are there.
  for (const char* key : {"road", "sidewalk", "building", "car", "pole"}) {
    EXPECT_GE(le["fused_points"]["per_class"][key]["evaluated"].get<int>(), 20) << key;
  }
  EXPECT_GE(le["fused_points"]["per_class"]["road"]["accuracy"].get<double>(), 0.9);
  EXPECT_GE(le["fused_points"]["per_class"]["building"]["accuracy"].get<double>(), 0.9);
}

TEST_F(SyntheticRunLabels, SemanticPlyHasTheLabelsAndCountsOfRunJson) {
  SEMSLAM_ASSERT_ARTIFACT(run, MonoRun());
  const nlohmann::json j = ReadJson(run / "run.json");
  const std::vector<SemanticPoint> points = ReadSemanticPly(run / "semantic_map.ply");
  ASSERT_FALSE(points.empty());
  const ClassCounts counts = CountLabels(points);
  for (int c = 0; c < kNumClasses; ++c) {
    EXPECT_EQ(counts[static_cast<size_t>(c)], j["classes"][std::string(ClassKey(c))].get<std::uint64_t>())
        << ClassKey(c);
  }
  EXPECT_EQ(counts[kNumClasses], j["classes"]["unlabeled"].get<std::uint64_t>());
  size_t labeled = 0;
  for (const SemanticPoint& p : points) {
    ASSERT_TRUE(p.position.allFinite());
    if (!IsValidTrainId(p.label)) continue;
    ++labeled;
    EXPECT_GT(p.confidence, 0.0f);
    EXPECT_LE(p.confidence, 1.0f + 1e-6f);
    EXPECT_GE(p.observations, 1);
  }
  EXPECT_GE(labeled, points.size() * 99 / 100);
}

// The map itself against the ground truth, independently of the system's own evaluation: aligned to the world
// by the trajectory's Sim(3), each map point is projected into the keyframes' true cameras; where the
// rendered depth there agrees with the point's (the point is on the surface the camera sees), the rendered
// label is a vote for the point's true class. Objects' centroids must lie in objects of their class.
TEST_F(SyntheticRunLabels, SemanticMapAgreesWithTheScene) {
  SEMSLAM_ASSERT_ARTIFACT(data, SyntheticDataset());
  SEMSLAM_ASSERT_ARTIFACT(run, MonoRun());
  const TrajectoryEvaluation evaluation = EvaluateTrajectoryFiles(
      run / "trajectory.tum", data / "poses" / "00.txt", SequenceDir(data) / "times.txt");
  const Sim3d world_from_map = evaluation.ate.truth_from_estimate;
  const std::unique_ptr<ImageSequence> sequence = OpenSequence(SequenceDir(data));
  const PinholeCamera& camera = sequence->camera();
  const std::optional<Trajectory> truth = sequence->GroundTruth();
  ASSERT_TRUE(truth && sequence->LabelDirectory() && sequence->DepthDirectory());
  const std::vector<SemanticPoint> points = ReadSemanticPly(run / "semantic_map.ply");
  std::vector<Eigen::Vector3d> world;
  for (const SemanticPoint& p : points) world.push_back(world_from_map * p.position);

  const Trajectory keyframes = ReadTumTrajectory(run / "keyframes.tum");
  std::vector<double> stamps;
  for (const StampedPose& k : keyframes) stamps.push_back(k.timestamp);
  // Per point: the true labels where a keyframe sees it on its surface (votes), and whether its own label is
  // within a pixel of where it projects (keypoints sit on corners, often on a class boundary).
  std::vector<std::array<int, kNumClasses>> votes(points.size());
  std::vector<int> views(points.size(), 0), near_views(points.size(), 0);
  for (const int frame : FrameIndices(stamps, ReadTimes(SequenceDir(data) / "times.txt"))) {
    ASSERT_GE(frame, 0);
    const std::string file = cv::format("%06d.png", frame);
    const cv::Mat labels = cv::imread((*sequence->LabelDirectory() / file).string(), cv::IMREAD_UNCHANGED);
    const cv::Mat depth = cv::imread((*sequence->DepthDirectory() / file).string(), cv::IMREAD_UNCHANGED);
    ASSERT_EQ(labels.type(), CV_8UC1) << file;
    ASSERT_EQ(depth.type(), CV_16UC1) << file;
    const Rigid3d camera_from_world = (*truth)[static_cast<size_t>(frame)].world_from_camera.Inverse();
    for (size_t i = 0; i < points.size(); ++i) {
      if (!IsValidTrainId(points[i].label)) continue;
      const Eigen::Vector3d c = camera_from_world * world[i];
      if (c.z() < 1.0) continue;
      const auto pixel = camera.ProjectIfVisible(c, 2.0);
      if (!pixel) continue;
      const int u = static_cast<int>(std::lround(pixel->x())), v = static_cast<int>(std::lround(pixel->y()));
      const double z = depth.at<std::uint16_t>(v, u) / 256.0;
      if (z <= 0.0 || std::abs(z - c.z()) > 0.1 + 0.03 * c.z()) continue;  // sky, occluded or off the surface
      const int label = labels.at<std::uint8_t>(v, u);
      if (!IsValidTrainId(label)) continue;
      ++votes[i][static_cast<size_t>(label)];
      ++views[i];
      bool near = false;
      for (int dv = -1; dv <= 1; ++dv) {
        for (int du = -1; du <= 1; ++du)
          near = near || labels.at<std::uint8_t>(v + dv, u + du) == points[i].label;
      }
      if (near) ++near_views[i];
    }
  }
  size_t seen = 0, right = 0, right_within_a_pixel = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    if (views[i] == 0) continue;
    ++seen;
    const int majority =
        static_cast<int>(std::max_element(votes[i].begin(), votes[i].end()) - votes[i].begin());
    if (majority == points[i].label) ++right;
    if (2 * near_views[i] > views[i]) ++right_within_a_pixel;
  }
  const double accuracy = seen ? static_cast<double>(right) / static_cast<double>(seen) : 0.0;
  const double lenient = seen ? static_cast<double>(right_within_a_pixel) / static_cast<double>(seen) : 0.0;
  RecordProperty("points_on_a_seen_surface", std::to_string(seen) + "/" + std::to_string(points.size()));
  RecordProperty("label_accuracy_of_those", std::to_string(accuracy));
  RecordProperty("label_accuracy_within_a_pixel", std::to_string(lenient));
  // Measured over seeds 1-3: 76-78 % of the points on a seen surface; their labels 88-91 % the true one by
  // majority over the views, 93-95 % within a pixel of where they project (keypoints sit on corners, and a
  // point a few centimetres off projects across the class boundary).
  EXPECT_GE(seen, points.size() * 65 / 100)
      << seen << " of " << points.size() << " points lie on a seen surface";
  EXPECT_GE(accuracy, 0.80) << right << " of " << seen;
  EXPECT_GE(lenient, 0.90) << right_within_a_pixel << " of " << seen;

  const sim::SyntheticCity city(sim::ReadSceneOptions(data / "scene.json"));
  const nlohmann::json objects = ReadJson(run / "objects.json");
  ASSERT_TRUE(objects.is_object() && objects.contains("objects"));
  EXPECT_EQ(objects.value("frame", ""), "map");
  int checked = 0, on_class = 0;
  for (const nlohmann::json& o : objects["objects"]) {
    const std::string cls = o.value("class", "");
    const auto id = TrainIdFromName(cls);
    ASSERT_TRUE(id.has_value()) << cls;
    if (cls == "road" || cls == "sidewalk" || cls == "building") continue;  // large, centroids anywhere
    const auto& c = o["centroid_map"];
    const Eigen::Vector3d centroid(c[0].get<double>(), c[1].get<double>(), c[2].get<double>());
    const sim::SurfaceClass surface = city.ClassAt(world_from_map * centroid);
    ++checked;
    if (surface.label == *id && surface.distance < 1.5) ++on_class;
  }
  RecordProperty("objects_on_their_class", std::to_string(on_class) + "/" + std::to_string(checked));
  EXPECT_GE(checked, 10);
  EXPECT_GE(on_class, checked * 6 / 10) << on_class << " of " << checked;  // measured 49 of 58
}

// GPS (1 m noise, a fix every frame, sampled every 30 frames) and the landmark catalogue.

}  // namespace
}  // namespace semslam::system_test
