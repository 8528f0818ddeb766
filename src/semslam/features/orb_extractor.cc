#include "semslam/features/orb_extractor.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_group.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <numeric>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "semslam/core/error.h"
#include "semslam/features/orb_descriptor.h"

namespace semslam {

void OrbOptions::Check() const {
  Require(num_features >= 1, "ORB options: num_features must be >= 1");
  Require(num_levels >= 1 && num_levels <= 32, "ORB options: num_levels must be in [1, 32]");
  Require(scale_factor > 1.0f && scale_factor <= 4.0f, "ORB options: scale_factor must be in (1, 4]");
  Require(initial_fast_threshold >= 1 && initial_fast_threshold <= 254,
          "ORB options: initial_fast_threshold must be in [1, 254]");
  Require(min_fast_threshold >= 1 && min_fast_threshold <= initial_fast_threshold,
          "ORB options: min_fast_threshold must be in [1, initial_fast_threshold]");
  Require(edge_threshold >= kMinKeypointBorder && edge_threshold <= 200,
          "ORB options: edge_threshold must be in [16, 200]");
  Require(cell_size >= 8 && cell_size <= 512, "ORB options: cell_size must be in [8, 512]");
  Require(level_share_exponent >= 0 && level_share_exponent <= 4,
          "ORB options: level_share_exponent must be in [0, 4]");
}

namespace {

// Run `fn(i)` for i in [0, n), in parallel if asked.
template <typename Fn>
void ForEach(bool parallel, size_t n, Fn&& fn) {
  if (!parallel || n <= 1) {
    for (size_t i = 0; i < n; ++i) fn(i);
    return;
  }
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) fn(i);
  });
}

// FAST corners (9 of 16, with non-maximum suppression) of `image` inside [x0, x1) x [y0, y1), detected on a
// sub-image that extends `margin` pixels further so that detection and suppression are exact there.
void DetectFast(const cv::Mat& image, int x0, int y0, int x1, int y1, int threshold,
                std::vector<cv::KeyPoint>& scratch, std::vector<CornerCandidate>& out) {
  constexpr int kMargin = 5;
  const int rx0 = std::max(0, x0 - kMargin), ry0 = std::max(0, y0 - kMargin);
  const int rx1 = std::min(image.cols, x1 + kMargin), ry1 = std::min(image.rows, y1 + kMargin);
  if (rx1 - rx0 < 7 || ry1 - ry0 < 7) return;
  scratch.clear();
  cv::FAST(image(cv::Rect(rx0, ry0, rx1 - rx0, ry1 - ry0)), scratch, threshold, true,
           cv::FastFeatureDetector::TYPE_9_16);
  for (const cv::KeyPoint& kp : scratch) {
    const float x = kp.pt.x + static_cast<float>(rx0), y = kp.pt.y + static_cast<float>(ry0);
    if (x < static_cast<float>(x0) || x >= static_cast<float>(x1) || y < static_cast<float>(y0) ||
        y >= static_cast<float>(y1)) {
      continue;
    }
    out.push_back({x, y, kp.response});
  }
}

struct Level {
  cv::Mat image;
  cv::Mat smoothed;
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;  // detection area
  int num_strips = 0;
  std::vector<std::vector<CornerCandidate>> strips;
  std::vector<CornerCandidate> candidates;
  std::vector<Keypoint> keypoints;
  std::vector<Descriptor> descriptors;
  bool usable() const { return x1 > x0 && y1 > y0; }
};

struct Task {
  int level;
  int strip;  // -1: smoothing
};

constexpr int kStripPixels = 80000;  // FAST work per task

}  // namespace

