#pragma once
// Small pieces shared by the RANSAC estimators (two-view, PnP, Sim(3)): a seeded sampler whose draws are
// the same on every platform (no std::uniform_int_distribution, whose algorithm the standard leaves open),
// and the adaptive iteration count.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

namespace semslam {

class RansacSampler {
 public:
  explicit RansacSampler(std::uint64_t seed) : engine_(seed) {}

  // Uniform in [0, n), n > 0, without modulo bias.
  std::size_t Uniform(std::size_t n) {
    const std::uint64_t range = static_cast<std::uint64_t>(n);
    const std::uint64_t limit =
        std::numeric_limits<std::uint64_t>::max() - std::numeric_limits<std::uint64_t>::max() % range;
    std::uint64_t x = engine_();
    while (x >= limit) x = engine_();
    return static_cast<std::size_t>(x % range);
  }

  // `k` distinct indices in [0, n) (k <= n), in draw order, into `out`.
  void Sample(std::size_t n, std::size_t k, std::vector<std::size_t>& out) {
    out.clear();
    while (out.size() < k) {
      const std::size_t i = Uniform(n);
      if (std::find(out.begin(), out.end(), i) == out.end()) out.push_back(i);
    }
  }

 private:
  std::mt19937_64 engine_;
};

// Iterations needed to draw, with probability `confidence`, at least one all-inlier sample of `sample_size`
// when a fraction `inlier_ratio` of the data are inliers; clamped to [0, max_iterations].
inline int RansacIterations(double inlier_ratio, int sample_size, double confidence, int max_iterations) {
  if (inlier_ratio <= 0.0) return max_iterations;
  if (inlier_ratio >= 1.0) return std::min(1, max_iterations);
  const double all_inliers = std::pow(inlier_ratio, sample_size);
  if (all_inliers <= std::numeric_limits<double>::min()) return max_iterations;
  const double n = std::log(1.0 - confidence) / std::log1p(-all_inliers);
  if (!(n < static_cast<double>(max_iterations))) return max_iterations;
  return std::max(1, static_cast<int>(std::ceil(n)));
}

}  // namespace semslam
