#include "semslam/core/timing.h"

#include <gtest/gtest.h>

namespace semslam {
namespace {

TEST(Timing, SummarizesKnownSamples) {
  std::vector<double> samples;
  for (int i = 1; i <= 20; ++i) samples.push_back(i);
  const TimingSummary s = Summarize(samples);
  EXPECT_EQ(s.count, 20u);
  EXPECT_DOUBLE_EQ(s.median_ms, 10.5);
  EXPECT_DOUBLE_EQ(s.mean_ms, 10.5);
  EXPECT_DOUBLE_EQ(s.p95_ms, 19.0);  // nearest rank: ceil(0.95 * 20) = 19th value
  EXPECT_DOUBLE_EQ(s.max_ms, 20.0);
  EXPECT_EQ(Summarize({}).count, 0u);
}

TEST(Timing, RegistryCollectsPerModule) {
  TimingRegistry registry;
  registry.Add("tracking", 3.0);
  registry.Add("tracking", 5.0);
  registry.Add("mapping", 7.0);
  const auto all = registry.SummarizeAll();
  EXPECT_DOUBLE_EQ(all.at("tracking").median_ms, 4.0);
  EXPECT_EQ(all.at("mapping").count, 1u);
}

}  // namespace
}  // namespace semslam