OrbExtractor::OrbExtractor(const OrbOptions& options) : options_(options) {
  options_.Check();
  geometry_ = PyramidGeometry::Make(options_.num_levels, options_.scale_factor);
  // Level l gets 1 / s^(e l) of level 0's share (e = level_share_exponent: 1 by side length, 2 by area).
  const double f = 1.0 / std::pow(static_cast<double>(options_.scale_factor), options_.level_share_exponent);
  const double first = options_.num_features * (1.0 - f) / (1.0 - std::pow(f, options_.num_levels));
  level_budget_.assign(static_cast<size_t>(options_.num_levels), 0);
  int assigned = 0;
  for (int l = 0; l + 1 < options_.num_levels; ++l) {
    const int n = static_cast<int>(std::lround(first * std::pow(f, l)));
    level_budget_[static_cast<size_t>(l)] = std::min(n, options_.num_features - assigned);
    assigned += level_budget_[static_cast<size_t>(l)];
  }
  level_budget_.back() = options_.num_features - assigned;
}

OrbExtractor::~OrbExtractor() = default;

std::vector<int> OrbExtractor::LevelBudgets() const { return level_budget_; }

std::vector<int> DistributeLevelBudgets(const std::vector<int>& wanted, const std::vector<int>& available) {
  Require(wanted.size() == available.size(), "DistributeLevelBudgets: size mismatch");
  const size_t n = wanted.size();
  const long total = std::accumulate(wanted.begin(), wanted.end(), 0L);
  std::vector<int> result(n);
  for (size_t l = 0; l < n; ++l) result[l] = std::max(0, std::min(wanted[l], available[l]));
  for (;;) {
    long deficit = total - std::accumulate(result.begin(), result.end(), 0L);
    if (deficit <= 0) break;
    double weight = 0;
    int open = 0;
    for (size_t l = 0; l < n; ++l) {
      if (result[l] < available[l]) {
        weight += std::max(wanted[l], 1);
        ++open;
      }
    }
    if (open == 0) break;
    const long start_deficit = deficit;
    for (size_t l = 0; l < n && deficit > 0; ++l) {
      if (result[l] >= available[l]) continue;
      const long share = std::max(1L, static_cast<long>(std::floor(static_cast<double>(start_deficit) *
                                                                   std::max(wanted[l], 1) / weight)));
      const long add = std::min({share, static_cast<long>(available[l] - result[l]), deficit});
      result[l] += static_cast<int>(add);
      deficit -= add;
    }
  }
  return result;
}

std::vector<int> SelectSpreadOut(const std::vector<CornerCandidate>& candidates, int budget, float x0,
                                 float y0, float x1, float y1) {
  const int n = static_cast<int>(candidates.size());
  std::vector<int> chosen;
  if (budget <= 0 || n == 0) return chosen;
  if (n <= budget) {
    chosen.resize(static_cast<size_t>(n));
    std::iota(chosen.begin(), chosen.end(), 0);
    return chosen;
  }
  const float width = std::max(x1 - x0, 1.0f), height = std::max(y1 - y0, 1.0f);
  const float side = std::sqrt(width * height / static_cast<float>(budget));
  const int cols = std::max(1, static_cast<int>(std::ceil(width / side)));
  const int rows = std::max(1, static_cast<int>(std::ceil(height / side)));
  const float inv_w = static_cast<float>(cols) / width, inv_h = static_cast<float>(rows) / height;
  // Strongest first (ties by index, for determinism). FAST scores are integers in [0, 255]: a counting
  // sort then; anything else sorts by key.
  std::vector<int> order(static_cast<size_t>(n));
  const bool small_integers = std::all_of(candidates.begin(), candidates.end(), [](const CornerCandidate& c) {
    return c.response >= 0.0f && c.response <= 255.0f && c.response == std::floor(c.response);
  });
  if (small_integers) {
    std::array<int, 257> start{};
    for (const CornerCandidate& c : candidates) ++start[255 - static_cast<size_t>(c.response) + 1];
    for (size_t b = 0; b < 256; ++b) start[b + 1] += start[b];
    for (int i = 0; i < n; ++i) {
      order[static_cast<size_t>(
          start[255 - static_cast<size_t>(candidates[static_cast<size_t>(i)].response)]++)] = i;
    }
  } else {
    std::vector<std::pair<float, int>> keyed(static_cast<size_t>(n));
    for (int i = 0; i < n; ++i)
      keyed[static_cast<size_t>(i)] = {-candidates[static_cast<size_t>(i)].response, i};
    std::sort(keyed.begin(), keyed.end());
    for (int i = 0; i < n; ++i) order[static_cast<size_t>(i)] = keyed[static_cast<size_t>(i)].second;
  }
  // Round of each candidate = how many stronger candidates share its cell.
  std::vector<int> cell_count(static_cast<size_t>(cols * rows), 0);
  std::vector<int> round(static_cast<size_t>(n));
  std::vector<int> per_round;
  for (const int i : order) {
    const CornerCandidate& c = candidates[static_cast<size_t>(i)];
    const int cx = std::clamp(static_cast<int>((c.x - x0) * inv_w), 0, cols - 1);
    const int cy = std::clamp(static_cast<int>((c.y - y0) * inv_h), 0, rows - 1);
    const int r = cell_count[static_cast<size_t>(cy * cols + cx)]++;
    round[static_cast<size_t>(i)] = r;
    if (r >= static_cast<int>(per_round.size())) per_round.resize(static_cast<size_t>(r) + 1, 0);
    ++per_round[static_cast<size_t>(r)];
  }
  // Full rounds fit; the last round is cut by strength.
  int last_round = 0;
  int taken = 0;
  while (last_round < static_cast<int>(per_round.size()) &&
         taken + per_round[static_cast<size_t>(last_round)] <= budget) {
    taken += per_round[static_cast<size_t>(last_round)];
    ++last_round;
  }
  int room = budget - taken;
  chosen.reserve(static_cast<size_t>(budget));
  for (const int i : order) {
    const int r = round[static_cast<size_t>(i)];
    if (r < last_round) {
      chosen.push_back(i);
    } else if (r == last_round && room > 0) {
      chosen.push_back(i);
      --room;
    }
  }
  return chosen;
}

