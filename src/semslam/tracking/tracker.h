#pragma once
// The tracking thread's work: features of each new frame, monocular or stereo initialization, camera
// pose from the motion model / the reference keyframe / the local map, keyframe decisions, and
// relocalization when tracking is lost. The caller (System) drives it frame by frame.

#include <cstdint>
#include <deque>
#include <limits>
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
  // A new keyframe is due when the frame tracks fewer than keyframe_tracked_ratio of the reference keyframe's
  // points and min_seconds have passed since the last one (max_seconds: whatever the ratio), or at once when
  // it tracks fewer than keyframe_collapse_ratio of them. In seconds of the frames' timestamps, not in
  // frames, so that at a lower frame rate, where the view changes more from frame to frame, keyframes still
  // come about as often per second. At 10 Hz these are 10 and 3 frames.
  double max_seconds_between_keyframes = 1.0;
  double min_seconds_between_keyframes = 0.3;
  double keyframe_tracked_ratio_mono = 0.9;
  double keyframe_tracked_ratio_stereo = 0.75;
  double keyframe_collapse_ratio_mono = 0.5;
  double keyframe_collapse_ratio_stereo = 0.25;
  // A monocular frame tracking fewer map points than this is weak: a keyframe is due without waiting
  // min_frames, so that new points come in as fast as the old ones leave the view (fast forward motion past
  // near foliage and parked cars). 0: off.
  int keyframe_weak_inliers_mono = 100;
  double close_depth_baselines = 40.0;  // stereo: points closer than this many baselines are "close"
  bool localization_only = false;       // track against the map without changing it
  // Keep map points whose fused label is a moving class (person, rider, vehicles) out of tracking and
  // relocalization (they need a segmenter to be known).
  bool exclude_dynamic = false;
  int init_min_matches = 100;
  // Initialization matches keypoints of levels [0, init_match_max_level], each within
  // init_match_level_difference levels of the other (forward motion changes the scale).
  int init_match_max_level = 2;
  int init_match_level_difference = 1;
  // Monocular initialization accepts a two-view reconstruction when the init_parallax_rank-th most
  // parallax-rich point has at least init_min_parallax_deg, no one part of the image counting for more than
  // its share (see geometry/two_view.h).
  double init_min_parallax_deg = 2.0;
  int init_parallax_rank = 50;
  int init_min_points = 100;  // well-triangulated points needed
  // Lost for this long (seconds) without relocalizing in the active map: a new map may start and the old one
  // is kept, to be merged when its places are seen again. Monocular re-initializes; stereo starts at once.
  // Until the new map has started, every frame tries relocalization in the lost map first: after a short
  // black-out the camera usually still sees what it saw last, and a map found again needs no merge.
  double relocalization_timeout_s = 1.0;
  // A map lost with at most this many keyframes is given up (discarded) instead of kept.
  int min_keyframes_to_keep_map = 6;
  // When the motion model keeps fewer than this share of the last frame's points, the motion changed (a stop,
  // a reversal) and the prediction may hold a wrong pose that far points agree with: the frame is also
  // matched to its reference keyframe without prediction, and the pose with more inliers is kept.
  double motion_model_min_kept_ratio = 0.5;

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
  // Lost right after initialization: the System should discard the active map (and a new one starts).
  bool reset_requested = false;
  bool new_map = false;  // lost for good: a new map was started with this frame
  int matched_points = 0;
  std::optional<Rigid3d> camera_from_world;
  std::uint32_t map_id = 0;   // the atlas map camera_from_world is in (when there is one)
  double milliseconds = 0.0;  // time spent tracking this frame (features included)
};

// How a frame got its pose.
enum class PoseProvenance : std::uint8_t {
  kNone,          // before the first map started
  kTracked,       // tracked (or relocalized) in a map
  kInterpolated,  // between the two frames a monocular map was initialized from
  kPredicted,     // lost: the motion model's prediction from the last tracked frame
};
const char* ToString(PoseProvenance source);

// One entry per processed frame, to rebuild the trajectory after loop closure: the pose relative to a
// reference keyframe, which keeps following its keyframe when the map is optimized or merged.
struct FrameRecord {
  std::uint64_t frame_id = 0;
  double timestamp = 0.0;
  KeyFrame* reference = nullptr;  // nullptr when the frame has no pose
  Rigid3d camera_from_reference;
  // The reference's scale_correction() when camera_from_reference was taken: a monocular loop or merge that
  // rescales the map around the keyframe rescales the frame's offset from it too.
  double reference_scale = 1.0;
  PoseProvenance source = PoseProvenance::kNone;
};

