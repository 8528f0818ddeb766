#pragma once
// The loop-closing thread: detects when the camera returns to a mapped place (bag-of-words candidates with
// covisibility consistency over consecutive keyframes), computes the Sim(3) (monocular) or SE(3) (stereo)
// between the two ends, verifies it in the current keyframe's neighbours and against the odometry between
// the two ends (how far it moves and turns the keyframe), fuses the duplicated points,
// corrects the essential graph, and refines the whole map with a global bundle adjustment in the
// background. A place of another map of the atlas (see map/map.h) merges the two maps: the active one is
// moved into the other's frame by the same transform, then corrected as a loop.

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <mutex>
#include <set>
#include <thread>
#include <utility>
#include <vector>

#include "semslam/core/timing.h"
#include "semslam/geometry/sim3.h"
#include "semslam/map/by_id.h"
#include "semslam/map/map.h"

namespace semslam {

// The rigid camera_from_world a corrected Sim(3) one stands for: the same camera, its map's scale divided
// out.
Rigid3d RigidPose(const Sim3d& camera_from_world);

// How far a loop's correction moves and turns a keyframe: from its pose `before` to the corrected
// camera_from_world `after` (whose scale, for a monocular map, is the map's, not the keyframe's), and the
// scale it gives the keyframe's side of the map (1 for stereo).
struct LoopCorrectionSize {
  double metres = 0.0;
  double degrees = 0.0;
  double scale = 1.0;
};
LoopCorrectionSize MeasureCorrection(const Rigid3d& before, const Sim3d& after);

class Vocabulary;
class KeyFrameDatabase;
class LocalMapper;

struct LoopCloserOptions {
  bool fix_scale = false;         // stereo: SE(3) loops
  int consistency_threshold = 3;  // consecutive consistent detections before a loop is tried
  int min_keyframes_between_loops = 10;
  int min_bow_matches = 20;
  int min_sim3_inliers = 20;
  int min_projected_matches = 40;
  // Geometric verification: the matched place, moved by the loop's transform, must also be found in this
  // many of the current keyframe's best covisible keyframes (up to 5 are tried), with at least
  // verification_matches matches each. A place that only looks the same (a repeated facade) agrees with
  // one view, not with the views around it.
  int min_verified_neighbours = 2;
  int verification_matches = 20;
  // The refined transform must agree with both keyframes' own 3D points: the median depth of the matched
  // points it maps into the current keyframe within this factor of their own (MedianDepthRatio). Reprojection
  // leaves the scale free where the two keyframes stand close together, and a merge refined to scale 0.000
  // collapsed a whole map onto a point (the cut KITTI drive, one core busy).
  double max_depth_ratio = 1.5;
  // Monocular: a transform refined by reprojection whose matched points land farther than this factor from
  // their own depth is refined again with its scale held at the one the two structures give
  // (RefineSim3KeepingStructureScale). Where the two keyframes stand close together, the refinement's scale
  // wanders: seed 4711's merge came out at 0.96-1.04 with the points at 1.29-1.41 times their depth (the
  // structures: 0.75-0.80), and the younger map, merged a third too large, ended 1.24-1.42 m off (0.55-0.85 m
  // over eight runs merged at the structures' scale). Of 393 loop and merge transforms logged, 382 kept their
  // points within 1.10.
  double max_refined_depth_ratio = 1.15;
  // Stereo only (a metric map, whose odometry drifts by a fraction of a percent): a loop within one map may
  // move the current keyframe by at most this share of the odometry between it and the matched keyframe
  // (the shortest chain of essential-graph links, see KeyFrameGraphDistance), plus
  // stereo_correction_slack_m. A larger jump means a place that looks the same elsewhere (towns repeat).
  // 3 % is several times what stereo odometry drifts on a busy machine, and keeps out a look-alike block
  // one street away while the odometry between the two is under a kilometre. Maps to merge share no
  // odometry.
  double max_stereo_correction_ratio = 0.03;
  double stereo_correction_slack_m = 3.0;
  // Monocular: a loop within one map may move the current keyframe by at most this share of the odometry
  // between the two keyframes (map units) plus the share its own scale explains, max(s, 1/s) - 1 for a loop
  // of scale s (a scale that drifted to s along the path puts the path's far end off by up to that share of
  // it), plus mono_correction_slack_depths times the keyframe's median scene depth (a Sim(3)'s error grows
  // with the depth of the points it comes from, and that depth is what a monocular map's unit means: loops
  // between two merged drives, joined by little more than the merge's link, move their keyframe by that).
  double max_mono_correction_ratio = 0.03;
  double mono_correction_slack_depths = 0.25;
  // A loop within one map may turn the current keyframe by at most this much. Odometry's heading drifts by
  // a few degrees where its length may drift by percents (monocular scale); a look-alike seen across a
  // crossing is off by the angle between the streets (a stereo loop at a corner that would have moved the
  // keyframe 12 m and turned it 90 degrees passed the length bound). Stereo: the slack plus a rate per 100 m
  // of odometry, far above the under 1 degree that the true loops measured so far turned their keyframe;
  // monocular, whose odometry has no metric length: a fixed bound.
  double stereo_rotation_slack_deg = 5.0;
  double max_stereo_rotation_deg_per_100m = 2.0;
  double max_mono_loop_rotation_deg = 30.0;
  bool merge_maps = true;  // merge maps of the atlas when a place of another one is recognized
  bool global_ba = true;
  // Run that BA at a lower priority than tracking and local mapping. SlamSystem clears it at synchronous
  // pacing, where tracking waits for the BA: there it would only yield to other processes.
  bool global_ba_low_priority = true;
  int global_ba_iterations = 10;
  // Keyframes one global BA (after a loop, and at the end of a run) optimizes together at most: a larger map
  // is adjusted in windows, which bounds the solver's memory (mapping/map_optimization.h).
  int global_ba_window_keyframes = 1000;
  bool enabled = true;