FeatureSet OrbExtractor::Extract(const cv::Mat& image, const cv::Mat& mask, ImagePyramid* pyramid_out) const {
  Require(!image.empty(), "ORB: empty image");
  Require(image.depth() == CV_8U && (image.channels() == 1 || image.channels() == 3),
          "ORB: need an 8-bit grey or BGR image");
  cv::Mat grey = image;
  if (image.channels() == 3) cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  Require(mask.empty() || (mask.type() == CV_8UC1 && mask.size() == grey.size()),
          "ORB: mask must be CV_8UC1 with the image's size");

  const size_t num_levels = static_cast<size_t>(geometry_.num_levels);
  const int border = options_.edge_threshold;
  std::vector<Level> levels(num_levels);
  ImagePyramid pyramid;
  InitImagePyramid(grey, geometry_, pyramid);

  // 1. Smoothing and FAST at the initial threshold, per level and strip; a level's tasks start as soon as
  // the level is built, while the next levels are being resized.
  auto run_task = [&](const Task& task) {
    Level& level = levels[static_cast<size_t>(task.level)];
    if (task.strip < 0) {
      if (options_.pattern == OrbDescriptorPattern::kSemslam)
        SmoothForDescriptor(level.image, level.smoothed);
      return;
    }
    const int s = task.strip;
    const int h = level.y1 - level.y0;
    const int sy0 = level.y0 + h * s / level.num_strips, sy1 = level.y0 + h * (s + 1) / level.num_strips;
    std::vector<cv::KeyPoint> scratch;
    DetectFast(level.image, level.x0, sy0, level.x1, sy1, options_.initial_fast_threshold, scratch,
               level.strips[static_cast<size_t>(s)]);
  };
  auto prepare_level = [&](size_t l, std::vector<Task>& tasks) {
    BuildImagePyramidLevel(geometry_, l, pyramid);
    Level& level = levels[l];
    level.image = pyramid.levels[l];
    level.x0 = border;
    level.y0 = border;
    level.x1 = level.image.cols - border;
    level.y1 = level.image.rows - border;
    tasks.clear();
    if (!level.usable()) return;
    const int area = (level.x1 - level.x0) * (level.y1 - level.y0);
    level.num_strips = std::clamp(area / kStripPixels, 1, std::max(1, (level.y1 - level.y0) / 16));
    level.strips.resize(static_cast<size_t>(level.num_strips));
    tasks.push_back({static_cast<int>(l), -1});
    for (int s = 0; s < level.num_strips; ++s) tasks.push_back({static_cast<int>(l), s});
  };
  std::vector<Task> tasks;
  if (options_.parallel) {
    tbb::task_group group;
    for (size_t l = 0; l < num_levels; ++l) {
      prepare_level(l, tasks);
      for (const Task& task : tasks) group.run([&run_task, task] { run_task(task); });
    }
    group.wait();
  } else {
    for (size_t l = 0; l < num_levels; ++l) {
      prepare_level(l, tasks);
      for (const Task& task : tasks) run_task(task);
    }
  }

  // 2. Per level: merge strips, lower the threshold in cells without corners, apply the mask.
  ForEach(options_.parallel, num_levels, [&](size_t l) {
    Level& level = levels[l];
    if (!level.usable()) return;
    size_t total = 0;
    for (const auto& s : level.strips) total += s.size();
    level.candidates.reserve(total + 64);
    for (const auto& s : level.strips) level.candidates.insert(level.candidates.end(), s.begin(), s.end());
    // Masked pixels get no keypoint; a cell whose corners are all masked counts as empty.
    auto masked = [&](const CornerCandidate& c) {
      const int mx = std::clamp(static_cast<int>(std::lround(pyramid.ToLevel0X(c.x, static_cast<int>(l)))), 0,
                                mask.cols - 1);
      const int my = std::clamp(static_cast<int>(std::lround(pyramid.ToLevel0Y(c.y, static_cast<int>(l)))), 0,
                                mask.rows - 1);
      return mask.at<std::uint8_t>(my, mx) == 0;
    };
    if (!mask.empty()) std::erase_if(level.candidates, masked);
    const size_t first_low = level.candidates.size();
    if (options_.min_fast_threshold < options_.initial_fast_threshold) {
      const int w = level.x1 - level.x0, h = level.y1 - level.y0;
      const int cols = std::max(1, (w + options_.cell_size / 2) / options_.cell_size);
      const int rows = std::max(1, (h + options_.cell_size / 2) / options_.cell_size);
      std::vector<int> count(static_cast<size_t>(cols * rows), 0);
      for (const CornerCandidate& c : level.candidates) {
        const int cx = std::min(cols - 1, static_cast<int>(c.x - static_cast<float>(level.x0)) * cols / w);
        const int cy = std::min(rows - 1, static_cast<int>(c.y - static_cast<float>(level.y0)) * rows / h);
        ++count[static_cast<size_t>(cy * cols + cx)];
      }
      std::vector<cv::KeyPoint> scratch;
      for (int cy = 0; cy < rows; ++cy) {
        for (int cx = 0; cx < cols; ++cx) {
          if (count[static_cast<size_t>(cy * cols + cx)] > 0) continue;
          // Cell bounds: the inverse of the binning above.
          const int bx0 = level.x0 + (cx * w + cols - 1) / cols,
                    bx1 = level.x0 + ((cx + 1) * w + cols - 1) / cols;
          const int by0 = level.y0 + (cy * h + rows - 1) / rows,
                    by1 = level.y0 + ((cy + 1) * h + rows - 1) / rows;
          DetectFast(level.image, bx0, by0, bx1, by1, options_.min_fast_threshold, scratch, level.candidates);
        }
      }
    }
    if (!mask.empty()) {
      level.candidates.erase(std::remove_if(level.candidates.begin() + static_cast<std::ptrdiff_t>(first_low),
                                            level.candidates.end(), masked),
                             level.candidates.end());
    }
  });

  // 3. Budgets, with what coarse or empty levels cannot use given to the others.
  std::vector<int> available(num_levels);
  for (size_t l = 0; l < num_levels; ++l) available[l] = static_cast<int>(levels[l].candidates.size());
  const std::vector<int> budget = DistributeLevelBudgets(level_budget_, available);

  // 4. Per level: even selection, orientation, descriptor.
  ForEach(options_.parallel, num_levels, [&](size_t l) {
    Level& level = levels[l];
    if (!level.usable() || budget[l] == 0) return;
    const std::vector<int> chosen = SelectSpreadOut(
        level.candidates, budget[l], static_cast<float>(level.x0), static_cast<float>(level.y0),
        static_cast<float>(level.x1), static_cast<float>(level.y1));
    level.keypoints.resize(chosen.size());
    if (options_.pattern == OrbDescriptorPattern::kSemslam) level.descriptors.resize(chosen.size());
    for (size_t k = 0; k < chosen.size(); ++k) {
      const CornerCandidate& c = level.candidates[static_cast<size_t>(chosen[k])];
      const int x = static_cast<int>(c.x), y = static_cast<int>(c.y);
      Keypoint& kp = level.keypoints[k];
      kp.pixel = {pyramid.ToLevel0X(c.x, static_cast<int>(l)), pyramid.ToLevel0Y(c.y, static_cast<int>(l))};
      kp.level = static_cast<int>(l);
      kp.response = c.response;
      kp.angle_deg = IntensityCentroidAngle(level.image, x, y);
      if (options_.pattern == OrbDescriptorPattern::kSemslam) {
        level.descriptors[k] = ComputeSteeredBrief(level.smoothed, x, y, kp.angle_deg);
      }
    }
  });

  FeatureSet features;
  features.pyramid = geometry_;
  features.image_width = grey.cols;
  features.image_height = grey.rows;
  size_t total = 0;
  for (const Level& level : levels) total += level.keypoints.size();
  features.keypoints.reserve(total);
  features.descriptors.reserve(total);
  for (Level& level : levels) {
    features.keypoints.insert(features.keypoints.end(), level.keypoints.begin(), level.keypoints.end());
    features.descriptors.insert(features.descriptors.end(), level.descriptors.begin(),
                                level.descriptors.end());
  }

  if (options_.pattern == OrbDescriptorPattern::kOpenCv && !features.keypoints.empty()) {
    // OpenCV's ORB places level-l pixel p at level-0 position p * s^l; hand it our level positions that way.
    std::vector<cv::KeyPoint> cv_keypoints;
    cv_keypoints.reserve(features.size());
    for (size_t i = 0; i < features.size(); ++i) {
      const Keypoint& kp = features.keypoints[i];
      const float s = geometry_.scale[static_cast<size_t>(kp.level)];
      const float lx = pyramid.FromLevel0X(kp.pixel.x(), kp.level),
                  ly = pyramid.FromLevel0Y(kp.pixel.y(), kp.level);
      cv_keypoints.emplace_back(cv::Point2f(std::round(lx) * s, std::round(ly) * s), 31.0f * s, kp.angle_deg,
                                kp.response, kp.level, static_cast<int>(i));
    }
    auto orb =
        cv::ORB::create(options_.num_features, options_.scale_factor, options_.num_levels, kMinKeypointBorder,
                        0, 2, cv::ORB::FAST_SCORE, 31, options_.initial_fast_threshold);
    cv::Mat descriptors;
    orb->compute(grey, cv_keypoints, descriptors);
    FeatureSet kept = features;
    kept.keypoints.clear();
    kept.descriptors.clear();
    for (size_t j = 0; j < cv_keypoints.size(); ++j) {
      const int i = cv_keypoints[j].class_id;
      if (i < 0 || static_cast<size_t>(i) >= features.size()) continue;
      Descriptor d;
      std::memcpy(d.data(), descriptors.ptr<std::uint8_t>(static_cast<int>(j)), sizeof(Descriptor));
      kept.keypoints.push_back(features.keypoints[static_cast<size_t>(i)]);
      kept.descriptors.push_back(d);
    }
    features = std::move(kept);
  }

  if (pyramid_out != nullptr) *pyramid_out = std::move(pyramid);
  return features;
}

}  // namespace semslam
