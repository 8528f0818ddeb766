#pragma once
// The SLAM system: owns the map, the vocabulary and keyframe database, and the tracking, local-mapping and
// loop-closing modules (the last two in their own threads). The only place that knows them all.

#include <atomic>
#include <deque>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <opencv2/core/mat.hpp>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <unordered_map>

#include "semslam/core/timing.h"
#include "semslam/geo/frame_position.h"
#include "semslam/geo/gps_fusion.h"
#include "semslam/geometry/camera.h"
#include "semslam/geometry/trajectory.h"
#include "semslam/loop/loop_closer.h"
#include "semslam/map/map.h"
#include "semslam/map/map_file.h"
#include "semslam/mapping/local_mapper.h"
#include "semslam/mapping/map_optimization.h"
#include "semslam/semantics/segmentation_worker.h"
#include "semslam/system/merge_verifier.h"
#include "semslam/system/pacing.h"
#include "semslam/tracking/tracker.h"

namespace semslam {

class Vocabulary;
class KeyFrameDatabase;

enum class SensorMode { kMonocular, kStereo };

// How frames are fed: as fast as possible, at the camera's rate (timestamps), or synchronously: after every
// keyframe, waiting for the mapper and then the loop closer (a loop correction or merge and the global BA
// after it), and for the segmentation of every keyframe and tracked frame. Synchronous runs are reproducible:
// the same input, options and build give the same outputs, bit for bit, however busy the machine (for tests
// and evaluation).
enum class Pacing { kFast, kRealtime, kSynchronous };

// "mono"/"stereo" and "fast"/"realtime"/"synchronous", as on the command line and in config files;
// nullopt for anything else.
std::optional<SensorMode> ParseSensorMode(std::string_view name);
std::optional<Pacing> ParsePacing(std::string_view name);
std::string_view PacingName(Pacing pacing);

struct SlamOptions {
  // Sets tracker.monocular, mapper.monocular and loop.fix_scale (SlamSystem derives them).
  SensorMode mode = SensorMode::kMonocular;
  Pacing pacing = Pacing::kRealtime;
  TrackerOptions tracker;
  LocalMapperOptions mapper;
  LoopCloserOptions loop;
  std::filesystem::path vocabulary;  // empty: the default vocabulary
  bool localization_only = false;    // track against a loaded map without changing it
  // Keep points on moving classes (person, rider, vehicles) out of tracking, relocalization and new points;
  // takes effect once keyframes are segmented (EnableSegmentation).
  bool exclude_dynamic = false;
  // A full bundle adjustment of the whole map when the sequence ends (trajectories follow their keyframes).
  bool final_global_ba = true;
  // Monocular maps: that bundle adjustment also refines the intrinsics (mapping/map_optimization.h), since
  // monocular scale in slow turns is sensitive to a calibration a percent off.
  bool final_refine_intrinsics = true;
  // ... and keeps the refinement only when it lowers the robust reprojection cost by this share of it.
  double final_refine_intrinsics_min_reduction = 0.01;
  // ... and only in a map of at least this many keyframes.
  int final_refine_intrinsics_min_keyframes = 15;
  // Keyframes waiting for the mapper: with more, tracking waits for it (on a busy machine a mapper that falls
  // behind leaves tracking without the points it needs at the next turn). 0: never wait.
  int max_queued_keyframes = 2;
  // Realtime pacing: a frame due while the mapper still works on a keyframe waits for it, up to this many of
  // the camera's frame intervals past when it was due. The frames after a keyframe are then tracked in the
  // map that keyframe completes, as at synchronous pacing, wherever the machine keeps up, so that the
  // keyframes and points of a drive depend on pacing only where it does not. 0: never wait.
  double realtime_wait_for_mapping_frames = 1.0;
  int final_global_ba_iterations = 20;
  int final_global_ba_refine_iterations = 20;  // its second pass, without the outliers of the first