  void Check() const;
  // The bounds above for a loop whose two ends are odometry_m apart along the map's links (metres, or a
  // monocular map's units; the monocular rotation bound does not use it).
  double MaxStereoCorrectionM(double odometry_m) const;
  double MaxMonoCorrection(double odometry, double loop_scale, double scene_depth) const;
  // The move bound of this map's kind: stereo or monocular (which uses loop_scale and scene_depth).
  double MaxCorrection(double odometry, double loop_scale, double scene_depth) const;
  double MaxRotationDeg(double odometry_m) const;
  // Whether a loop within one map of that odometry may make this correction (within both bounds);
  // scene_depth, the current keyframe's median scene depth, sets the monocular slack.
  bool AllowsCorrection(const LoopCorrectionSize& correction, double odometry_m, double scene_depth) const;
};

struct LoopEvent {
  std::uint64_t query_keyframe = 0;
  std::uint64_t matched_keyframe = 0;
  double query_timestamp = 0.0;
  double matched_timestamp = 0.0;  // when the matched place was seen
  int matches = 0;
  int verified_neighbours = 0;  // covisible keyframes that confirmed the place
  double scale = 1.0;           // of the correction (monocular drift) or of the merged map
  double correction_m = 0.0;    // how far the query keyframe moved
  double correction_deg = 0.0;  // and how far it turned
  bool merge = false;           // a merge of two maps rather than a loop in one
  std::uint32_t map_id = 0;     // the query keyframe's map (the one merged away, for a merge)
  std::uint32_t matched_map_id = 0;
};

class LoopCloser {
 public:
  LoopCloser(const LoopCloserOptions& options, Map& map, const Vocabulary& vocabulary,
             KeyFrameDatabase& database, LocalMapper& mapper, TimingRegistry& timing);
  ~LoopCloser();

  void Start();
  void RequestFinish();
  void Join();

  void InsertKeyFrame(KeyFrame* keyframe);
  // Whether a verified place between two drives goes ahead: the current keyframe, the matched one (of another
  // map, or of another session of the same map) and the transform that would take the current keyframe's map
  // into the matched one's frame (for a loop: the current keyframe's correction).
  using PlaceCheck = std::function<bool(const KeyFrame& current, const KeyFrame& matched,
                                        const Sim3d& matched_from_current_map)>;
  // Keyframes a place is not looked for among.
  struct PlaceExclusions {
    std::set<std::uint32_t> maps;
    std::set<std::uint32_t> sessions;
  };
  // What the thread does with a keyframe, in the caller's thread, for a closer not started (merging saved
  // maps): detection among keyframes not `excluded`, then verification, `place_check` for a merge or a loop
  // between sessions, and correction. Returns whether a loop or merge was made.
  bool ProcessKeyFrame(KeyFrame* current, const PlaceExclusions& excluded = {},
                       const PlaceCheck& place_check = {});
  // The place check of the thread's own keyframes (none: every verified place goes ahead). Before Start.
  void SetPlaceCheck(PlaceCheck place_check) { place_check_ = std::move(place_check); }
  // Forgets the consistency groups of earlier keyframes (before keyframes that do not follow them).
  void ForgetCandidates();
  // Blocks until the queue is empty and no global BA is running.
  void WaitUntilIdle();
  void Reset();

