#pragma once
// Asynchronous segmentation of keyframes on a worker thread of its own, so that tracking never waits for the
// network. Submit() only stores the request; when the worker falls behind, it takes the newest pending
// keyframe and skips the older ones (counted and listed). Each result is delivered, with its keyframe id, to
// a callback called on the worker thread; a result may arrive long after its keyframe was made (the caller
// fuses it then: see label_fusion.h for points created in the meantime).

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <opencv2/core/mat.hpp>
#include <optional>
#include <thread>
#include <vector>

#include "semslam/core/timing.h"
#include "semslam/semantics/segmentation.h"
#include "semslam/semantics/segmenter.h"

namespace semslam {

struct SegmentationResult {
  std::uint64_t keyframe_id = 0;
  std::int64_t frame_index = -1;
  Segmentation segmentation;
  double milliseconds = 0.0;  // time spent in Segmenter::Segment
};

struct SegmentationWorkerStats {
  std::uint64_t submitted = 0;
  std::uint64_t segmented = 0;  // results delivered
  std::uint64_t skipped = 0;    // superseded by a newer keyframe before the worker got to them
  std::uint64_t failed = 0;     // the segmenter threw (logged)
  TimingSummary segmentation_ms;
};

struct SegmentationWorkerOptions {
  // Pending requests kept; when more arrive, the oldest are skipped. The worker always takes the newest.
  size_t max_pending = 1;
  void Check() const;
};

class SegmentationWorker {
 public:
  using Callback = std::function<void(SegmentationResult&&)>;
  using Options = SegmentationWorkerOptions;

  // Starts the thread. `callback` is called on the worker thread, one result at a time; exceptions it throws
  // are logged and counted as failures.
  SegmentationWorker(std::shared_ptr<Segmenter> segmenter, Callback callback, Options options = {});
  // Stops (pending requests are skipped) and joins. Must not run inside the callback.
  ~SegmentationWorker();
  SegmentationWorker(const SegmentationWorker&) = delete;
  SegmentationWorker& operator=(const SegmentationWorker&) = delete;

  // Queues a keyframe; never blocks on the segmentation (only on a short mutex). `image` is shared, not
  // copied: the caller must not write into it afterwards. `frame_index` is for segmenters that read per-frame
  // files. Ignored after Stop().
  void Submit(std::uint64_t keyframe_id, cv::Mat image, std::int64_t frame_index = -1);
  // Blocks until nothing is pending or running (for the end of a run, and tests).
  void WaitUntilIdle();
  // Stops the thread after the segmentation in progress; pending requests are skipped unless `drain`, in
  // which case they are segmented first. Idempotent.
  void Stop(bool drain = false);

  SegmentationWorkerStats stats() const;
  // Ids of the keyframes skipped so far, in the order they were skipped.
  std::vector<std::uint64_t> SkippedKeyframes() const;
  // Whether a segmentation is running or pending.
  bool Busy() const;

 private:
  struct Request {
    std::uint64_t keyframe_id;
    cv::Mat image;
    std::int64_t frame_index;
  };
  void Run();

  std::shared_ptr<Segmenter> segmenter_;
  Callback callback_;
  Options options_;

  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::condition_variable idle_;
  std::deque<Request> pending_;
  bool running_request_ = false;
  bool stop_ = false;
  bool drain_ = false;
  bool finished_ = false;  // the thread has left Run()
  SegmentationWorkerStats stats_;
  std::vector<double> samples_ms_;
  std::vector<std::uint64_t> skipped_ids_;
  std::thread thread_;
};

}  // namespace semslam