  void Check() const;
};

struct SlamStatistics {
  size_t frames = 0;
  size_t tracked = 0;       // frames tracked (or relocalized) in some map
  size_t with_pose = 0;     // frames with a pose in some map that is not a prediction
  size_t interpolated = 0;  // of those: frames between the two a monocular map was initialized from, which
                            // could not be tracked against it
  size_t predicted = 0;     // frames while lost: the motion model's pose
  size_t maps = 0;          // maps holding keyframes at the end
  size_t maps_started = 0;  // new maps after tracking was lost for good (the first map not counted)
  size_t merges = 0;        // maps merged into others
  size_t keyframes = 0;
  size_t map_points = 0;
  size_t keyframes_created = 0;  // culled ones included
  size_t points_created = 0;
  size_t loops = 0;
  size_t relocalizations = 0;
  size_t resets = 0;
  size_t segmented_keyframes = 0;  // keyframes whose segmentation was fused
  size_t segmented_frames = 0;     // other tracked frames segmented while the worker had time
};

// The camera a session's frames are undistorted with, once a map is loaded (SlamSystem::LoadMap).
struct TrackingCameraChoice {
  PinholeCamera camera;
  std::optional<std::uint32_t>
      map_id;  // the loaded map whose refined camera it is; nullopt: the sequence's own
  std::string reason;
};

// The loaded maps' camera, or the sequence's own. The map holding the most keyframes decides: its camera when
// it is a refinement (MapCamera::refined) of the sensor the sequence has, that is when the sequence's camera
// is the map's nominal one (same image size and distortion, fx, fy, cx, cy within `tolerance_px`; the
// distortion of an unrefined map is not compared, a version-2 file does not have it). A stereo session keeps
// its rectified pair's calibration. `other_sensor` tells a sequence of another camera than that map's.
TrackingCameraChoice ChooseTrackingCamera(const PinholeCamera& sequence, bool stereo,
                                          const std::map<std::uint32_t, MapCamera>& cameras,
                                          const std::map<std::uint32_t, size_t>& keyframes_per_map,
                                          bool* other_sensor = nullptr, double tolerance_px = 0.01);

class SlamSystem {
 public:
  SlamSystem(const SlamOptions& options, const PinholeCamera& camera, std::optional<StereoRig> stereo);
  ~SlamSystem();
  SlamSystem(const SlamSystem&) = delete;
  SlamSystem& operator=(const SlamSystem&) = delete;

  // Loads a map saved by SaveMap before the first frame and begins a new session in it; tracking then starts
  // by relocalizing (in any of its maps), with the camera ChooseTrackingCamera gives (a warning when the
  // sequence's camera is another sensor than the map's).
  MapFileContents LoadMap(const std::filesystem::path& path);
  // Adds a saved map's sessions and maps to this system's atlas, beside those it holds
  // (system/session_merge.h: maps of several drives merged into one); before the first frame, for a system
  // that tracks no frames.
  MapFileContents AppendMap(const std::filesystem::path& path);
  // The camera frames are undistorted with, and why.
  const TrackingCameraChoice& tracking_camera() const { return tracking_camera_; }
  // The camera of each map holding keyframes, as SaveMap writes it: a loaded map's, a refinement the final BA
  // kept (after Finish), or the camera this session tracks with.
  std::map<std::uint32_t, MapCamera> MapCameras() const;
  // Names the current session (the sequence this run reads).
  void NameSession(const std::string& name, const std::string& source);
  void SaveMap(const std::filesystem::path& path, const MapFileContents& extra = {}) const;

  // Segments keyframes with `segmenter` on a worker thread of its own (tracking never waits for it; when it
  // falls behind it takes the newest keyframe) and fuses each result into the map (paper §III-B): the points
  // the keyframe sees now, and those that gain an observation in it later. At synchronous pacing every
  // keyframe and tracked frame is segmented and fused, in frame order, before the next frame. Call before the
  // first frame.
  void EnableSegmentation(std::shared_ptr<Segmenter> segmenter);
  std::optional<SegmentationWorkerStats> SegmentationStats() const;
  // The final bundle adjustment's self-calibration, one entry per monocular map it ran on (after Finish).
  const std::vector<IntrinsicsRefinement>& IntrinsicsRefinements() const { return intrinsics_refinements_; }

  // `color`: the image the segmenter sees, 8-bit BGR of a colour camera (empty: `left`, grey).
  TrackingResult ProcessFrame(std::uint64_t frame_id, double timestamp, const cv::Mat& left,
                              const cv::Mat& right = {}, const cv::Mat& mask = {}, const cv::Mat& color = {});
  // Lets mapping and loop closing (and a running global BA) finish, then stops the threads.
  void Finish();

