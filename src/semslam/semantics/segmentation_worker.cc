#include "semslam/semantics/segmentation_worker.h"

#include <spdlog/spdlog.h>

#include <exception>

#include "semslam/core/error.h"

namespace semslam {

void SegmentationWorkerOptions::Check() const {
  Require(max_pending >= 1, "SegmentationWorker: max_pending must be >= 1");
}

SegmentationWorker::SegmentationWorker(std::shared_ptr<Segmenter> segmenter, Callback callback,
                                       Options options)
    : segmenter_(std::move(segmenter)), callback_(std::move(callback)), options_(options) {
  options_.Check();
  Require(segmenter_ != nullptr, "SegmentationWorker: no segmenter");
  Require(static_cast<bool>(callback_), "SegmentationWorker: no callback");
  thread_ = std::thread([this] { Run(); });
}

SegmentationWorker::~SegmentationWorker() { Stop(); }

void SegmentationWorker::Submit(std::uint64_t keyframe_id, cv::Mat image, std::int64_t frame_index) {
  {
    std::lock_guard lock(mutex_);
    if (stop_) return;
    ++stats_.submitted;
    pending_.push_back(Request{keyframe_id, std::move(image), frame_index});
    while (pending_.size() > options_.max_pending) {
      skipped_ids_.push_back(pending_.front().keyframe_id);
      ++stats_.skipped;
      pending_.pop_front();
    }
  }
  wake_.notify_one();
}

void SegmentationWorker::Run() {
  for (;;) {
    Request request;
    {
      std::unique_lock lock(mutex_);
      wake_.wait(lock, [this] { return stop_ || !pending_.empty(); });
      if (pending_.empty() || (stop_ && !drain_)) {
        for (const Request& r : pending_) skipped_ids_.push_back(r.keyframe_id);
        stats_.skipped += pending_.size();
        pending_.clear();
        finished_ = true;
        idle_.notify_all();
        return;
      }
      if (stop_) {
        // Draining: everything still pending, in order.
        request = std::move(pending_.front());
        pending_.pop_front();
      } else {
        // The newest request; older ones are skipped.
        request = std::move(pending_.back());
        pending_.pop_back();
        for (const Request& r : pending_) skipped_ids_.push_back(r.keyframe_id);
        stats_.skipped += pending_.size();
        pending_.clear();
      }
      running_request_ = true;
    }
    SegmentationResult result;
    result.keyframe_id = request.keyframe_id;
    result.frame_index = request.frame_index;
    bool ok = false;
    try {
      const Stopwatch watch;
      result.segmentation = segmenter_->Segment(request.image, request.frame_index);
      result.milliseconds = watch.ElapsedMs();
      ok = true;
    } catch (const std::exception& e) {
      spdlog::warn("segmentation of keyframe {} failed: {}", request.keyframe_id, e.what());
    }
    const double milliseconds = result.milliseconds;
    bool delivered = false;
    if (ok) {
      try {
        callback_(std::move(result));
        delivered = true;
      } catch (const std::exception& e) {
        spdlog::warn("segmentation callback for keyframe {} failed: {}", request.keyframe_id, e.what());
      }
    }
    {
      std::lock_guard lock(mutex_);
      running_request_ = false;
      if (delivered) {
        ++stats_.segmented;
        samples_ms_.push_back(milliseconds);
      } else {
        ++stats_.failed;
      }
      if (pending_.empty()) idle_.notify_all();
    }
  }
}

void SegmentationWorker::WaitUntilIdle() {
  std::unique_lock lock(mutex_);
  idle_.wait(lock, [this] { return (pending_.empty() && !running_request_) || finished_; });
}

void SegmentationWorker::Stop(bool drain) {
  {
    std::lock_guard lock(mutex_);
    if (!stop_) drain_ = drain;
    stop_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable() && thread_.get_id() != std::this_thread::get_id()) thread_.join();
  idle_.notify_all();
}

SegmentationWorkerStats SegmentationWorker::stats() const {
  std::lock_guard lock(mutex_);
  SegmentationWorkerStats s = stats_;
  s.segmentation_ms = Summarize(samples_ms_);
  return s;
}

std::vector<std::uint64_t> SegmentationWorker::SkippedKeyframes() const {
  std::lock_guard lock(mutex_);
  return skipped_ids_;
}

bool SegmentationWorker::Busy() const {
  std::lock_guard lock(mutex_);
  return running_request_ || !pending_.empty();
}

}  // namespace semslam
