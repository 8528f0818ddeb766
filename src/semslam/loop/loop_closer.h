#pragma once
// The loop-closing thread: detects when the camera returns to a mapped place (bag-of-words candidates with
// covisibility consistency over consecutive keyframes), computes the Sim(3) (monocular) or SE(3) (stereo)
// between the two ends, fuses the duplicated points, corrects the essential graph, and refines the whole
// map with a global bundle adjustment in the background.

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <map>
#include <mutex>
#include <set>
#include <thread>
#include <vector>

#include "semslam/core/timing.h"
#include "semslam/geometry/sim3.h"
#include "semslam/map/map.h"

namespace semslam {

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
  // A loop may correct the current keyframe by at most this fraction of the distance driven since the matched
  // keyframe, and turn it by at most max_correction_deg: drift grows with distance (a few percent, monocular
  // scale drift included), while a place that only looks the same (repeated facades, symmetric crossings)
  // asks for a jump.
  double max_correction_ratio = 0.1;
  double max_correction_deg = 20.0;
  bool global_ba = true;
  int global_ba_iterations = 10;
  bool enabled = true;

  void Check() const;
};

struct LoopEvent {
  std::uint64_t query_keyframe = 0;
  std::uint64_t matched_keyframe = 0;
  double query_timestamp = 0.0;
  int matches = 0;
  double scale = 1.0;         // of the correction (monocular drift)
  double correction_m = 0.0;  // how far the query keyframe moved
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
  // Blocks until the queue is empty and no global BA is running.
  void WaitUntilIdle();
  void Reset();

  std::vector<LoopEvent> loops() const;
  int num_global_ba() const { return num_global_ba_.load(); }

 private:
  void Run();
  bool DetectLoop(KeyFrame* current);
  bool ComputeSim3(KeyFrame* current);
  bool CorrectionIsPlausible(const KeyFrame* current, const KeyFrame* candidate,
                             const Sim3d& corrected_current_from_world) const;
  void CorrectLoop(KeyFrame* current);
  void OptimizeEssentialGraph(KeyFrame* loop_keyframe, KeyFrame* current,
                              const std::map<KeyFrame*, Sim3d>& non_corrected,
                              const std::map<KeyFrame*, Sim3d>& corrected,
                              const std::map<KeyFrame*, std::set<KeyFrame*>>& loop_connections);
  void RunGlobalBundleAdjustment(std::uint64_t loop_keyframe_id);
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

  // The loop found by ComputeSim3.
  KeyFrame* matched_keyframe_ = nullptr;
  Sim3d current_from_world_;  // corrected pose of the current keyframe (Scw)
  std::vector<MapPoint*> current_matched_points_;
  std::vector<MapPoint*> loop_points_;
  int last_matches_ = 0;

  mutable std::mutex loops_mutex_;
  std::vector<LoopEvent> loops_;

  std::thread global_ba_thread_;
  std::atomic<bool> global_ba_running_{false};
  std::atomic<bool> global_ba_abort_{false};
  std::atomic<int> num_global_ba_{0};
};

}  // namespace semslam
