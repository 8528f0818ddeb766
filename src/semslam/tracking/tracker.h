#pragma once
// The tracking thread's work: features of each new frame, monocular or stereo initialization, camera
// pose from the motion model / the reference keyframe / the local map, keyframe decisions, and
// relocalization when tracking is lost. The caller (System) drives it frame by frame.

#include <cstdint>
#include <memory>
#include <opencv2/core/mat.hpp>
#include <optional>
#include <vector>

#include "semslam/core/timing.h"
#include "semslam/features/orb_extractor.h"
#include "semslam/geometry/camera.h"
#include "semslam/map/frame.h"
#include "semslam/map/map.h"

namespace semslam {

class Vocabulary;
class KeyFrameDatabase;
class LocalMapper;

struct TrackerOptions {
  bool monocular = true;
  OrbOptions orb;             // for tracking frames
  int init_num_features = 0;  // features for monocular initialization frames (0 = 2 x orb.num_features)
  // Initialization frames share features among levels by area: the fine levels keep the near points whose
  // parallax the two-view test needs (by side length, the 200-frame city initialized at frame 14, not 0).
  double init_level_share_exponent = 2.0;
  int max_frames_between_keyframes = 10;  // usually the frame rate
  // A new keyframe is due when the frame tracks fewer than this share of the reference keyframe's points.
  double keyframe_tracked_ratio_mono = 0.9;
  double keyframe_tracked_ratio_stereo = 0.75;
  int min_frames_between_keyframes = 0;
  double close_depth_baselines = 40.0;  // stereo: points closer than this many baselines are "close"
  bool localization_only = false;       // track against the map without changing it
  // Keep map points whose fused label is a moving class (person, rider, vehicles) out of tracking and
  // relocalization (they need a segmenter to be known).
  bool exclude_dynamic = false;
  int init_min_matches = 100;
  // Monocular initialization accepts a two-view reconstruction when the init_parallax_rank-th most
  // parallax-rich point has at least init_min_parallax_deg (see geometry/two_view.h).
  double init_min_parallax_deg = 2.0;
  int init_parallax_rank = 50;
  int init_min_points = 100;  // well-triangulated points needed

  void Check() const;
};

enum class TrackingState { kNotInitialized, kOk, kLost };
const char* ToString(TrackingState state);

// A keyframe made while tracking a frame, and the frame it was made of (monocular initialization makes the
// first keyframe of an earlier frame).
struct NewKeyFrame {
  std::uint64_t keyframe_id = 0;
  std::uint64_t frame_id = 0;
};

// What happened to one frame.
struct TrackingResult {
  TrackingState state = TrackingState::kNotInitialized;
  bool initialized_now = false;
  bool relocalized = false;
  bool new_keyframe = false;
  std::vector<NewKeyFrame> new_keyframes;  // including those of an initialization
  bool reset_requested = false;            // lost right after initialization: the System should reset the map
  int matched_points = 0;
  std::optional<Rigid3d> camera_from_world;
  double milliseconds = 0.0;  // time spent tracking this frame (features included)
};

// One entry per processed frame, to rebuild the trajectory after loop closure: the pose relative to a
// reference keyframe, which keeps following its keyframe when the map is optimized.
struct FrameRecord {
  std::uint64_t frame_id = 0;
  double timestamp = 0.0;
  KeyFrame* reference = nullptr;  // nullptr when the frame was not tracked
  Rigid3d camera_from_reference;
};

// The frame's pose in the map as it stands now (through its reference keyframe, or the nearest parent of a
// culled one); nullopt when the frame was not tracked. Read lock on the map held by the caller.
std::optional<Rigid3d> CurrentCameraFromWorld(const FrameRecord& record);

class Tracker {
 public:
  Tracker(const TrackerOptions& options, const PinholeCamera& camera, std::optional<StereoRig> stereo,
          Map& map, const Vocabulary& vocabulary, KeyFrameDatabase& database, LocalMapper* mapper,
          TimingRegistry& timing);
  ~Tracker();

  // Tracks one frame. `right` is empty for monocular input; `mask` (optional, 8-bit, non-zero = keep)
  // excludes image regions from feature extraction.
  TrackingResult Track(std::uint64_t frame_id, double timestamp, const cv::Mat& left,
                       const cv::Mat& right = {}, const cv::Mat& mask = {});

  TrackingState state() const { return state_; }
  const std::vector<FrameRecord>& records() const { return records_; }
  // The frame tracked last (its matches to map points, outliers removed); nullptr before the first.
  const Frame* last_frame() const { return last_frame_.get(); }
  int num_relocalizations() const { return num_relocalizations_; }
  // Starts from a loaded map: the next frame is relocalized instead of initializing.
  void SetMapLoaded();
  // Forgets the tracking state; the System clears the map and the other threads alongside.
  void Reset();

 private:
  std::shared_ptr<const FrameData> ExtractFeatures(const cv::Mat& left, const cv::Mat& right,
                                                   const cv::Mat& mask, bool initialization);
  bool InitializeMonocular(Frame& frame);
  bool InitializeStereo(Frame& frame);
  bool TrackReferenceKeyFrame(Frame& frame);
  bool TrackWithMotionModel(Frame& frame);
  bool TrackLocalMap(Frame& frame);
  bool Relocalize(Frame& frame);
  void UpdateLocalMap(Frame& frame);
  void SearchLocalMapPoints(Frame& frame);
  int OptimizeFramePose(Frame& frame);
  bool NeedNewKeyFrame(const Frame& frame) const;
  void CreateNewKeyFrame(Frame& frame);
  void ComputeBow(Frame& frame) const;
  // Clears the matches pose optimization rejected; returns the matches left to points in the map.
  int DiscardOutliers(Frame& frame) const;
  // Clears matches to moving points when exclude_dynamic is set; returns the matches left.
  int DropDynamicMatches(Frame& frame) const;
  void ReplaceMergedPoints(Frame& frame) const;

  TrackerOptions options_;
  PinholeCamera camera_;
  std::optional<StereoRig> stereo_;
  Map& map_;
  const Vocabulary& vocabulary_;
  KeyFrameDatabase& database_;
  LocalMapper* mapper_;
  TimingRegistry& timing_;
  std::unique_ptr<OrbExtractor> extractor_;
  std::unique_ptr<OrbExtractor> right_extractor_;
  std::unique_ptr<OrbExtractor> init_extractor_;

  TrackingState state_ = TrackingState::kNotInitialized;
  std::unique_ptr<Frame> last_frame_;
  std::optional<Rigid3d> velocity_;  // current_from_last of the previous step
  int last_big_change_ = 0;
  std::uint64_t last_relocalization_frame_ = 0;
  KeyFrame* last_keyframe_ = nullptr;
  KeyFrame* reference_keyframe_ = nullptr;
  std::vector<KeyFrame*> local_keyframes_;
  std::vector<MapPoint*> local_points_;
  int inliers_ = 0;
  int num_relocalizations_ = 0;
  bool map_loaded_ = false;

  // Monocular initialization state.
  std::unique_ptr<Frame> init_frame_;
  std::vector<Eigen::Vector2f> init_prior_positions_;

  std::vector<FrameRecord> records_;
  std::vector<NewKeyFrame> new_keyframes_;  // of the frame being tracked
};

}  // namespace semslam
