#pragma once
// The local-mapping thread: takes the keyframes tracking creates, links them into the map, triangulates
// new points against covisible keyframes, fuses duplicates, runs local bundle adjustment, and culls
// bad points and redundant keyframes. Hands each processed keyframe to the loop closer.

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

#include "semslam/core/timing.h"
#include "semslam/map/map.h"

namespace semslam {

class Vocabulary;
class KeyFrameDatabase;

struct LocalMapperOptions {
  bool monocular = true;
  double close_depth_baselines = 40.0;  // stereo: "close" points, as in tracking
  int triangulation_neighbours_mono = 20;
  int triangulation_neighbours_stereo = 10;
  double redundant_keyframe_ratio =
      0.9;  // a keyframe is culled when this share of its points is seen elsewhere
  int local_ba_iterations = 5;
  double min_parallax_deg = 1.15;  // monocular triangulation: rays closer than this give no new point
  // No new points from keypoints a segmentation labeled as moving classes.
  bool exclude_dynamic = false;  // first pass; a second pass of twice as many follows without outliers
  // Cut a keyframe's work short (triangulation with further neighbours, fusion, local BA) when newer
  // keyframes wait, and abort a local BA when one arrives. SlamSystem clears it at synchronous pacing, where
  // what the mapper does with a keyframe must not depend on when the next one was queued.
  bool yield_to_new_keyframes = true;

  void Check() const;
};

class LocalMapper {
 public:
  LocalMapper(const LocalMapperOptions& options, Map& map, const Vocabulary& vocabulary,
              KeyFrameDatabase& database, TimingRegistry& timing);
  ~LocalMapper();

  // Called with each keyframe after it is processed (the loop closer, the segmentation scheduler, ...).
  void AddKeyFrameListener(std::function<void(KeyFrame*)> listener);

  void Start();
  void RequestFinish();  // finishes the queue first, then stops the thread
  void Join();

  void InsertKeyFrame(KeyFrame* keyframe);
  bool AcceptsKeyFrames() const { return accept_keyframes_.load(); }
  size_t KeyframesInQueue() const;
  void InterruptBA() { abort_ba_.store(true); }
  // Blocks until every queued keyframe is processed and the thread is idle.
  void WaitUntilIdle();
  // The same for at most `seconds`; whether the mapper is idle.
  bool WaitUntilIdleFor(double seconds);
  bool IsIdle() const;
  // Blocks until at most `n` keyframes wait in the queue (the mapper is working through them).
  void WaitForQueueAtMost(size_t n);

  // Pause protocol for the loop closer: RequestStop(), wait for IsStopped(), work, Release(). Requests are
  // counted: the mapper runs again only when every holder has released it (a loop correction and the global
  // BA of the previous loop may hold it at once; one clearing the other's request deadlocked the loop closer).
  void RequestStop();
  bool IsStopped() const;
  bool StopRequested() const;
  void Release();
  // Blocks while a holder keeps the mapper paused; returns at once when none does, or once the thread ended.
  void WaitWhilePaused();
  // Tracking marks a keyframe insertion in progress so the mapper does not stop under it. Returns false
  // if the mapper is already stopped.
  bool SetNotStop(bool value);

  // Drops the queue (the map is being reset). Blocks until done.
  void Reset();

  int num_processed() const { return num_processed_.load(); }
  bool IsFinished() const { return finished_.load(); }

 private:
  void Run();
  bool HasNewKeyFrames() const;
  // Whether to cut the current keyframe's work short for newer ones (options_.yield_to_new_keyframes).
  bool NewerKeyFramesWaiting() const { return options_.yield_to_new_keyframes && HasNewKeyFrames(); }
  void ProcessNewKeyFrame();
  void CullRecentPoints();
  void CreateNewMapPoints();
  void SearchInNeighbours();
  void LocalBundleAdjustment();
  void CullKeyFrames();
  bool StopIfRequested();

  LocalMapperOptions options_;
  Map& map_;
  const Vocabulary& vocabulary_;
  KeyFrameDatabase& database_;
  TimingRegistry& timing_;
  std::vector<std::function<void(KeyFrame*)>> listeners_;

  mutable std::mutex queue_mutex_;
  std::condition_variable queue_cv_;
  std::deque<KeyFrame*> queue_;
  KeyFrame* current_ = nullptr;
  bool busy_ = false;
  // Under queue_mutex_: nothing queued and nothing being processed.
  bool IdleLocked() const { return queue_.empty() && !busy_; }

  std::atomic<bool> accept_keyframes_{true};
  std::atomic<bool> abort_ba_{false};
  std::atomic<bool> finish_requested_{false};
  std::atomic<int> num_processed_{0};
  std::atomic<bool> finished_{false};

  mutable std::mutex stop_mutex_;
  int stop_requests_ = 0;  // holders of the pause (the loop closer, its global BA, a map reset)
  bool stopped_ = false;
  bool not_stop_ = false;
  std::atomic<bool> reset_requested_{false};

  std::thread thread_;
};

}  // namespace semslam
