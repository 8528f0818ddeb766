// The local mapper's pause protocol, which the loop closer, its global BA and a map reset share, and the
// bounded wait for it that realtime pacing uses.

#include "semslam/mapping/local_mapper.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <functional>
#include <thread>

#include "semslam/core/timing.h"
#include "semslam/map/map.h"
#include "semslam/place/keyframe_database.h"
#include "semslam/place/vocabulary.h"
#include "support/kitti_camera.h"

namespace semslam {
namespace {

bool WaitFor(const std::function<bool()>& condition) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (!condition()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return true;
}

// A started mapper over an empty map.
class LocalMapperPause : public ::testing::Test {
 protected:
  LocalMapperPause() { mapper.Start(); }

  Map map;
  const Vocabulary vocabulary;
  KeyFrameDatabase database{1};
  TimingRegistry timing;
  LocalMapper mapper{LocalMapperOptions{}, map, vocabulary, database, timing};
};

TEST_F(LocalMapperPause, RunsAgainOnlyWhenEveryHolderReleasedIt) {

  // A loop correction pauses the mapper while the previous loop's global BA holds it too: the BA's release
  // must not let the mapper run under the correction (it used to clear the other request, and the
  // correction then waited forever for a stop that never came).
  mapper.RequestStop();
  ASSERT_TRUE(WaitFor([&] { return mapper.IsStopped(); }));
  mapper.RequestStop();
  mapper.Release();
  EXPECT_TRUE(mapper.StopRequested());
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  EXPECT_TRUE(mapper.IsStopped());
  EXPECT_FALSE(mapper.SetNotStop(true)) << "tracking must not insert a keyframe into a paused mapper";

  mapper.Release();
  EXPECT_FALSE(mapper.StopRequested());
  ASSERT_TRUE(WaitFor([&] { return !mapper.IsStopped(); }));
  EXPECT_TRUE(mapper.SetNotStop(true));
  mapper.SetNotStop(false);

  // And it can be paused again, then finishes.
  mapper.RequestStop();
  ASSERT_TRUE(WaitFor([&] { return mapper.IsStopped(); }));
  mapper.Release();
  mapper.RequestFinish();
  mapper.Join();
  EXPECT_TRUE(mapper.IsFinished());
}

TEST_F(LocalMapperPause, TrackingWaitsUntilTheLastHolderReleasesIt) {
  // Synchronous pacing waits out a loop correction this way (SlamSystem::ProcessFrame).
  mapper.WaitWhilePaused();  // nobody holds it: returns at once
  mapper.RequestStop();
  mapper.RequestStop();
  ASSERT_TRUE(WaitFor([&] { return mapper.IsStopped(); }));
  std::atomic<bool> returned{false};
  std::thread tracking([&] {
    mapper.WaitWhilePaused();
    returned = true;
  });
  mapper.Release();
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  EXPECT_FALSE(returned) << "one holder still keeps the mapper paused";
  mapper.Release();
  EXPECT_TRUE(WaitFor([&] { return returned.load(); }));
  tracking.join();
  mapper.RequestFinish();
  mapper.Join();
  mapper.RequestStop();
  mapper.WaitWhilePaused();  // a finished mapper never pauses: returns at once
  EXPECT_TRUE(mapper.IsFinished());
}

TEST_F(LocalMapperPause, AReleaseWithoutARequestChangesNothing) {
  mapper.Release();
  EXPECT_FALSE(mapper.StopRequested());
  mapper.RequestStop();
  ASSERT_TRUE(WaitFor([&] { return mapper.IsStopped(); }));
  mapper.Release();
  ASSERT_TRUE(WaitFor([&] { return !mapper.IsStopped(); }));
  mapper.RequestFinish();
  mapper.Join();
  EXPECT_TRUE(mapper.IsFinished());
}

TEST_F(LocalMapperPause, AWaitForIdleGivesUpAfterItsTime) {
  EXPECT_TRUE(mapper.IsIdle());
  EXPECT_TRUE(mapper.WaitUntilIdleFor(5.0));  // nothing to do: returns at once

  // A keyframe waits in the queue of a paused mapper: realtime pacing's wait must not block on it.
  mapper.RequestStop();
  ASSERT_TRUE(WaitFor([&] { return mapper.IsStopped(); }));
  const PinholeCamera camera = KittiCamera();
  FeatureSet no_features;
  no_features.image_width = camera.width;
  no_features.image_height = camera.height;
  KeyFrame* waiting =
      map.AddKeyFrame(Frame(0, 0.0, MakeFrameData(camera, std::nullopt, std::move(no_features), {}, {})));
  mapper.InsertKeyFrame(waiting);
  EXPECT_FALSE(mapper.IsIdle());
  EXPECT_FALSE(mapper.WaitUntilIdleFor(0.02));

  mapper.Reset();  // the keyframe is dropped unprocessed
  EXPECT_TRUE(mapper.IsIdle());
  EXPECT_TRUE(mapper.WaitUntilIdleFor(5.0));
  mapper.Release();
  mapper.RequestFinish();
  mapper.Join();
  EXPECT_TRUE(mapper.IsFinished());
}

}  // namespace
}  // namespace semslam
