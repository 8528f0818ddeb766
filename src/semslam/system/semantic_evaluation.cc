#include "semslam/system/semantic_evaluation.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <optional>
#include <unordered_map>

#include "semslam/core/error.h"

namespace semslam {
namespace {

cv::Mat ReadTruthImage(const std::filesystem::path& dir, std::uint64_t frame, const PinholeCamera& camera,
                       int type, const char* what) {
  const std::filesystem::path path = dir / fmt::format("{:06d}.png", frame);
  cv::Mat image = cv::imread(path.string(), cv::IMREAD_UNCHANGED);
  if (image.empty()) throw InputError(path, std::string("cannot read the ground-truth ") + what + " image");
  if (image.type() != type || image.cols != camera.width || image.rows != camera.height) {
    throw InputError(path, fmt::format("expected a {}-bit {}x{} {} image", type == CV_8UC1 ? 8 : 16,
                                       camera.width, camera.height, what));
  }
  return image;
}

cv::Mat ReadTrueLabels(const std::filesystem::path& label_dir, std::uint64_t frame,
                       const PinholeCamera& camera) {
  return ReadTruthImage(label_dir, frame, camera, CV_8UC1, "label");
}

// The true pose at `timestamp` (within a millisecond), if the truth has one.
std::optional<Rigid3d> TruePose(const Trajectory& truth, double timestamp) {
  const auto it = std::lower_bound(truth.begin(), truth.end(), timestamp - 1e-3,
                                   [](const StampedPose& p, double t) { return p.timestamp < t; });
  if (it == truth.end() || std::abs(it->timestamp - timestamp) > 1e-3) return std::nullopt;
  return it->world_from_camera;
}

int ArgMax(const ClassLogProbs& values) {
  return static_cast<int>(std::max_element(values.begin(), values.end()) - values.begin());
}

}  // namespace

SemanticEvaluation EvaluateSemantics(const Map& map, const std::filesystem::path& label_dir) {
  auto lock = map.ReadLock();
  SemanticEvaluation result;
  // Votes of the observing keyframes for each point's true class.
  std::unordered_map<const MapPoint*, std::array<std::uint16_t, kNumClasses>> votes;
  for (const KeyFrame* kf : map.KeyFrames()) {
    if (kf->keypoint_labels.empty()) continue;
    const cv::Mat truth = ReadTrueLabels(label_dir, kf->frame_id(), kf->camera());
    ++result.keyframes;
    const auto& keypoints = kf->features().keypoints;
    for (size_t i = 0; i < keypoints.size(); ++i) {
      const int u = std::clamp(static_cast<int>(std::lround(keypoints[i].pixel.x())), 0, truth.cols - 1);
      const int v = std::clamp(static_cast<int>(std::lround(keypoints[i].pixel.y())), 0, truth.rows - 1);
      const int true_class = truth.at<std::uint8_t>(v, u);
      if (!IsValidTrainId(true_class)) continue;
      ClassLogProbs observation;
      if (kf->keypoint_labels.Get(i, &observation))
        result.single_frame.Add(true_class, ArgMax(observation) == true_class);
      const MapPoint* point = kf->map_point(static_cast<int>(i));
      if (point != nullptr && !point->is_bad()) ++votes[point][static_cast<size_t>(true_class)];
    }
  }
  for (const auto& [point, counts] : votes) {
    const int true_class = static_cast<int>(std::max_element(counts.begin(), counts.end()) - counts.begin());
    const int label = point->labels().Label();
    if (!IsValidTrainId(label)) {
      ++result.points_unlabeled;
      continue;
    }
    result.fused.Add(true_class, label == true_class);
  }
  return result;
}

void SurfaceEvaluationOptions::Check() const {
  Require(std::isfinite(depth_tolerance) && depth_tolerance > 0.0,
          "SurfaceEvaluationOptions: depth_tolerance must be > 0");
  Require(boundary_radius >= 0, "SurfaceEvaluationOptions: boundary_radius must be >= 0");
  Require(keyframe_window >= 0, "SurfaceEvaluationOptions: keyframe_window must be >= 0");
}

namespace {

// True-class votes of one map point under one way of placing it in the truth frames.
struct Votes {
  std::array<std::uint16_t, kNumClasses> count{};
  bool boundary = false;
};

// One truth frame: its labels and depth, and how a map point lands in it.
struct TruthView {
  const cv::Mat& labels;
  const cv::Mat& depth;
  const PinholeCamera& camera;
  int boundary_radius;
  double depth_tolerance;