  // The map most of this run's frames were tracked in (after merges), whose frame the trajectories use.
  std::uint32_t MainMapId() const;
  // Frames of this run with a pose that is not a prediction, by map id.
  std::map<std::uint32_t, size_t> TrackedFramesPerMap() const;
  // Every frame of this run with a pose in the main map (tracked, or interpolated at initialization;
  // world_from_camera), following its reference keyframe's current pose.
  Trajectory FrameTrajectory() const;
  // This session's keyframes of the main map.
  Trajectory KeyFrameTrajectory() const;
  // The same with frame indices (and keyframe ids), in frame order.
  std::vector<FramePose> FramePoses() const;
  std::vector<FramePose> KeyFramePoses() const;
  // The same for one map of the atlas: this run's frames with a pose in it (not predicted), and its keyframes
  // of this session or, with `all_sessions`, of every session (a loaded map's too).
  std::vector<FramePose> FramePoses(std::uint32_t map_id) const;
  std::vector<FramePose> KeyFramePoses(std::uint32_t map_id, bool all_sessions) const;
  // Loop edges and strong covisibility links between `keyframes` (indices into it), with their current
  // relative poses.
  std::vector<FusionEdge> KeyFrameEdges(const std::vector<FramePose>& keyframes,
                                        int min_covisibility_weight = 100) const;
  // Every frame of this run that has a pose in some map (predicted ones included, and marked), in frame
  // order, each with its map id.
  std::vector<FramePose> AllFramePoses() const;
  // Loop edges and strong covisibility links between the keyframes of KeyFramePoses() (indices into it), with
  // their current relative poses: the map's own constraints for GPS fusion.
  std::vector<FusionEdge> KeyFrameEdges(int min_covisibility_weight = 100) const;
  SlamStatistics Statistics() const;
  std::vector<LoopEvent> Loops() const;
  std::vector<LoopEvent> Merges() const;

  Map& map() { return *map_; }
  const Map& map() const { return *map_; }
  LocalMapper& mapper() { return *mapper_; }
  LoopCloser& loop_closer() { return *loop_closer_; }
  const Vocabulary& vocabulary() const { return *vocabulary_; }
  TimingRegistry& timing() { return timing_; }
  const SlamOptions& options() const { return options_; }

 private:
  // Lost right after a map started: that map is given up (the others stay) and a new one starts.
  void DiscardActiveMap();
  // Synchronous pacing, after a frame: until the mapper has processed the keyframes it made and the loop
  // closer has acted on them (a loop's correction and global BA included).
  void WaitForMappingAndLoopClosing(const TrackingResult& result);
  void OnSegmentation(SegmentationResult&& result);
  void SubmitForSegmentation(std::uint64_t frame_id, const cv::Mat& left, const TrackingResult& result);
  // The camera of maps this session makes: the loaded map's whose camera it tracks with, or the sequence's.
  MapCamera SessionCamera() const;

  SlamOptions options_;
  PinholeCamera camera_;
  std::optional<StereoRig> stereo_;
  TimingRegistry timing_;
  std::unique_ptr<Vocabulary> vocabulary_;
  std::unique_ptr<KeyFrameDatabase> database_;
  std::unique_ptr<Map> map_;
  std::unique_ptr<LocalMapper> mapper_;
  std::unique_ptr<LoopCloser> loop_closer_;
  // Stereo: merges of the run's maps wait for a second place out of sight of the first (no map is in the
  // world during a run). A stereo merge is an SE(3) with nothing like a monocular one's scale to disagree
  // with the structure, and a look-alike block (towns repeat their facades) passes the loop closer's checks
  // at one place, not at two.
  std::set<std::uint32_t> no_world_maps_;
  std::unique_ptr<MergeVerifier> merge_verifier_;
  std::unique_ptr<Tracker> tracker_;
  size_t frames_ = 0;
  size_t tracked_ = 0;
  std::optional<double> last_timestamp_;  // of the last frame processed
  size_t resets_ = 0;
  RealtimePacer pacer_;
  bool finished_ = false;
  std::unique_ptr<SegmentationWorker> segmentation_;
  std::atomic<size_t> segmented_keyframes_{0};
  std::atomic<size_t> segmented_frames_{0};
  // Frames (not keyframes) sent to the segmentation worker, by request id: the points they matched and where.
  struct FrameObservations {
    std::vector<MapPoint*> points;
    std::vector<Eigen::Vector2f> pixels;
  };
  std::mutex pending_frames_mutex_;
  std::unordered_map<std::uint64_t, FrameObservations> pending_frames_;
  // The last frames' images: a monocular initialization makes a keyframe of an earlier frame.
  static constexpr size_t kRecentImages = 32;
  std::deque<std::pair<std::uint64_t, cv::Mat>> recent_images_;
  std::vector<IntrinsicsRefinement> intrinsics_refinements_;
  TrackingCameraChoice tracking_camera_;
  // Maps loaded, and maps whose refined camera the final BA kept; the others have this session's camera.
  std::map<std::uint32_t, MapCamera> map_cameras_;
};

}  // namespace semslam
