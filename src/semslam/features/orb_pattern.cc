#include "semslam/features/orb_pattern.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <numbers>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>
#include <set>
#include <sstream>
#include <tuple>

#include "semslam/core/error.h"

namespace semslam {

std::uint64_t PatternRandom::Next() {
  std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

double PatternRandom::Uniform() { return static_cast<double>(Next() >> 11) * 0x1.0p-53; }

double PatternRandom::Gaussian() {
  if (has_spare_) {
    has_spare_ = false;
    return spare_;
  }
  double u1 = Uniform();
  while (u1 <= 1e-300) u1 = Uniform();
  const double u2 = Uniform();
  const double r = std::sqrt(-2.0 * std::log(u1));
  spare_ = r * std::sin(2.0 * std::numbers::pi * u2);
  has_spare_ = true;
  return r * std::cos(2.0 * std::numbers::pi * u2);
}

int PatternRandom::UniformInt(int lo, int hi) {
  return lo + static_cast<int>(Next() % static_cast<std::uint64_t>(hi - lo + 1));
}

std::vector<BriefPair> GenerateGaussianPairs(std::uint64_t seed, int count, double sigma) {
  Require(count > 0 && sigma > 0, "GenerateGaussianPairs: need count > 0 and sigma > 0");
  PatternRandom random(seed);
  constexpr int r2 = kBriefPatternRadius * kBriefPatternRadius;
  auto point = [&](int& x, int& y) {
    do {
      x = static_cast<int>(std::lround(sigma * random.Gaussian()));
      y = static_cast<int>(std::lround(sigma * random.Gaussian()));
    } while (x * x + y * y > r2);
  };
  std::vector<BriefPair> pairs;
  std::set<std::tuple<int, int, int, int>> seen;
  int attempts = 0;
  while (static_cast<int>(pairs.size()) < count) {
    Require(++attempts < 100 * count + 1000, "GenerateGaussianPairs: too many pairs asked for");
    int x1, y1, x2, y2;
    point(x1, y1);
    point(x2, y2);
    if ((x1 - x2) * (x1 - x2) + (y1 - y2) * (y1 - y2) < 4) continue;  // adjacent points say little
    // A test and its swap are the same test (negated); keep one orientation.
    const auto a = std::make_pair(x1, y1), b = std::make_pair(x2, y2);
    const auto key = std::make_tuple(std::min(a, b).first, std::min(a, b).second, std::max(a, b).first,
                                     std::max(a, b).second);
    if (!seen.insert(key).second) continue;
    pairs.push_back({static_cast<std::int8_t>(x1), static_cast<std::int8_t>(y1), static_cast<std::int8_t>(x2),
                     static_cast<std::int8_t>(y2)});
  }
  return pairs;
}

cv::Mat MakeSyntheticTrainingImage(std::uint64_t seed, cv::Size size) {
  PatternRandom random(seed * 7919 + 17);
  const int w = size.width, h = size.height;
  // Background: a linear gradient in a random direction.
  cv::Mat image(size, CV_8UC1);
  {
    const double a = random.Uniform() * 2 * std::numbers::pi;
    const double g0 = 40 + 170 * random.Uniform(), g1 = 40 + 170 * random.Uniform();
    const double ca = std::cos(a), sa = std::sin(a), norm = std::hypot(w, h);
    for (int y = 0; y < h; ++y) {
      auto* row = image.ptr<std::uint8_t>(y);
      for (int x = 0; x < w; ++x) {
        const double t = 0.5 + ((x - w / 2.0) * ca + (y - h / 2.0) * sa) / norm;
        row[x] = cv::saturate_cast<std::uint8_t>(g0 + (g1 - g0) * t);
      }
    }
  }
  // One draw per statement: a call evaluates its arguments in the compiler's order, and the images (so the
  // learned pattern) must not depend on the compiler. The order is the one the stored table was learned with
  // (GCC evaluates a call's arguments last to first).
  auto intensity = [&] { return cv::Scalar(random.UniformInt(0, 255)); };
  auto rand_point = [&] {
    const int y = random.UniformInt(-h / 8, h + h / 8);
    const int x = random.UniformInt(-w / 8, w + w / 8);
    return cv::Point(x, y);
  };
  const int num_shapes = random.UniformInt(60, 140);
  for (int i = 0; i < num_shapes; ++i) {
    const int kind = random.UniformInt(0, 6);
    const cv::Point c = rand_point();
    const double scale = std::min(w, h) * (0.02 + 0.25 * random.Uniform() * random.Uniform());
    switch (kind) {
      case 0: {  // rotated rectangle
        const double a = random.Uniform() * std::numbers::pi;
        const double sx = scale * (0.3 + random.Uniform()), sy = scale * (0.3 + random.Uniform());
        std::vector<cv::Point> pts;
        for (int k = 0; k < 4; ++k) {
          const double px = (k == 0 || k == 3 ? -sx : sx), py = (k < 2 ? -sy : sy);
          pts.emplace_back(static_cast<int>(c.x + px * std::cos(a) - py * std::sin(a)),
                           static_cast<int>(c.y + px * std::sin(a) + py * std::cos(a)));
        }
        cv::fillConvexPoly(image, pts, intensity(), cv::LINE_AA);
        break;
      }
      case 1: {  // polygon
        std::vector<cv::Point> pts;
        const int n = random.UniformInt(3, 7);
        for (int k = 0; k < n; ++k) {
          const double a = 2 * std::numbers::pi * (k + 0.8 * random.Uniform()) / n;
          const double r = scale * (0.4 + random.Uniform());
          pts.emplace_back(static_cast<int>(c.x + r * std::cos(a)), static_cast<int>(c.y + r * std::sin(a)));
        }
        std::vector<std::vector<cv::Point>> polys = {pts};
        cv::fillPoly(image, polys, intensity(), cv::LINE_AA);
        break;
      }
      case 2: {  // ellipse
        const int thickness = random.UniformInt(0, 2) == 0 ? 2 : cv::FILLED;
        const cv::Scalar value = intensity();
        const double angle = random.Uniform() * 180;
        const int ry = static_cast<int>(scale * (0.2 + random.Uniform())) + 1;
        const int rx = static_cast<int>(scale * (0.2 + random.Uniform())) + 1;
        cv::ellipse(image, c, cv::Size(rx, ry), angle, 0, 360, value, thickness, cv::LINE_AA);
        break;
      }
      case 3: {  // line
        const int thickness = random.UniformInt(1, 4);
        const cv::Scalar value = intensity();
        cv::line(image, c, rand_point(), value, thickness, cv::LINE_AA);
        break;
      }
      case 4: {  // grid of small rectangles (windows, tiles)
        const int nx = random.UniformInt(2, 6), ny = random.UniformInt(2, 5);
        const int cw = random.UniformInt(4, 16), ch = random.UniformInt(4, 16);
        const int gap = random.UniformInt(3, 10);
        const cv::Scalar value = intensity();
        for (int gy = 0; gy < ny; ++gy) {
          for (int gx = 0; gx < nx; ++gx) {
            const cv::Point p0(c.x + gx * (cw + gap), c.y + gy * (ch + gap));
            cv::rectangle(image, p0, p0 + cv::Point(cw, ch), value, cv::FILLED);
          }
        }
        break;
      }
      case 5: {  // textured region (foliage, gravel, bricks): band-limited noise inside an ellipse
        const int rx = static_cast<int>(scale * (0.5 + random.Uniform())) + 4;
        const int ry = static_cast<int>(scale * (0.5 + random.Uniform())) + 4;
        cv::Mat texture(2 * ry + 1, 2 * rx + 1, CV_32FC1);
        for (int y = 0; y < texture.rows; ++y) {
          for (int x = 0; x < texture.cols; ++x)
            texture.at<float>(y, x) = static_cast<float>(random.Gaussian());
        }
        const double blur = 0.7 + 2.5 * random.Uniform();
        cv::GaussianBlur(texture, texture, cv::Size(0, 0), blur);
        const double contrast = (20 + 60 * random.Uniform()) * blur;
        const double base = 30 + 190 * random.Uniform();
        cv::Mat region_mask = cv::Mat::zeros(texture.size(), CV_8UC1);
        cv::ellipse(region_mask, cv::Point(rx, ry), cv::Size(rx, ry), random.Uniform() * 180, 0, 360,
                    cv::Scalar(255), cv::FILLED);
        for (int y = 0; y < texture.rows; ++y) {
          const int iy = c.y - ry + y;
          if (iy < 0 || iy >= h) continue;
          for (int x = 0; x < texture.cols; ++x) {
            const int ix = c.x - rx + x;
            if (ix < 0 || ix >= w || region_mask.at<std::uint8_t>(y, x) == 0) continue;
            image.at<std::uint8_t>(iy, ix) =
                cv::saturate_cast<std::uint8_t>(base + contrast * texture.at<float>(y, x));
          }
        }
        break;
      }
      default: {  // soft blob
        cv::circle(image, c, static_cast<int>(scale * 0.5) + 1, intensity(), cv::FILLED, cv::LINE_AA);
        break;
      }
    }
  }
  // Rotate the whole composition by a random angle so that axis-aligned shapes lose their preference.
  {
    const double a = random.Uniform() * 360.0;
    const cv::Mat rot =
        cv::getRotationMatrix2D(cv::Point2f(static_cast<float>(w) / 2, static_cast<float>(h) / 2), a, 1.0);
    cv::Mat rotated;
    cv::warpAffine(image, rotated, rot, size, cv::INTER_LINEAR, cv::BORDER_REFLECT_101);
    image = rotated;
  }
  cv::GaussianBlur(image, image, cv::Size(3, 3), 0.5 + random.Uniform());
  // Sensor noise.
  cv::Mat noise(size, CV_16SC1);
  const double sigma = 2.0 + 5.0 * random.Uniform();
  for (int y = 0; y < h; ++y) {
    auto* row = noise.ptr<std::int16_t>(y);
    for (int x = 0; x < w; ++x) row[x] = static_cast<std::int16_t>(std::lround(sigma * random.Gaussian()));
  }
  cv::Mat image16;
  image.convertTo(image16, CV_16SC1);
  image16 += noise;
  image16.convertTo(image, CV_8UC1);
  return image;
}

void PatternLearningOptions::Check() const {
  Require(num_candidates >= 256, "pattern learning: num_candidates must be >= 256");
  Require(candidate_sigma > 0, "pattern learning: candidate_sigma must be positive");
  Require(num_images >= 1 && keypoints_per_image >= 1, "pattern learning: need images and keypoints");
  Require(start_correlation > 0 && start_correlation < 1 && correlation_step > 0,
          "pattern learning: bad correlation thresholds");
}

namespace {

// Oriented training patches: (smoothed image index, x, y, cos, sin).
struct TrainingPatch {
  int image;
  int x, y;
  float c, s;
};

struct TrainingSet {
  std::vector<cv::Mat> smoothed;
  std::vector<TrainingPatch> patches;
};

TrainingSet MakeTrainingSet(const PatternLearningOptions& options) {
  TrainingSet set;
  for (int i = 0; i < options.num_images; ++i) {
    const cv::Mat image = MakeSyntheticTrainingImage(options.seed + static_cast<std::uint64_t>(i));
    std::vector<cv::KeyPoint> corners;
    cv::FAST(image, corners, 20, true);
    std::stable_sort(corners.begin(), corners.end(),
                     [](const cv::KeyPoint& a, const cv::KeyPoint& b) { return a.response > b.response; });
    cv::Mat smoothed;
    SmoothForDescriptor(image, smoothed);
    set.smoothed.push_back(smoothed);
    int taken = 0;
    for (const auto& kp : corners) {
      if (taken >= options.keypoints_per_image) break;
      const int x = static_cast<int>(kp.pt.x), y = static_cast<int>(kp.pt.y);
      if (x < kMinKeypointBorder || y < kMinKeypointBorder || x >= image.cols - kMinKeypointBorder ||
          y >= image.rows - kMinKeypointBorder) {
        continue;
      }
      const float a = IntensityCentroidAngle(image, x, y) * static_cast<float>(std::numbers::pi / 180.0);
      set.patches.push_back({i, x, y, std::cos(a), std::sin(a)});
      ++taken;
    }
  }
  return set;
}

// Bit matrix: test t's results over all patches, packed in 64-bit words.
struct TestBits {
  size_t words = 0;
  std::vector<std::uint64_t> bits;  // tests x words
  std::vector<double> mean;
  const std::uint64_t* Row(size_t t) const { return bits.data() + t * words; }
};

TestBits EvaluateTests(const TrainingSet& set, const std::vector<BriefPair>& tests) {
  TestBits out;
  const size_t n = set.patches.size();
  out.words = (n + 63) / 64;
  out.bits.assign(tests.size() * out.words, 0);
  out.mean.assign(tests.size(), 0.0);
  for (size_t k = 0; k < n; ++k) {
    const TrainingPatch& p = set.patches[k];
    const cv::Mat& img = set.smoothed[static_cast<size_t>(p.image)];
    auto pixel = [&](int px, int py) {
      const int u =
          static_cast<int>(std::floor(static_cast<float>(px) * p.c - static_cast<float>(py) * p.s + 0.5f));
      const int v =
          static_cast<int>(std::floor(static_cast<float>(px) * p.s + static_cast<float>(py) * p.c + 0.5f));
      return img.at<std::uint8_t>(p.y + v, p.x + u);
    };
    for (size_t t = 0; t < tests.size(); ++t) {
      const BriefPair& q = tests[t];
      if (pixel(q.x1, q.y1) < pixel(q.x2, q.y2))
        out.bits[t * out.words + k / 64] |= std::uint64_t{1} << (k % 64);
    }
  }
  for (size_t t = 0; t < tests.size(); ++t) {
    size_t ones = 0;
    for (size_t w = 0; w < out.words; ++w) ones += static_cast<size_t>(std::popcount(out.Row(t)[w]));
    out.mean[t] = static_cast<double>(ones) / static_cast<double>(n);
  }
  return out;
}

double Correlation(const TestBits& bits, size_t a, size_t b, size_t n) {
  size_t both = 0;
  const std::uint64_t* ra = bits.Row(a);
  const std::uint64_t* rb = bits.Row(b);
  for (size_t w = 0; w < bits.words; ++w) both += static_cast<size_t>(std::popcount(ra[w] & rb[w]));
  const double pa = bits.mean[a], pb = bits.mean[b];
  const double denom = std::sqrt(pa * (1 - pa) * pb * (1 - pb));
  if (denom <= 0) return 1.0;
  return (static_cast<double>(both) / static_cast<double>(n) - pa * pb) / denom;
}

PatternLearningStats Stats(const TestBits& bits, const std::vector<size_t>& kept, size_t n) {
  PatternLearningStats stats;
  stats.training_patches = static_cast<int>(n);
  double bias = 0, corr = 0;
  size_t pairs = 0;
  for (size_t i = 0; i < kept.size(); ++i) {
    bias += std::abs(bits.mean[kept[i]] - 0.5);
    for (size_t j = 0; j < i; ++j, ++pairs) corr += std::abs(Correlation(bits, kept[i], kept[j], n));
  }
  stats.mean_abs_bias = bias / static_cast<double>(kept.size());
  stats.mean_abs_correlation = pairs > 0 ? corr / static_cast<double>(pairs) : 0.0;
  return stats;
}

}  // namespace

BriefPattern LearnBriefPattern(const PatternLearningOptions& options, PatternLearningStats* stats) {
  options.Check();
  const TrainingSet set = MakeTrainingSet(options);
  Require(set.patches.size() >= 1000, "pattern learning: too few training patches");
  const std::vector<BriefPair> candidates =
      GenerateGaussianPairs(options.seed, options.num_candidates, options.candidate_sigma);
  const TestBits bits = EvaluateTests(set, candidates);
  const size_t n = set.patches.size();
  // Order by closeness of the mean to 0.5 (ties by index, for determinism).
  std::vector<size_t> order(candidates.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    return std::abs(bits.mean[a] - 0.5) < std::abs(bits.mean[b] - 0.5);
  });
  std::vector<size_t> kept;
  double threshold = options.start_correlation;
  for (;; threshold += options.correlation_step) {
    Require(threshold < 1.0, "pattern learning: could not select 256 tests");
    kept.clear();
    for (const size_t t : order) {
      bool ok = true;
      for (const size_t k : kept) {
        if (std::abs(Correlation(bits, t, k, n)) > threshold) {
          ok = false;
          break;
        }
      }
      if (ok) kept.push_back(t);
      if (kept.size() == 256) break;
    }
    if (kept.size() == 256) break;
  }
  BriefPattern pattern{};
  for (size_t i = 0; i < 256; ++i) pattern[i] = candidates[kept[i]];
  if (stats != nullptr) {
    *stats = Stats(bits, kept, n);
    stats->final_correlation_threshold = threshold;
  }
  return pattern;
}

PatternLearningStats EvaluateBriefPattern(const BriefPattern& pattern,
                                          const PatternLearningOptions& options) {
  options.Check();
  const TrainingSet set = MakeTrainingSet(options);
  const std::vector<BriefPair> tests(pattern.begin(), pattern.end());
  const TestBits bits = EvaluateTests(set, tests);
  std::vector<size_t> all(256);
  for (size_t i = 0; i < 256; ++i) all[i] = i;
  return Stats(bits, all, set.patches.size());
}

std::string FormatBriefPatternTable(const BriefPattern& pattern) {
  std::ostringstream out;
  out << "// Generated by semslam::LearnBriefPattern(PatternLearningOptions{}) (orb_pattern.h); do not "
         "edit.\n";
  for (const BriefPair& p : pattern) {
    out << "{" << int{p.x1} << ", " << int{p.y1} << ", " << int{p.x2} << ", " << int{p.y2} << "},\n";
  }
  return out.str();
}

}  // namespace semslam