  // Votes for the true class where `in_camera` (metres, this camera's frame) lies on the surface the camera
  // sees; nothing when it is outside the image, on the sky, occluded, or off the surface.
  void Vote(const Eigen::Vector3d& in_camera, Votes& votes) const {
    if (!(in_camera.z() > 0.0)) return;
    const auto pixel = camera.ProjectIfVisible(in_camera);
    if (!pixel) return;
    const int u = static_cast<int>(std::lround(pixel->x())), v = static_cast<int>(std::lround(pixel->y()));
    const double true_depth = depth.at<std::uint16_t>(v, u) / 256.0;
    if (true_depth <= 0.0 || std::abs(in_camera.z() - true_depth) > depth_tolerance * true_depth) return;
    const int true_class = labels.at<std::uint8_t>(v, u);
    if (!IsValidTrainId(true_class)) return;
    ++votes.count[static_cast<size_t>(true_class)];
    const int r = boundary_radius;
    for (int dv = -r; dv <= r && !votes.boundary; ++dv) {
      for (int du = -r; du <= r; ++du) {
        const int x = std::clamp(u + du, 0, labels.cols - 1), y = std::clamp(v + dv, 0, labels.rows - 1);
        if (labels.at<std::uint8_t>(y, x) != true_class) {
          votes.boundary = true;
          break;
        }
      }
    }
  }
};

// Median of true depth / map depth over a keyframe's own points (at their keypoints): the local scale of a
// monocular map, which drifts along the trajectory. 0 when too few points tell.
double LocalScale(const KeyFrame& kf, const cv::Mat& depth) {
  std::vector<double> ratios;
  const auto& keypoints = kf.features().keypoints;
  for (size_t i = 0; i < keypoints.size(); ++i) {
    const MapPoint* point = kf.map_point(static_cast<int>(i));
    if (point == nullptr || point->is_bad()) continue;
    const double z = (kf.camera_from_world() * point->position()).z();
    const int u = static_cast<int>(std::lround(keypoints[i].pixel.x()));
    const int v = static_cast<int>(std::lround(keypoints[i].pixel.y()));
    if (z <= 0.0 || u < 0 || v < 0 || u >= depth.cols || v >= depth.rows) continue;
    const double true_depth = depth.at<std::uint16_t>(v, u) / 256.0;
    if (true_depth > 0.0) ratios.push_back(true_depth / z);
  }
  if (ratios.size() < 10) return 0.0;
  const auto middle = ratios.begin() + static_cast<std::ptrdiff_t>(ratios.size() / 2);
  std::nth_element(ratios.begin(), middle, ratios.end());
  return *middle;
}

void Tally(const std::unordered_map<const MapPoint*, Votes>& votes,
           const std::vector<const MapPoint*>& labelled, SurfaceScores& scores) {
  for (const auto& [point, vote] : votes) {
    const auto best = std::max_element(vote.count.begin(), vote.count.end());
    const int true_class = static_cast<int>(best - vote.count.begin());
    int frames = 0;
    for (std::uint16_t c : vote.count) frames += c;
    if (frames == 0) continue;
    const bool boundary = vote.boundary || *best < frames;  // near another class, or the frames disagree
    const int label = point->labels().Label();
    if (!IsValidTrainId(label)) {
      ++scores.points_unlabeled;
      continue;
    }
    const bool right = label == true_class;
    scores.points.Add(true_class, right);
    (boundary ? scores.on_boundary : scores.off_boundary).Add(true_class, right);
    ++scores.confusion[static_cast<size_t>(true_class)][static_cast<size_t>(label)];
  }
  for (const MapPoint* point : labelled) {
    const auto it = votes.find(point);
    int frames = 0;
    if (it != votes.end()) {
      for (std::uint16_t c : it->second.count) frames += c;
    }
    if (frames == 0) ++scores.points_unverified;
  }
}

}  // namespace

SurfaceEvaluation EvaluateSemantics3d(const Map& map, const SurfaceTruth& truth,
                                      const SurfaceEvaluationOptions& options) {
  options.Check();
  Trajectory sorted = truth.truth;
  std::sort(sorted.begin(), sorted.end(),
            [](const StampedPose& a, const StampedPose& b) { return a.timestamp < b.timestamp; });
  auto lock = map.ReadLock();
  // Each point is checked in the keyframes from `keyframe_window` before its first observing keyframe to as
  // many after its last: wherever it can be seen, whether or not its feature was matched there.
  struct Candidate {
    const MapPoint* point;
    std::uint64_t first, last;  // keyframe ids
  };
  std::vector<Candidate> candidates;
  std::vector<const MapPoint*> labelled;
  const auto window = static_cast<std::uint64_t>(options.keyframe_window);
  for (const MapPoint* point : map.MapPoints()) {
    if (point->is_bad() || point->observations().empty()) continue;
    std::uint64_t first = UINT64_MAX, last = 0;
    for (const auto& [kf, index] : point->observations()) {
      first = std::min(first, kf->id());
      last = std::max(last, kf->id());
    }
    candidates.push_back({point, first > window ? first - window : 0, last + window});
    if (IsValidTrainId(point->labels().Label())) labelled.push_back(point);
  }
  std::unordered_map<const MapPoint*, Votes> per_frame, global;
  SurfaceEvaluation result;
  for (const KeyFrame* kf : map.KeyFrames()) {
    if (kf->is_bad()) continue;
    const std::optional<Rigid3d> world_from_camera = TruePose(sorted, kf->timestamp());
    if (!world_from_camera) continue;
    const PinholeCamera& camera = kf->camera();
    const cv::Mat labels = ReadTrueLabels(truth.label_dir, kf->frame_id(), camera);
    const cv::Mat depth = ReadTruthImage(truth.depth_dir, kf->frame_id(), camera, CV_16UC1, "depth");
    // A metric map (stereo) keeps scale 1; a monocular one has its own, drifting scale.
    const double scale = truth.metric ? 1.0 : LocalScale(*kf, depth);
    if (scale <= 0.0) continue;
    ++result.keyframes;
    const TruthView view{labels, depth, camera, options.boundary_radius, options.depth_tolerance};
    const Rigid3d true_camera_from_world = world_from_camera->Inverse();
    for (const Candidate& c : candidates) {
      if (kf->id() < c.first || kf->id() > c.last) continue;
      // Per frame: the keyframe's estimated camera put onto its true one. Global: the whole map aligned once.
      view.Vote(scale * (kf->camera_from_world() * c.point->position()), per_frame[c.point]);
      view.Vote(true_camera_from_world * (truth.truth_from_map * c.point->position()), global[c.point]);
    }
  }
  Tally(per_frame, labelled, result.per_frame);
  Tally(global, labelled, result.global);
  return result;
}

}  // namespace semslam
