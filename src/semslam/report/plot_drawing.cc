#include "semslam/report/plot_drawing.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <opencv2/imgproc.hpp>

namespace semslam::plot {

void DrawLabel(cv::Mat& image, const std::string& text, cv::Point at, double scale, const cv::Scalar& color) {
  cv::putText(image, text, at, kFont, scale, kWhite, 3, cv::LINE_AA);
  cv::putText(image, text, at, kFont, scale, color, 1, cv::LINE_AA);
}

cv::Size TextSize(const std::string& text, double scale, int thickness) {
  int baseline = 0;
  return cv::getTextSize(text, kFont, scale, thickness, &baseline);
}

void DrawTitle(cv::Mat& image, const std::string& title) {
  if (title.empty()) return;
  // Centred, but clear of the north arrow at the top left.
  const cv::Size size = TextSize(title, 0.7, 2);
  DrawLabel(image, title, cv::Point(std::max(60, (image.cols - size.width) / 2), 28), 0.7);
}

void DrawCross(cv::Mat& image, cv::Point c, int r, const cv::Scalar& color, int thickness) {
  cv::line(image, c + cv::Point(-r, -r), c + cv::Point(r, r), color, thickness, cv::LINE_AA);
  cv::line(image, c + cv::Point(-r, r), c + cv::Point(r, -r), color, thickness, cv::LINE_AA);
}

void DrawDashedPolyline(cv::Mat& image, const std::vector<cv::Point2d>& points, const cv::Scalar& color,
                        int thickness, double dash_px, double gap_px) {
  // Walks the polyline, drawing `dash_px` on and `gap_px` off, the phase carried across vertices.
  const double period = dash_px + gap_px;
  double phase = 0.0;
  for (size_t i = 1; i < points.size(); ++i) {
    const cv::Point2d a = points[i - 1], b = points[i];
    const double length = std::hypot(b.x - a.x, b.y - a.y);
    double s = 0.0;
    while (s < length) {
      const double in_period = std::fmod(phase + s, period);
      const bool on = in_period < dash_px;
      const double step = std::min(length - s, on ? dash_px - in_period : period - in_period);
      if (on) {
        const cv::Point2d p = a + (b - a) * (s / length), q = a + (b - a) * ((s + step) / length);
        cv::line(image, cv::Point(cvRound(p.x), cvRound(p.y)), cv::Point(cvRound(q.x), cvRound(q.y)), color,
                 thickness, cv::LINE_AA);
      }
      s += std::max(step, 1e-6);
    }
    phase = std::fmod(phase + length, period);
  }
}

void LabelPlacer::ReserveAround(cv::Point centre, int radius) {
  taken_.emplace_back(centre.x - radius, centre.y - radius, 2 * radius + 1, 2 * radius + 1);
}

bool LabelPlacer::Free(const cv::Rect& box) const {
  if (box.x < 0 || box.y < 0 || box.x + box.width > size_.width || box.y + box.height > size_.height) return false;
  return std::none_of(taken_.begin(), taken_.end(), [&](const cv::Rect& t) { return (t & box).area() > 0; });
}

cv::Rect LabelPlacer::Place(cv::Mat& image, const std::string& text, cv::Point anchor, double scale,
                        const cv::Scalar& color) {
  const cv::Size size = TextSize(text, scale);
  const int w = size.width, h = size.height;
  // Top-left corners around the anchor, nearest first: right, left, above, below and the diagonals.
  const auto spots = [&](int d) {
    return std::array<cv::Point, 8>{cv::Point(d, -h / 2),          cv::Point(-d - w, -h / 2),
                                    cv::Point(-w / 2, -d - h),      cv::Point(-w / 2, d),
                                    cv::Point(d, -d - h),           cv::Point(-d - w, -d - h),
                                    cv::Point(d, d),                cv::Point(-d - w, d)};
  };
  const int pad = 2;
  for (const int d : {9, 22, 40, 62}) {
    for (const cv::Point& offset : spots(d)) {
      const cv::Rect box(anchor + offset - cv::Point(pad, pad), cv::Size(w + 2 * pad, h + 2 * pad + 3));
      if (!Free(box)) continue;
      if (d > 9) {
        const cv::Point near = anchor + offset + cv::Point(std::clamp(-offset.x, 0, w), std::clamp(-offset.y, 0, h));
        cv::line(image, anchor, near, kGrey, 1, cv::LINE_AA);
      }
      DrawLabel(image, text, anchor + offset + cv::Point(0, h), scale, color);
      taken_.push_back(box);
      return box;
    }
  }
  const cv::Point offset = spots(9)[0];
  DrawLabel(image, text, anchor + offset + cv::Point(0, h), scale, color);
  taken_.emplace_back(anchor + offset, cv::Size(w, h));
  return taken_.back();
}

double NiceLength(double limit) {
  if (!(limit > 0) || !std::isfinite(limit)) return 1.0;
  const double p = std::pow(10.0, std::floor(std::log10(limit)));
  for (const double m : {5.0, 2.0, 1.0}) {
    if (m * p <= limit) return m * p;
  }
  return p;
}

std::string LengthLabel(double length, bool metres) {
  if (!metres) return fmt::format("{:g} map unit{}", length, length == 1.0 ? "" : "s");
  if (length >= 1000.0) return fmt::format("{:g} km", length / 1000.0);
  if (length >= 1.0) return fmt::format("{:g} m", length);
  return fmt::format("{:g} cm", length * 100.0);
}

void DrawScaleBar(cv::Mat& image, double pixels_per_unit, bool metres) {
  const double length = NiceLength(0.2 * image.cols / pixels_per_unit);
  const int length_px = static_cast<int>(std::lround(length * pixels_per_unit));
  const cv::Point start(20, image.rows - 22);
  const cv::Point end = start + cv::Point(length_px, 0);
  cv::rectangle(image, start + cv::Point(0, -3), end + cv::Point(0, 3), kBlack, cv::FILLED);
  cv::rectangle(image, start + cv::Point(length_px / 2, -2), end + cv::Point(0, 2), kWhite, cv::FILLED);
  DrawLabel(image, LengthLabel(length, metres), end + cv::Point(8, 5));
}

void DrawNorthArrow(cv::Mat& image) {
  const cv::Point tip(30, 30), base(30, 62);
  cv::arrowedLine(image, base, tip, kBlack, 2, cv::LINE_AA, 0, 0.35);
  DrawLabel(image, "N", tip + cv::Point(8, 12));
}

cv::Mat WithLegend(const cv::Mat& image, const std::vector<LegendEntry>& entries) {
  if (entries.empty()) return image;
  int text_width = 0;
  for (const LegendEntry& e : entries) text_width = std::max(text_width, TextSize(e.text).width);
  const int row = 22;
  const int w = 46 + text_width + 12, h = 10 + row * static_cast<int>(entries.size());
  cv::Mat panel(std::max(image.rows, h + 10), w + 20, CV_8UC3, kWhite);
  const cv::Point origin(5, std::min(60, std::max(0, panel.rows - h - 1)));
  cv::rectangle(panel, origin, origin + cv::Point(w, h), cv::Scalar(120, 120, 120), 1);
  for (size_t i = 0; i < entries.size(); ++i) {
    const LegendEntry& e = entries[i];
    const cv::Point c = origin + cv::Point(22, 5 + row / 2 + row * static_cast<int>(i));
    switch (e.symbol) {
      case LegendEntry::Symbol::kLine:
        cv::line(panel, c - cv::Point(14, 0), c + cv::Point(14, 0), e.color, 3, cv::LINE_AA);
        break;
      case LegendEntry::Symbol::kDashedLine:
        DrawDashedPolyline(panel, {cv::Point2d(c.x - 14, c.y), cv::Point2d(c.x + 14, c.y)}, e.color, 2, 6, 4);
        break;
      case LegendEntry::Symbol::kDot:
        cv::circle(panel, c, 5, e.color, cv::FILLED, cv::LINE_AA);
        break;
      case LegendEntry::Symbol::kCross:
        DrawCross(panel, c, 5, e.color);
        break;
      case LegendEntry::Symbol::kSquare:
        cv::rectangle(panel, c - cv::Point(6, 6), c + cv::Point(6, 6), e.color, cv::FILLED);
        break;
      case LegendEntry::Symbol::kBand:
        cv::rectangle(panel, c - cv::Point(14, 6), c + cv::Point(14, 6), e.color, cv::FILLED);
        break;
    }
    cv::putText(panel, e.text, c + cv::Point(24, 5), kFont, 0.5, kBlack, 1, cv::LINE_AA);
  }
  cv::Mat body = image;
  if (image.rows < panel.rows) {
    cv::copyMakeBorder(image, body, 0, panel.rows - image.rows, 0, 0, cv::BORDER_CONSTANT, kWhite);
  }
  cv::Mat out;
  cv::hconcat(body, panel, out);
  return out;
}

cv::Scalar Viridis(double t) {
  cv::Mat value(1, 1, CV_8UC1, cv::Scalar(std::lround(std::clamp(t, 0.0, 1.0) * 255.0)));
  cv::Mat colored;
  cv::applyColorMap(value, colored, cv::COLORMAP_VIRIDIS);
  const cv::Vec3b c = colored.at<cv::Vec3b>(0, 0);
  return {static_cast<double>(c[0]), static_cast<double>(c[1]), static_cast<double>(c[2])};
}

void DrawColorBar(cv::Mat& image, double low, double high, const std::string& caption) {
  const int bar_w = 200, bar_h = 12;
  const cv::Point bar(image.cols - bar_w - 30, image.rows - 30);
  for (int x = 0; x < bar_w; ++x) {
    cv::line(image, bar + cv::Point(x, 0), bar + cv::Point(x, bar_h - 1), Viridis(x / (bar_w - 1.0)));
  }
  cv::rectangle(image, cv::Rect(bar.x, bar.y, bar_w, bar_h), kBlack, 1);
  const std::string lo = fmt::format("{:.3g}", low), hi = fmt::format("{:.3g}", high);
  DrawLabel(image, lo, bar + cv::Point(-TextSize(lo).width / 2, -6));
  DrawLabel(image, hi, bar + cv::Point(bar_w - TextSize(hi).width / 2, -6));
  DrawLabel(image, caption, bar + cv::Point(bar_w / 2 - TextSize(caption).width / 2, -22));
}

cv::Scalar Bgr(std::uint8_t r, std::uint8_t g, std::uint8_t b) {
  return {static_cast<double>(b), static_cast<double>(g), static_cast<double>(r)};
}

std::vector<Eigen::Vector2d> Horizontal(const Points3d& points) {
  std::vector<Eigen::Vector2d> out;
  out.reserve(points.size());
  for (const Eigen::Vector3d& p : points) {
    if (p.allFinite()) out.push_back(p.head<2>());
  }
  return out;
}

}  // namespace semslam::plot
