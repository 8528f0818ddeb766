#include "semslam/features/orb_descriptor.h"

#include <cmath>
#include <numbers>
#include <opencv2/imgproc.hpp>

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

Descriptor ComputeSteeredBrief(const cv::Mat& smoothed, int x, int y, float angle_deg, const BriefPattern& pattern) {
  const float radians = angle_deg * static_cast<float>(std::numbers::pi / 180.0);
  const float c = std::cos(radians);
  const float s = std::sin(radians);
  const int step = static_cast<int>(smoothed.step1());
  const std::uint8_t* center = smoothed.ptr<std::uint8_t>(y) + x;
  // Rotated point p' = R(angle) p, rounded to the nearest pixel; as offsets from the centre pixel.
  std::array<int, 512> offsets;
  for (size_t i = 0; i < 256; ++i) {
    const BriefPair& p = pattern[i];
    const float x1 = p.x1, y1 = p.y1, x2 = p.x2, y2 = p.y2;
    const int u1 = static_cast<int>(std::floor(x1 * c - y1 * s + 0.5f));
    const int v1 = static_cast<int>(std::floor(x1 * s + y1 * c + 0.5f));
    const int u2 = static_cast<int>(std::floor(x2 * c - y2 * s + 0.5f));
    const int v2 = static_cast<int>(std::floor(x2 * s + y2 * c + 0.5f));
    offsets[2 * i] = v1 * step + u1;
    offsets[2 * i + 1] = v2 * step + u2;
  }
  Descriptor d{};
  for (size_t word = 0; word < 4; ++word) {
    std::uint64_t bits = 0;
    const int* o = offsets.data() + word * 128;
    for (int b = 0; b < 64; ++b) {
      bits |= static_cast<std::uint64_t>(center[o[2 * b]] < center[o[2 * b + 1]]) << b;
    }
    d[word] = bits;
  }
  return d;
}

}  // namespace semslam
