#include "semslam/report/plots.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <set>
#include <stdexcept>

#include "semslam/core/atomic_file.h"
#include "semslam/core/error.h"
#include "semslam/semantics/class_table.h"

namespace semslam {

namespace {

constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;
const cv::Scalar kBlack(0, 0, 0);
const cv::Scalar kWhite(255, 255, 255);

std::vector<Eigen::Vector2d> Horizontal(const Points3d& points) {
  std::vector<Eigen::Vector2d> out;
  out.reserve(points.size());
  for (const Eigen::Vector3d& p : points) {
    if (p.allFinite()) out.push_back(p.head<2>());
  }
  return out;
}

void Append(std::vector<Eigen::Vector2d>& to, const std::vector<Eigen::Vector2d>& from) {
  to.insert(to.end(), from.begin(), from.end());
}

void DrawPolyline(cv::Mat& image, const TopView& view, const Points3d& points, const cv::Scalar& color,
                  int thickness) {
  std::vector<cv::Point> pixels;
  pixels.reserve(points.size());
  for (const Eigen::Vector3d& p : points) {
    if (p.allFinite()) pixels.push_back(view.ToPixel(p.head<2>()));
  }
  if (pixels.size() >= 2) cv::polylines(image, pixels, false, color, thickness, cv::LINE_AA);
}

// Text with a white halo, readable over lines and heat maps.
void DrawLabel(cv::Mat& image, const std::string& text, cv::Point at, double scale = 0.5,
               const cv::Scalar& color = kBlack) {
  cv::putText(image, text, at, kFont, scale, kWhite, 3, cv::LINE_AA);
  cv::putText(image, text, at, kFont, scale, color, 1, cv::LINE_AA);
}

void DrawCross(cv::Mat& image, cv::Point c, int r, const cv::Scalar& color, int thickness = 2) {
  cv::line(image, c + cv::Point(-r, -r), c + cv::Point(r, r), color, thickness, cv::LINE_AA);
  cv::line(image, c + cv::Point(-r, r), c + cv::Point(r, -r), color, thickness, cv::LINE_AA);
}

// A round length (1, 2 or 5 times a power of ten) about a fifth of the drawing's width.
double NiceLength(double metres) {
  const double p = std::pow(10.0, std::floor(std::log10(metres)));
  for (const double m : {5.0, 2.0, 1.0}) {
    if (m * p <= metres) return m * p;
  }
  return p;
}

std::string LengthLabel(double metres) {
  if (metres >= 1000.0) return fmt::format("{:g} km", metres / 1000.0);
  if (metres >= 1.0) return fmt::format("{:g} m", metres);
  return fmt::format("{:g} cm", metres * 100.0);
}

void DrawScaleBarAndNorth(cv::Mat& image, const TopView& view) {
  const double length_m = NiceLength(0.2 * view.width() / view.pixels_per_metre());
  const int length_px = static_cast<int>(std::lround(length_m * view.pixels_per_metre()));
  const cv::Point start(20, view.height() - 22);
  const cv::Point end = start + cv::Point(length_px, 0);
  cv::rectangle(image, start + cv::Point(0, -3), end + cv::Point(0, 3), kBlack, cv::FILLED);
  cv::rectangle(image, start + cv::Point(length_px / 2, -2), end + cv::Point(0, 2), kWhite, cv::FILLED);
  DrawLabel(image, LengthLabel(length_m), end + cv::Point(8, 5));
  // North arrow, top left.
  const cv::Point tip(30, 30), base(30, 62);
  cv::arrowedLine(image, base, tip, kBlack, 2, cv::LINE_AA, 0, 0.35);
  DrawLabel(image, "N", tip + cv::Point(8, 12));
}

struct LegendEntry {
  enum class Symbol { kLine, kDot, kCross, kSquare };
  Symbol symbol;
  cv::Scalar color;
  std::string text;
};

// The image with a legend panel appended on its right (the drawing's pixels keep their coordinates).
cv::Mat WithLegend(const cv::Mat& image, const std::vector<LegendEntry>& entries) {
  if (entries.empty()) return image;
  int text_width = 0;
  for (const LegendEntry& e : entries) {
    int baseline = 0;
    text_width = std::max(text_width, cv::getTextSize(e.text, kFont, 0.5, 1, &baseline).width);
  }
  const int row = 22;
  const int w = 46 + text_width + 12, h = 10 + row * static_cast<int>(entries.size());
  cv::Mat panel(image.rows, w + 20, CV_8UC3, kWhite);
  const cv::Point origin(5, std::min(60, std::max(0, image.rows - h - 1)));
  cv::rectangle(panel, origin, origin + cv::Point(w, h), cv::Scalar(120, 120, 120), 1);
  for (size_t i = 0; i < entries.size(); ++i) {
    const LegendEntry& e = entries[i];
    const cv::Point c = origin + cv::Point(22, 5 + row / 2 + row * static_cast<int>(i));
    switch (e.symbol) {
      case LegendEntry::Symbol::kLine:
        cv::line(panel, c - cv::Point(14, 0), c + cv::Point(14, 0), e.color, 3, cv::LINE_AA);
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
    }
    cv::putText(panel, e.text, c + cv::Point(24, 5), kFont, 0.5, kBlack, 1, cv::LINE_AA);
  }
  cv::Mat out;
  cv::hconcat(image, panel, out);
  return out;
}

void DrawTitle(cv::Mat& image, const std::string& title) {
  if (title.empty()) return;
  int baseline = 0;
  const cv::Size size = cv::getTextSize(title, kFont, 0.7, 2, &baseline);
  DrawLabel(image, title, cv::Point((image.cols - size.width) / 2, 28), 0.7);
}

cv::Scalar Bgr(const Rgb& c) {
  return {static_cast<double>(c.b), static_cast<double>(c.g), static_cast<double>(c.r)};
}

}  // namespace

void PlotOptions::Check() const {
  Require(max_side_px >= 100 && max_side_px <= 20000, "plot max_side_px must be in [100, 20000]");
  Require(margin_px >= 0 && margin_px < max_side_px / 2, "plot margin_px must be in [0, max_side_px / 2)");
  Require(std::isfinite(min_extent_m) && min_extent_m > 0, "plot min_extent_m must be positive");
}

TopView::TopView(const std::vector<Eigen::Vector2d>& points, const PlotOptions& options) {
  options.Check();
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector2d hi = -lo;
  for (const Eigen::Vector2d& p : points) {
    if (!p.allFinite()) continue;
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  if (!lo.allFinite()) lo = hi = Eigen::Vector2d::Zero();
  // At least min_extent_m on each side, centred.
  const Eigen::Vector2d centre = 0.5 * (lo + hi);
  const Eigen::Vector2d half = (0.5 * (hi - lo)).cwiseMax(0.5 * options.min_extent_m);
  lo = centre - half;
  hi = centre + half;
  const Eigen::Vector2d extent = hi - lo;
  const int inner = options.max_side_px - 2 * options.margin_px;
  pixels_per_metre_ = inner / extent.maxCoeff();
  min_ = lo;
  margin_ = options.margin_px;
  width_ = static_cast<int>(std::ceil(extent.x() * pixels_per_metre_)) + 2 * margin_;
  height_ = static_cast<int>(std::ceil(extent.y() * pixels_per_metre_)) + 2 * margin_;
}

cv::Point2d TopView::ToPixelF(const Eigen::Vector2d& enu) const {
  return {margin_ + (enu.x() - min_.x()) * pixels_per_metre_,
          (height_ - margin_) - (enu.y() - min_.y()) * pixels_per_metre_};
}

cv::Point TopView::ToPixel(const Eigen::Vector2d& enu) const {
  const cv::Point2d p = ToPixelF(enu);
  return {static_cast<int>(std::lround(p.x)), static_cast<int>(std::lround(p.y))};
}

Eigen::Vector2d TopView::ToEnu(const cv::Point2d& pixel) const {
  return {min_.x() + (pixel.x - margin_) / pixels_per_metre_,
          min_.y() + ((height_ - margin_) - pixel.y) / pixels_per_metre_};
}

cv::Mat TopView::NewImage() const { return cv::Mat(height_, width_, CV_8UC3, kWhite); }

cv::Mat RenderGpsPlot(const GpsPlotInput& input, const PlotOptions& options) {
  Require(input.gps_inliers.empty() || input.gps_inliers.size() == input.gps_enu.size(),
          "GPS plot: one inlier flag per fix");
  std::vector<Eigen::Vector2d> all = Horizontal(input.gps_enu);
  Append(all, Horizontal(input.trajectory_enu));
  Append(all, Horizontal(input.single_sim3_enu));
  const TopView view(all, options);
  cv::Mat image = view.NewImage();
  std::vector<LegendEntry> legend;
  if (!input.single_sim3_enu.empty()) {
    DrawPolyline(image, view, input.single_sim3_enu, PlotColors::SingleSim3(), 2);
    legend.push_back({LegendEntry::Symbol::kLine, PlotColors::SingleSim3(), "SLAM, one Sim(3)"});
  }
  DrawPolyline(image, view, input.trajectory_enu, PlotColors::Trajectory(), 2);
  legend.push_back({LegendEntry::Symbol::kLine, PlotColors::Trajectory(), "SLAM trajectory (transformed)"});
  bool any_outlier = false;
  for (size_t i = 0; i < input.gps_enu.size(); ++i) {
    if (!input.gps_enu[i].allFinite()) continue;
    const cv::Point p = view.ToPixel(input.gps_enu[i].head<2>());
    if (input.gps_inliers.empty() || input.gps_inliers[i]) {
      cv::circle(image, p, 5, PlotColors::GpsInlier(), cv::FILLED, cv::LINE_AA);
    } else {
      DrawCross(image, p, 6, PlotColors::GpsOutlier());
      any_outlier = true;
    }
  }
  legend.push_back({LegendEntry::Symbol::kDot, PlotColors::GpsInlier(), "GPS fixes"});
  if (any_outlier)
    legend.push_back({LegendEntry::Symbol::kCross, PlotColors::GpsOutlier(), "GPS outliers (rejected)"});
  DrawScaleBarAndNorth(image, view);
  DrawTitle(image, options.title);
  return WithLegend(image, legend);
}

cv::Mat RenderTopologyPlot(const TopologicalMap& map, const PlotOptions& options) {
  Points3d trajectory;
  for (const TopoKeyframe& k : map.keyframes) trajectory.push_back(k.enu);
  std::vector<Eigen::Vector2d> all = Horizontal(trajectory);
  for (const TopoNode& n : map.nodes) all.push_back(n.enu.head<2>());
  for (const TopoLandmark& l : map.landmarks) {
    if (l.node >= 0) all.push_back(l.enu.head<2>());
  }
  const TopView view(all, options);
  cv::Mat image = view.NewImage();
  DrawPolyline(image, view, trajectory, cv::Scalar(215, 215, 215), 2);
  for (const TopoEdge& e : map.edges) DrawPolyline(image, view, e.polyline_enu, PlotColors::Edge(), 3);
  for (const TopoLandmark& l : map.landmarks) {
    if (l.node < 0) continue;
    const cv::Point at = view.ToPixel(l.enu.head<2>());
    const cv::Point node = view.ToPixel(map.nodes[static_cast<size_t>(l.node)].enu.head<2>());
    cv::line(image, at, node, PlotColors::LandmarkNode(), 1, cv::LINE_AA);
    cv::circle(image, at, 4, PlotColors::LandmarkNode(), 1, cv::LINE_AA);
  }
  for (const TopoNode& n : map.nodes) {
    const cv::Point p = view.ToPixel(n.enu.head<2>());
    if (n.is_turn)
      cv::rectangle(image, p - cv::Point(6, 6), p + cv::Point(6, 6), PlotColors::TurnNode(), cv::FILLED);
    if (n.is_landmark)
      cv::circle(image, p, n.is_turn ? 5 : 7, PlotColors::LandmarkNode(), cv::FILLED, cv::LINE_AA);
  }
  for (const TopoNode& n : map.nodes) {
    std::string names;
    for (const int l : n.landmarks)
      names += (names.empty() ? "" : " / ") + map.landmarks[static_cast<size_t>(l)].name;
    if (!names.empty()) DrawLabel(image, names, view.ToPixel(n.enu.head<2>()) + cv::Point(10, -8));
  }
  DrawScaleBarAndNorth(image, view);
  DrawTitle(image, options.title);
  return WithLegend(image, {{LegendEntry::Symbol::kDot, PlotColors::LandmarkNode(), "landmark node"},
                            {LegendEntry::Symbol::kSquare, PlotColors::TurnNode(), "turn node"},
                            {LegendEntry::Symbol::kLine, PlotColors::Edge(), "reachable (driven)"},
                            {LegendEntry::Symbol::kLine, cv::Scalar(215, 215, 215), "trajectory"}});
}

cv::Mat RenderSemanticMapPlot(const Points3d& points_enu, const std::vector<int>& labels,
                              const Points3d& trajectory_enu, const PlotOptions& options) {
  Require(labels.size() == points_enu.size(), "semantic map plot: one label per point");
  // Framed by the trajectory and the points near it: a few far, badly triangulated points would otherwise
  // shrink the map into a corner.
  constexpr double kMarginM = 60.0;
  std::vector<Eigen::Vector2d> all = Horizontal(trajectory_enu);
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const auto& p : all) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  for (const Eigen::Vector2d& p : Horizontal(points_enu)) {
    const bool near = all.empty() || ((p.array() >= lo.array() - kMarginM).all() &&
                                      (p.array() <= hi.array() + kMarginM).all());
    if (near) all.push_back(p);
  }
  const TopView view(all, options);
  cv::Mat image = view.NewImage();
  std::set<int> present;
  const int radius = view.pixels_per_metre() >= 4.0 ? 2 : 1;
  for (size_t i = 0; i < points_enu.size(); ++i) {
    if (!points_enu[i].allFinite()) continue;
    const bool labelled = IsValidTrainId(labels[i]);
    if (labelled && labels[i] == TrainId(SemanticClass::kSky)) continue;  // sky points have no place on a map
    if (labelled) present.insert(labels[i]);
    const cv::Scalar color = labelled ? Bgr(ClassColor(labels[i])) : cv::Scalar(180, 180, 180);
    cv::circle(image, view.ToPixel(points_enu[i].head<2>()), radius, color, cv::FILLED);
  }
  DrawPolyline(image, view, trajectory_enu, kBlack, 1);
  std::vector<LegendEntry> legend;
  for (const int c : present)
    legend.push_back({LegendEntry::Symbol::kSquare, Bgr(ClassColor(c)), std::string(ClassName(c))});
  legend.push_back({LegendEntry::Symbol::kLine, kBlack, "trajectory"});
  DrawScaleBarAndNorth(image, view);
  DrawTitle(image, options.title);
  return WithLegend(image, legend);
}

cv::Mat RenderMembershipPlot(const MembershipRaster& raster, const std::vector<PlacedLandmark>& landmarks,
                             const Points3d& trajectory_enu, const PlotOptions& options) {
  Require(
      raster.cols >= 0 && raster.rows >= 0 &&
          raster.max_membership.size() == static_cast<size_t>(raster.cols) * static_cast<size_t>(raster.rows),
      "membership plot: raster size mismatch");
  std::vector<Eigen::Vector2d> all = Horizontal(trajectory_enu);
  for (const PlacedLandmark& l : landmarks) all.push_back(l.enu.head<2>());
  if (raster.cols > 0 && raster.rows > 0) {
    all.push_back(raster.origin);
    all.push_back(raster.origin + raster.cell_m * Eigen::Vector2d(raster.cols, raster.rows));
  }
  const TopView view(all, options);
  cv::Mat image = view.NewImage();
  if (raster.cols > 0 && raster.rows > 0) {
    // Sample the raster at every pixel (nearest cell), then colour by a perceptual map.
    cv::Mat value(image.rows, image.cols, CV_8UC1, cv::Scalar(0));
    cv::Mat inside(image.rows, image.cols, CV_8UC1, cv::Scalar(0));
    for (int y = 0; y < image.rows; ++y) {
      for (int x = 0; x < image.cols; ++x) {
        const Eigen::Vector2d enu = view.ToEnu(cv::Point2d(x + 0.5, y + 0.5));
        const int col = static_cast<int>(std::floor((enu.x() - raster.origin.x()) / raster.cell_m));
        const int row = static_cast<int>(std::floor((enu.y() - raster.origin.y()) / raster.cell_m));
        if (col < 0 || row < 0 || col >= raster.cols || row >= raster.rows) continue;
        const float m = raster.max_membership[static_cast<size_t>(row) * static_cast<size_t>(raster.cols) +
                                              static_cast<size_t>(col)];
        value.at<std::uint8_t>(y, x) =
            static_cast<std::uint8_t>(std::lround(std::clamp(m, 0.0f, 1.0f) * 255.0f));
        inside.at<std::uint8_t>(y, x) = 255;
      }
    }
    cv::Mat colored;
    cv::applyColorMap(value, colored, cv::COLORMAP_VIRIDIS);
    colored.copyTo(image, inside);
  }
  DrawPolyline(image, view, trajectory_enu, kWhite, 2);
  for (const PlacedLandmark& l : landmarks) {
    const cv::Point p = view.ToPixel(l.enu.head<2>());
    cv::circle(image, p, 5, kWhite, cv::FILLED, cv::LINE_AA);
    cv::circle(image, p, 5, kBlack, 1, cv::LINE_AA);
    DrawLabel(image, l.landmark.name, p + cv::Point(8, -6));
  }
  // Colour bar: membership 0 .. 1.
  const int bar_w = 200, bar_h = 12;
  const cv::Point bar(image.cols - bar_w - 30, image.rows - 30);
  cv::Mat ramp(1, 256, CV_8UC1);
  for (int i = 0; i < 256; ++i) ramp.at<std::uint8_t>(0, i) = static_cast<std::uint8_t>(i);
  cv::Mat ramp_colored, ramp_resized;
  cv::applyColorMap(ramp, ramp_colored, cv::COLORMAP_VIRIDIS);
  cv::resize(ramp_colored, ramp_resized, cv::Size(bar_w, bar_h), 0, 0, cv::INTER_NEAREST);
  ramp_resized.copyTo(image(cv::Rect(bar.x, bar.y, bar_w, bar_h)));
  cv::rectangle(image, cv::Rect(bar.x, bar.y, bar_w, bar_h), kBlack, 1);
  DrawLabel(image, "0", bar + cv::Point(-4, -6));
  DrawLabel(image, "1", bar + cv::Point(bar_w - 4, -6));
  DrawLabel(image, "membership", bar + cv::Point(bar_w / 2 - 40, -6));
  DrawScaleBarAndNorth(image, view);
  DrawTitle(image, options.title);
  return image;
}

void WritePlot(const std::filesystem::path& path, const cv::Mat& image) {
  Require(!image.empty(), "WritePlot: empty image");
  std::vector<std::uint8_t> bytes;
  if (!cv::imencode(".png", image, bytes)) throw std::runtime_error("cannot encode PNG for " + path.string());
  WriteFileAtomically(path, std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
}

}  // namespace semslam
