// The asynchronous segmentation worker: never blocks the caller, takes the newest keyframe when behind,
// delivers every result it computes.

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <set>
#include <stdexcept>
#include <thread>
#include <vector>

#include "semslam/core/error.h"
#include "semslam/semantics/segmentation_worker.h"

namespace semslam {
namespace {

// A segmenter that blocks until released, labels everything with (frame_index % 19), and throws for frame
// 666.
class GatedSegmenter : public Segmenter {
 public:
  std::string Describe() const override { return "gated"; }
  Segmentation Segment(const cv::Mat& image, std::int64_t frame_index) override {
    std::unique_lock lock(mutex_);
    started_.push_back(frame_index);
    changed_.notify_all();
    changed_.wait(lock, [&] { return open_ || released_ > 0; });
    if (!open_) --released_;
    if (frame_index == 666) throw std::runtime_error("broken frame");
    return Segmentation::FromLabels(
        cv::Mat(image.size(), CV_8UC1, cv::Scalar(static_cast<int>(frame_index % 19))), image.size(), 0.9f);
  }
  void WaitStarted(size_t n) {
    std::unique_lock lock(mutex_);
    ASSERT_TRUE(changed_.wait_for(lock, std::chrono::seconds(10), [&] { return started_.size() >= n; }));
  }
  void Release(int n = 1) {
    std::lock_guard lock(mutex_);
    released_ += n;
    changed_.notify_all();
  }
  void Open() {
    std::lock_guard lock(mutex_);
    open_ = true;
    changed_.notify_all();
  }
  std::vector<std::int64_t> started() {
    std::lock_guard lock(mutex_);
    return started_;
  }

 private:
  std::mutex mutex_;
  std::condition_variable changed_;
  std::vector<std::int64_t> started_;
  int released_ = 0;
  bool open_ = false;
};

struct Collected {
  std::mutex mutex;
  std::vector<std::uint64_t> keyframes;
  std::vector<int> labels;
};

TEST(SegmentationWorker, TakesTheNewestWhenBehindAndDeliversEveryResult) {
  auto segmenter = std::make_shared<GatedSegmenter>();
  Collected collected;
  SegmentationWorker worker(segmenter, [&](SegmentationResult&& r) {
    std::lock_guard lock(collected.mutex);
    collected.keyframes.push_back(r.keyframe_id);
    collected.labels.push_back(r.segmentation.LabelAt(0, 0));
    EXPECT_EQ(static_cast<std::int64_t>(r.keyframe_id) * 10, r.frame_index);
    EXPECT_GE(r.milliseconds, 0.0);
  });
  const cv::Mat image(4, 4, CV_8UC1, cv::Scalar(0));
  worker.Submit(1, image, 10);
  segmenter->WaitStarted(1);  // keyframe 1 is being segmented (and blocks)
  // The worker is busy: these return at once; 2 and 3 are superseded by 4.
  const auto before = std::chrono::steady_clock::now();
  worker.Submit(2, image, 20);
  worker.Submit(3, image, 30);
  worker.Submit(4, image, 40);
  EXPECT_LT(std::chrono::steady_clock::now() - before, std::chrono::milliseconds(100));
  EXPECT_TRUE(worker.Busy());
  segmenter->Release();  // finishes 1; the worker then takes 4
  segmenter->WaitStarted(2);
  segmenter->Release();
  worker.WaitUntilIdle();
  EXPECT_EQ(segmenter->started(), (std::vector<std::int64_t>{10, 40}));
  {
    std::lock_guard lock(collected.mutex);
    EXPECT_EQ(collected.keyframes, (std::vector<std::uint64_t>{1, 4}));
    EXPECT_EQ(collected.labels, (std::vector<int>{10, 40 % 19}));
  }
  const SegmentationWorkerStats stats = worker.stats();
  EXPECT_EQ(stats.submitted, 4u);
  EXPECT_EQ(stats.segmented, 2u);
  EXPECT_EQ(stats.skipped, 2u);
  EXPECT_EQ(stats.failed, 0u);
  EXPECT_EQ(stats.segmentation_ms.count, 2u);
  EXPECT_EQ(worker.SkippedKeyframes(), (std::vector<std::uint64_t>{2, 3}));
  EXPECT_FALSE(worker.Busy());
}

TEST(SegmentationWorker, KeepsAWindowOfPendingAndSurvivesFailures) {
  auto segmenter = std::make_shared<GatedSegmenter>();
  std::mutex mutex;
  std::vector<std::uint64_t> delivered;
  SegmentationWorker::Options options;
  options.max_pending = 2;
  SegmentationWorker worker(
      segmenter,
      [&](SegmentationResult&& r) {
        std::lock_guard lock(mutex);
        delivered.push_back(r.keyframe_id);
        if (r.keyframe_id == 9) throw std::runtime_error("callback failure");
      },
      options);
  const cv::Mat image(2, 2, CV_8UC1, cv::Scalar(0));
  worker.Submit(1, image, 666);  // the segmenter throws for this one
  segmenter->WaitStarted(1);
  worker.Submit(2, image, 2);
  worker.Submit(3, image, 3);
  worker.Submit(4, image, 4);  // the window keeps 3 and 4; 2 is dropped
  segmenter->Open();
  worker.WaitUntilIdle();
  worker.Submit(9, image, 9);
  worker.WaitUntilIdle();
  const auto stats = worker.stats();
  EXPECT_EQ(stats.failed, 2u);  // keyframe 1 (segmenter) and 9 (callback)
  EXPECT_EQ(stats.segmented, 1u);
  EXPECT_EQ(worker.SkippedKeyframes(), (std::vector<std::uint64_t>{2, 3}));  // 3 lost to the newest, 4
  std::lock_guard lock(mutex);
  EXPECT_EQ(delivered, (std::vector<std::uint64_t>{4, 9}));
}

TEST(SegmentationWorker, StopDrainsOrSkipsPending) {
  for (bool drain : {false, true}) {
    auto segmenter = std::make_shared<GatedSegmenter>();
    std::atomic<int> delivered{0};
    SegmentationWorker::Options options;
    options.max_pending = 3;
    SegmentationWorker worker(
        segmenter, [&](SegmentationResult&&) { ++delivered; }, options);
    const cv::Mat image(2, 2, CV_8UC1, cv::Scalar(0));
    worker.Submit(1, image, 1);
    segmenter->WaitStarted(1);
    worker.Submit(2, image, 2);
    worker.Submit(3, image, 3);
    // Stop while keyframe 1 is still running (Stop joins, so from another thread), then let it finish.
    std::thread stopper([&] { worker.Stop(drain); });
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    segmenter->Open();
    stopper.join();
    worker.Submit(4, image, 4);  // ignored after Stop
    EXPECT_EQ(delivered.load(), drain ? 3 : 1) << drain;
    EXPECT_EQ(worker.stats().skipped, drain ? 0u : 2u) << drain;
    worker.WaitUntilIdle();  // returns at once after Stop
  }
  EXPECT_THROW(SegmentationWorker(nullptr, [](SegmentationResult&&) {}), InvalidArgument);
}

}  // namespace
}  // namespace semslam
