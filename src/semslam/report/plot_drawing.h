#pragma once
// Drawing primitives shared by the plots (report/ internal): labels with a halo that avoid each other, legends,
// scale bars in metres or map units, a north arrow, dashed lines, colour maps and colour bars.

#include <opencv2/core/mat.hpp>
#include <opencv2/core/types.hpp>
#include <string>
#include <utility>
#include <vector>

#include "semslam/geometry/eigen_types.h"

namespace semslam::plot {

inline constexpr int kFont = 0;  // cv::FONT_HERSHEY_SIMPLEX
const cv::Scalar kBlack(0, 0, 0);
const cv::Scalar kWhite(255, 255, 255);
const cv::Scalar kGrey(150, 150, 150);

// Text with a white halo, readable over lines and heat maps; `at` is the baseline's left end.
void DrawLabel(cv::Mat& image, const std::string& text, cv::Point at, double scale = 0.5,
               const cv::Scalar& color = kBlack);
cv::Size TextSize(const std::string& text, double scale = 0.5, int thickness = 1);
void DrawTitle(cv::Mat& image, const std::string& title);
void DrawCross(cv::Mat& image, cv::Point c, int r, const cv::Scalar& color, int thickness = 2);
void DrawDashedPolyline(cv::Mat& image, const std::vector<cv::Point2d>& points, const cv::Scalar& color,
                        int thickness, double dash_px = 10.0, double gap_px = 6.0);

// Places labels next to their anchors without overlapping each other or the areas marked taken: the first free
// spot of eight around the anchor, then further out with a leader line; a label with no free spot at all is
// drawn at its first spot anyway (never dropped).
class LabelPlacer {
 public:
  explicit LabelPlacer(cv::Size image_size) : size_(image_size) {}
  void Reserve(const cv::Rect& area) { taken_.push_back(area); }
  void ReserveAround(cv::Point centre, int radius);
  // Returns the area the label took.
  cv::Rect Place(cv::Mat& image, const std::string& text, cv::Point anchor, double scale = 0.5,
                 const cv::Scalar& color = kBlack);

 private:
  bool Free(const cv::Rect& box) const;
  cv::Size size_;
  std::vector<cv::Rect> taken_;
};

// A round length (1, 2 or 5 times a power of ten) no longer than `limit`.
double NiceLength(double limit);
// "2 km", "50 m", "20 cm"; in map units: "50 map units".
std::string LengthLabel(double length, bool metres);

// Scale bar at the bottom left: `pixels_per_unit` pixels per metre (or per map unit when !metres).
void DrawScaleBar(cv::Mat& image, double pixels_per_unit, bool metres);
// North arrow at the top left (only for views whose up is north).
void DrawNorthArrow(cv::Mat& image);

struct LegendEntry {
  enum class Symbol { kLine, kDashedLine, kDot, kCross, kSquare, kBand };
  // A constructor rather than an aggregate: emplace_back needs one under clang 14 (no parenthesized aggregate
  // initialization).
  LegendEntry(Symbol symbol_in, cv::Scalar color_in, std::string text_in)
      : symbol(symbol_in), color(color_in), text(std::move(text_in)) {}
  Symbol symbol;
  cv::Scalar color;
  std::string text;
};
// The image with a legend panel appended on its right (the drawing's pixels keep their coordinates).
cv::Mat WithLegend(const cv::Mat& image, const std::vector<LegendEntry>& entries);

// A perceptual colour map (viridis) at t in [0, 1].
cv::Scalar Viridis(double t);
// A horizontal colour bar from `low` to `high` with its caption, at the bottom right.
void DrawColorBar(cv::Mat& image, double low, double high, const std::string& caption);

cv::Scalar Bgr(std::uint8_t r, std::uint8_t g, std::uint8_t b);

// Horizontal (x, y) of finite points.
std::vector<Eigen::Vector2d> Horizontal(const Points3d& points);

}  // namespace semslam::plot
