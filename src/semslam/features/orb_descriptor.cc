#include "semslam/features/orb_descriptor.h"

#include <cmath>
#include <numbers>
#include <opencv2/imgproc.hpp>
#include <optional>

namespace semslam {
namespace {

// Half-widths of the orientation disc per row offset: |u| <= kDiscHalfWidth[|v|].
struct DiscTable {
  std::array<int, kOrientationRadius + 1> half_width{};
  DiscTable() {
    const double r2 = (kOrientationRadius + 0.5) * (kOrientationRadius + 0.5);
    for (int v = 0; v <= kOrientationRadius; ++v) {
      half_width[static_cast<size_t>(v)] = static_cast<int>(std::floor(std::sqrt(r2 - v * v)));
    }
  }
};
const DiscTable kDisc;

}  // namespace

const BriefPattern& SemslamBriefPattern() {
  static const BriefPattern pattern = [] {
    BriefPattern p{};
    static constexpr std::int8_t kTable[256][4] = {
#include "semslam/features/orb_pattern_table.inc"
    };
    for (size_t i = 0; i < 256; ++i) p[i] = {kTable[i][0], kTable[i][1], kTable[i][2], kTable[i][3]};
    return p;
  }();
  return pattern;
}

void SmoothForDescriptor(const cv::Mat& image, cv::Mat& smoothed) {
  cv::GaussianBlur(image, smoothed, cv::Size(7, 7), 2.0, 2.0, cv::BORDER_REFLECT_101);
}

float IntensityCentroidAngle(const cv::Mat& image, int x, int y) {
  const std::ptrdiff_t step = static_cast<std::ptrdiff_t>(image.step1());
  const std::uint8_t* center = image.ptr<std::uint8_t>(y) + x;
  int m10 = 0;
  int m01 = 0;
  // Centre row.
  {
    const int w = kDisc.half_width[0];
    for (int u = -w; u <= w; ++u) m10 += u * center[u];
  }
  // Rows +v and -v together: m10 gets u * (I+ + I-), m01 gets v * (I+ - I-).
  for (int v = 1; v <= kOrientationRadius; ++v) {
    const int w = kDisc.half_width[static_cast<size_t>(v)];
    const std::uint8_t* below = center + v * step;
    const std::uint8_t* above = center - v * step;
    int diff = 0;
    for (int u = -w; u <= w; ++u) {
      const int b = below[u];
      const int a = above[u];
      diff += b - a;
      m10 += u * (b + a);
    }
    m01 += v * diff;
  }
  float angle = static_cast<float>(std::atan2(static_cast<double>(m01), static_cast<double>(m10)) *
                                   (180.0 / std::numbers::pi));
  if (angle < 0.0f) angle += 360.0f;
  if (angle >= 360.0f) angle -= 360.0f;
  return angle;
}

namespace {

// The pattern as float arrays, so that steering all 256 tests vectorizes.
struct SteeringTable {
  alignas(32) float x1[256], y1[256], x2[256], y2[256];
  explicit SteeringTable(const BriefPattern& pattern) {
    for (size_t i = 0; i < 256; ++i) {
      x1[i] = pattern[i].x1;
      y1[i] = pattern[i].y1;
      x2[i] = pattern[i].x2;
      y2[i] = pattern[i].y2;
    }
  }
};

// Nearest integer of |v| < 100 without a library call: truncation of a positive number is its floor.
inline int RoundSmall(float v) { return static_cast<int>(v + 128.5f) - 128; }

}  // namespace

Descriptor ComputeSteeredBrief(const cv::Mat& smoothed, int x, int y, float angle_deg,
                               const BriefPattern& pattern) {
  static const SteeringTable kDefaultTable(SemslamBriefPattern());
  const bool is_default = &pattern == &SemslamBriefPattern();
  std::optional<SteeringTable> own;
  if (!is_default) own.emplace(pattern);
  const SteeringTable& t = is_default ? kDefaultTable : *own;

  const float radians = angle_deg * static_cast<float>(std::numbers::pi / 180.0);
  const float c = std::cos(radians);
  const float s = std::sin(radians);
  const int step = static_cast<int>(smoothed.step1());
  const std::uint8_t* center = smoothed.ptr<std::uint8_t>(y) + x;
  // Rotated point p' = R(angle) p, rounded to the nearest pixel, as offsets from the centre pixel.
  alignas(32) int first[256];
  alignas(32) int second[256];
  for (size_t i = 0; i < 256; ++i) {
    const int u1 = RoundSmall(t.x1[i] * c - t.y1[i] * s);
    const int v1 = RoundSmall(t.x1[i] * s + t.y1[i] * c);
    const int u2 = RoundSmall(t.x2[i] * c - t.y2[i] * s);
    const int v2 = RoundSmall(t.x2[i] * s + t.y2[i] * c);
    first[i] = v1 * step + u1;
    second[i] = v2 * step + u2;
  }
  Descriptor d{};
  for (size_t word = 0; word < 4; ++word) {
    std::uint64_t bits = 0;
    const int* a = first + word * 64;
    const int* b = second + word * 64;
    for (int k = 0; k < 64; ++k) bits |= static_cast<std::uint64_t>(center[a[k]] < center[b[k]]) << k;
    d[word] = bits;
  }
  return d;
}

}  // namespace semslam