// The frame's pose in its map as it stands now (through its reference keyframe, or the nearest parent of a
// culled one); nullopt when the frame has no pose or its map was discarded. Read lock on the map held by
// the caller.
std::optional<Rigid3d> CurrentCameraFromWorld(const FrameRecord& record);
// The keyframe a record's pose hangs from now (its reference, or the nearest good ancestor of a culled one);
// nullptr when there is none. Read lock on the map held by the caller.
const KeyFrame* CurrentReference(const FrameRecord& record);

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
  // Starts from a loaded map: the next frame is relocalized (in any of its maps) instead of initializing.
  void SetMapLoaded();
  // The camera frames are undistorted with (a loaded map's refined one, SlamSystem::LoadMap); before the first
  // frame.
  void SetCamera(const PinholeCamera& camera);
  // Forgets the tracking state (the frame records stay); the System has discarded the active map and
  // started a new one.
  void Reset();
  int num_new_maps() const { return num_new_maps_; }

 private:
  std::shared_ptr<const FrameData> ExtractFeatures(const cv::Mat& left, const cv::Mat& right,
                                                   const cv::Mat& mask, bool initialization);
  bool InitializeMonocular(Frame& frame);
  // Tracks a frame in the map it was tracked in last (motion model or reference keyframe), or relocalizes it,
  // then against the local map; on success the map found is the active one and a keyframe is made when one
  // is due.
  bool TrackInMap(Frame& frame, TrackingResult& result);
  bool InitializeStereo(Frame& frame);
  // Inliers matched to the reference keyframe by bag of words, from the last frame's pose; 0 when it fails.
  int TrackReferenceKeyFrame(Frame& frame);
  // Inliers among the last frame's points matched from a predicted pose, the pose then optimized; 0 when
  // it fails or cannot keep more than `more_than`.
  int TrackFromPrediction(Frame& frame, const Rigid3d& camera_from_world, int more_than = 0);
  // The same from `predicted` turned about the camera centre: no turn since the last frame, and pitch and
  // heading one and two search windows either way. The frame keeps the pose with the most inliers; 0 when
  // none keeps more than `more_than`.
  int TrackWithTurnedPredictions(Frame& frame, const Rigid3d& predicted, int more_than);
  // The constant-velocity prediction; where it keeps few of the last frame's points, a turned prediction
  // that keeps clearly more, then the reference keyframe by bag of words (tracker_motion.cc).
  bool TrackWithMotionModelOrReference(Frame& frame);
  bool TrackLocalMap(Frame& frame);
  bool Relocalize(Frame& frame);
  // A frame tracked on under half the last frame's inliers may be far from where the motion model put it
  // (frames dropped or cut from the recording): relocalized by appearance, it takes that pose when the local
  // map confirms it with more inliers. Call after TrackLocalMap succeeded; true when the frame was
  // relocalized.
  bool RelocalizeAfterCollapse(Frame& frame, int last_inliers);
  // Lost for good: a new map is made active (stereo initializes it from `frame` at once); until it starts,
  // frames are relocalized in the lost map first.
  void StartNewMap(Frame& frame, TrackingResult& result);
  // A map initialized from `frame` (monocular: with an earlier one); counts the maps started after a loss.
  bool InitializeMap(Frame& frame);
  // The new map's first keyframe, linked to the lost map where the motion before the loss puts it (GapLink).
  void LinkNewMapToLostMap(const Frame& frame);
  // Beyond this many steps of the last motion (10 s at 10 Hz) a lost camera's prediction stays where it is.
  static constexpr int kMaxPredictedSteps = 100;
  // The record of a frame without a tracked pose, `frames` after the last tracked one: the motion model's
  // prediction, when there is one.
  void PredictPose(FrameRecord& record, int frames) const;
  // Steps of the last motion from the last tracked frame to one at `timestamp`, `frames` later: by the clock
  // (dropped frames leave a gap in time), else by frames.
  double StepsSinceTracked(double timestamp, int frames) const;
  // The map moved (a loop correction, a merge, a global BA) after this frame was tracked, once the tracking
  // lock was released: the frame follows its reference keyframe. Call under a map lock.
  void FollowMapChange(Frame& frame) const;
  // Back to "not initialized" in the active map: no last frame, motion, keyframes or local map. The last
  // tracked pose stays (lost frames are still predicted from it) unless Reset() drops it too.
  void ForgetTrackingState();
  // Frames between the two a monocular map was initialized from get poses in it: tracked against the second
  // keyframe from a pose interpolated between the two, or that interpolated pose.
  void PoseInitializationFrames(KeyFrame* first, KeyFrame* second);
  void UpdateLocalMap(Frame& frame);
  void SearchLocalMapPoints(Frame& frame);
  int OptimizeFramePose(Frame& frame);
  bool NeedNewKeyFrame(const Frame& frame) const;
  // Whether `elapsed` seconds between two frames' timestamps reach `seconds` (tracker_keyframes.cc).
  static bool SecondsReached(double elapsed, double seconds);
  void CreateNewKeyFrame(Frame& frame);
  // Queues the keyframes this frame made in the mapper (at the end of Track()).
  void HandKeyFramesToMapper();
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
  // The current frame's pose relative to its reference keyframe, taken under the lock it was tracked (or made
  // a keyframe) under: what the frame keeps when the map moves before its pose is recorded. Reset by each
  // Track().
  std::optional<Rigid3d> tracked_camera_from_reference_;
  std::uint64_t last_relocalization_frame_ = 0;
  // When the last relocalization was (frame timestamp); -inf before the first.
  double last_relocalization_time_ = -std::numeric_limits<double>::infinity();
  // The last relocalization was a recovery: within reach of the motion model's prediction after a short
  // loss. The local map then confirms it with fewer inliers, and keyframes need not wait: right after a gap a
  // monocular map holds few points the camera still sees, and only a keyframe adds more.
  bool last_relocalization_recovered_ = false;
  KeyFrame* last_keyframe_ = nullptr;
  KeyFrame* reference_keyframe_ = nullptr;
  std::vector<KeyFrame*> local_keyframes_;
  std::vector<MapPoint*> local_points_;
  int inliers_ = 0;
  // The last frame's inliers when TrackInMap tracked it, else 0 (a map's first frame counts its points, not
  // inliers of a pose optimization).
  int last_tracked_inliers_ = 0;
  int num_relocalizations_ = 0;
  int num_new_maps_ = 0;
  bool map_loaded_ = false;
  // Since when tracking is lost (timestamp of the first lost frame), and the last tracked frame's pose and
  // motion, from which lost frames are predicted.
  std::optional<double> lost_since_;
  FrameRecord last_tracked_;  // its reference is nullptr while no frame was tracked
  std::optional<Rigid3d> last_velocity_;
  double last_step_seconds_ = 0.0;  // between the last two tracked frames: the time last_velocity_ covers
  int frames_since_tracked_ = 0;
  // Where tracking was in the map lost for good, while the map after it has not started (or was given up
  // young): relocalization there comes first. `record_index` is the last tracked frame's record.
  struct LostMap {
    FrameRecord last_tracked;
    std::optional<Rigid3d> velocity;
    double step_seconds = 0.0;
    size_t record_index = 0;
  };
  std::optional<LostMap> lost_map_;

  // Monocular initialization state: the first frame, where its features were seen last, and the frames
  // since (posed once the map starts).
  std::unique_ptr<Frame> init_frame_;
  std::vector<Eigen::Vector2f> init_prior_positions_;
  static constexpr size_t kMaxBetweenFrames = 40;
  std::deque<Frame> init_between_frames_;

  std::vector<FrameRecord> records_;
  std::vector<NewKeyFrame> new_keyframes_;  // of the frame being tracked
  // The frame's new keyframes reach the mapper only once the frame's record is taken: a local BA of a
  // keyframe already queued could otherwise move it between the two, and the frame's pose relative to its
  // own keyframe would depend on the threads' timing, at synchronous pacing too.
  std::vector<KeyFrame*> keyframes_for_mapper_;
  bool holding_mapper_ = false;  // SetNotStop(true) since CreateNewKeyFrame, until the hand-over
};

}  // namespace semslam