  std::vector<LoopEvent> loops() const;   // loops closed within a map
  std::vector<LoopEvent> merges() const;  // maps merged
  int num_global_ba() const { return num_global_ba_.load(); }

 private:
  void Run();
  bool DetectLoop(KeyFrame* current, const PlaceExclusions& excluded);
  bool ComputeSim3(KeyFrame* current);
  // How many of the current keyframe's best covisibles find loop_points_ where current_from_world_ puts them.
  int CountVerifiedNeighbours(const KeyFrame* current) const;
  // Whether the refined transform agrees with both keyframes' 3D points (options_.max_depth_ratio); `matches`
  // holds the candidate's point for each of the current keyframe's features, or nullptr.
  bool AgreesWithStructure(const KeyFrame& current, const KeyFrame& candidate,
                           const std::vector<MapPoint*>& matches, const Sim3d& current_from_candidate) const;
  // Refines the RANSAC's `current_from_candidate` by reprojection: RefineSim3 for a stereo map,
  // RefineSim3KeepingStructureScale (options_.max_refined_depth_ratio) for a monocular one. Clears the
  // outliers from `matches`; returns the inlier count.
  int RefineLoopSim3(const KeyFrame& current, const KeyFrame& candidate, std::vector<MapPoint*>& matches,
                     Sim3d* current_from_candidate) const;
  bool CorrectionAgreesWithOdometry(const KeyFrame* current, const KeyFrame* candidate) const;
  // Moves the current keyframe's map into the matched keyframe's frame (write lock held); returns the
  // event's scale.
  double MoveMapToMatchedFrame(KeyFrame* current);
  void CorrectLoop(KeyFrame* current);
  // By keyframe id: the order the correction moves points, fuses duplicates and adds graph edges in.
  using PosesById = std::map<KeyFrame*, Sim3d, ById>;
  using LinksById = std::map<KeyFrame*, std::set<KeyFrame*, ById>, ById>;
  void OptimizeEssentialGraph(KeyFrame* loop_keyframe, KeyFrame* current, const PosesById& non_corrected,
                              const PosesById& corrected, const LinksById& loop_connections);
  void RunGlobalBundleAdjustment(std::uint64_t loop_keyframe_id, std::uint32_t map_id);
  void StopGlobalBundleAdjustment();

  LoopCloserOptions options_;
  Map& map_;
  const Vocabulary& vocabulary_;
  KeyFrameDatabase& database_;
  LocalMapper& mapper_;
  TimingRegistry& timing_;

  mutable std::mutex queue_mutex_;
  std::condition_variable queue_cv_;
  std::deque<KeyFrame*> queue_;
  bool busy_ = false;
  std::atomic<bool> finish_requested_{false};
  std::thread thread_;

  // Detection state.
  struct ConsistentGroup {
    std::set<KeyFrame*> keyframes;
    int consistency = 0;
  };
  std::vector<ConsistentGroup> consistent_groups_;
  std::vector<KeyFrame*> enough_consistent_candidates_;
  std::uint64_t last_loop_keyframe_id_ = 0;
  PlaceCheck place_check_;

  // The loop found by ComputeSim3.
  KeyFrame* matched_keyframe_ = nullptr;
  Sim3d current_from_world_;  // corrected pose of the current keyframe (Scw)
  std::vector<MapPoint*> current_matched_points_;
  std::vector<MapPoint*> loop_points_;
  int last_matches_ = 0;
  int last_verified_ = 0;

  mutable std::mutex loops_mutex_;
  std::vector<LoopEvent> events_;  // loops and merges, in order

  std::thread global_ba_thread_;
  std::atomic<bool> global_ba_running_{false};
  std::atomic<bool> global_ba_abort_{false};
  std::atomic<int> num_global_ba_{0};
};

}  // namespace semslam
