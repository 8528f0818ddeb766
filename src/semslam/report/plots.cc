#include "semslam/report/plots.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "semslam/core/atomic_file.h"
#include "semslam/core/error.h"
#include "semslam/report/plot_drawing.h"
#include "semslam/semantics/class_table.h"

namespace semslam {

using namespace plot;  // NOLINT: the drawing primitives of this module

namespace {

void Append(std::vector<Eigen::Vector2d>& to, const std::vector<Eigen::Vector2d>& from) {
  to.insert(to.end(), from.begin(), from.end());
}

std::vector<cv::Point2d> Pixels(const TopView& view, const Points3d& points) {
  std::vector<cv::Point2d> pixels;
  pixels.reserve(points.size());
  for (const Eigen::Vector3d& p : points) {
    if (p.allFinite()) pixels.push_back(view.ToPixelF(p.head<2>()));
  }
  return pixels;
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

// Scale bar, and the north arrow when the view is north-up.
void DrawFrameMarks(cv::Mat& image, const TopView& view, const PlotOptions& options) {
  DrawScaleBar(image, view.pixels_per_metre(), options.metres);
  if (options.north_up) DrawNorthArrow(image);
}

cv::Scalar ToBgr(const Rgb& c) { return Bgr(c.r, c.g, c.b); }

double Percentile(std::vector<double> values, double q) {
  const auto k = static_cast<size_t>(q * static_cast<double>(values.size() - 1));
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
  return values[k];
}

}  // namespace

void PlotOptions::Check() const {
  Require(max_side_px >= 100 && max_side_px <= 20000, "plot max_side_px must be in [100, 20000]");
  Require(margin_px >= 0 && margin_px < max_side_px / 2, "plot margin_px must be in [0, max_side_px / 2)");
  Require(std::isfinite(min_extent_m) && min_extent_m > 0, "plot min_extent_m must be positive");
}

TopView::TopView(const std::vector<Eigen::Vector2d>& points, const PlotOptions& options)
    : TopView(points, {}, options) {}

TopView::TopView(const std::vector<Eigen::Vector2d>& always, const std::vector<Eigen::Vector2d>& bulk,
                 const PlotOptions& options) {
  options.Check();
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector2d hi = -lo;
  for (const Eigen::Vector2d& p : always) {
    if (!p.allFinite()) continue;
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  std::vector<double> xs, ys;
  for (const Eigen::Vector2d& p : bulk) {
    if (!p.allFinite()) continue;
    xs.push_back(p.x());
    ys.push_back(p.y());
  }
  if (!xs.empty()) {
    lo = lo.cwiseMin(Eigen::Vector2d(Percentile(xs, 0.01), Percentile(ys, 0.01)));
    hi = hi.cwiseMax(Eigen::Vector2d(Percentile(xs, 0.99), Percentile(ys, 0.99)));
  }
  Fit(lo, hi, options);
}

void TopView::Fit(Eigen::Vector2d lo, Eigen::Vector2d hi, const PlotOptions& options) {
  if (!lo.allFinite() || !hi.allFinite()) lo = hi = Eigen::Vector2d::Zero();
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
  // The fused trajectory, thick, under the single similarity's, dashed: where they agree both stay visible.
  DrawPolyline(image, view, input.trajectory_enu, PlotColors::Trajectory(), 4);
  legend.emplace_back(LegendEntry::Symbol::kLine, PlotColors::Trajectory(),
                      input.single_sim3_enu.empty() ? "SLAM trajectory (transformed)" : "SLAM, GPS fusion");
  if (!input.single_sim3_enu.empty()) {
    DrawDashedPolyline(image, Pixels(view, input.single_sim3_enu), PlotColors::SingleSim3(), 2);
    legend.emplace_back(LegendEntry::Symbol::kDashedLine, PlotColors::SingleSim3(), "SLAM, one Sim(3)");
  }
  bool any_outlier = false;
  for (size_t i = 0; i < input.gps_enu.size(); ++i) {
    if (!input.gps_enu[i].allFinite()) continue;
    const cv::Point p = view.ToPixel(input.gps_enu[i].head<2>());
    if (input.gps_inliers.empty() || input.gps_inliers[i]) {
      cv::circle(image, p, 5, PlotColors::GpsInlier(), cv::FILLED, cv::LINE_AA);
      cv::circle(image, p, 5, kWhite, 1, cv::LINE_AA);
    } else {
      DrawCross(image, p, 6, PlotColors::GpsOutlier());
      any_outlier = true;
    }
  }
  legend.emplace_back(LegendEntry::Symbol::kDot, PlotColors::GpsInlier(), "GPS fixes used");
  if (any_outlier)
    legend.emplace_back(LegendEntry::Symbol::kCross, PlotColors::GpsOutlier(), "GPS outliers (rejected)");
  DrawFrameMarks(image, view, options);
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
  const cv::Scalar trajectory_color(215, 215, 215);
  DrawPolyline(image, view, trajectory, trajectory_color, 2);
  for (const TopoEdge& e : map.edges) DrawPolyline(image, view, e.polyline_enu, PlotColors::Edge(), 3);
  LabelPlacer labels(image.size());
  labels.Reserve(cv::Rect(0, 0, image.cols, 44));                // title
  labels.Reserve(cv::Rect(0, image.rows - 40, image.cols, 40));  // scale bar
  labels.Reserve(cv::Rect(0, 0, 60, 80));                        // north arrow
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
    labels.ReserveAround(p, 7);
  }
  // One label per landmark node; names of nodes that share a spot avoid each other.
  for (const TopoNode& n : map.nodes) {
    std::string names;
    for (const int l : n.landmarks)
      names += (names.empty() ? "" : " / ") + map.landmarks[static_cast<size_t>(l)].name;
    if (!names.empty()) labels.Place(image, names, view.ToPixel(n.enu.head<2>()));
  }
  DrawFrameMarks(image, view, options);
  DrawTitle(image, options.title);
  std::vector<LegendEntry> legend;
  if (map.NumLandmarkNodes() > 0)
    legend.emplace_back(LegendEntry::Symbol::kDot, PlotColors::LandmarkNode(), "landmark node");
  if (map.NumTurnNodes() > 0)
    legend.emplace_back(LegendEntry::Symbol::kSquare, PlotColors::TurnNode(), "turn node");
  if (!map.edges.empty())
    legend.emplace_back(LegendEntry::Symbol::kLine, PlotColors::Edge(), "reachable (driven)");
  legend.emplace_back(LegendEntry::Symbol::kLine, trajectory_color, "trajectory");
  return WithLegend(image, legend);
}

cv::Mat RenderSemanticMapPlot(const Points3d& points_enu, const std::vector<int>& labels,
                              const Points3d& trajectory_enu, const PlotOptions& options) {
  Require(labels.size() == points_enu.size(), "semantic map plot: one label per point");
  const TopView view(Horizontal(trajectory_enu), Horizontal(points_enu), options);
  cv::Mat image = view.NewImage();
  std::array<long long, kNumClasses> counts{};
  long long unlabeled = 0;
  const int sky = TrainId(SemanticClass::kSky);
  for (const int label : labels) {
    if (!IsValidTrainId(label)) {
      ++unlabeled;
    } else if (label != sky) {
      ++counts[static_cast<size_t>(label)];
    }
  }
  const ClassDisplay display = MakeClassDisplay(counts);
  const int radius = view.pixels_per_metre() >= 4.0 ? 2 : 1;
  bool any_other = unlabeled > 0;
  for (size_t i = 0; i < points_enu.size(); ++i) {
    if (!points_enu[i].allFinite()) continue;
    const bool labelled = IsValidTrainId(labels[i]);
    if (labelled && labels[i] == sky) continue;  // sky points have no place on a map
    const bool listed = labelled && display.listed[static_cast<size_t>(labels[i])];
    if (labelled && !listed) any_other = true;
    const cv::Scalar color =
        listed ? ToBgr(display.color[static_cast<size_t>(labels[i])]) : ToBgr(display.other);
    cv::circle(image, view.ToPixel(points_enu[i].head<2>()), radius, color, cv::FILLED);
  }
  DrawPolyline(image, view, trajectory_enu, kBlack, 1);
  // Listed classes, commonest first.
  std::vector<int> order;
  for (int c = 0; c < kNumClasses; ++c) {
    if (display.listed[static_cast<size_t>(c)]) order.push_back(c);
  }
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return counts[static_cast<size_t>(a)] > counts[static_cast<size_t>(b)];
  });
  std::vector<LegendEntry> legend;
  for (const int c : order) {
    legend.emplace_back(LegendEntry::Symbol::kSquare, ToBgr(display.color[static_cast<size_t>(c)]),
                        std::string(ClassName(c)));
  }
  if (any_other)
    legend.emplace_back(LegendEntry::Symbol::kSquare, ToBgr(display.other), "other classes, unlabeled");
  legend.emplace_back(LegendEntry::Symbol::kLine, kBlack, "trajectory");
  DrawFrameMarks(image, view, options);
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
  LabelPlacer names(image.size());
  names.Reserve(cv::Rect(0, 0, image.cols, 44));
  names.Reserve(cv::Rect(0, image.rows - 60, image.cols, 60));
  names.Reserve(cv::Rect(0, 0, 60, 80));
  for (const PlacedLandmark& l : landmarks) {
    const cv::Point p = view.ToPixel(l.enu.head<2>());
    cv::circle(image, p, 5, kWhite, cv::FILLED, cv::LINE_AA);
    cv::circle(image, p, 5, kBlack, 1, cv::LINE_AA);
    names.ReserveAround(p, 6);
  }
  for (const PlacedLandmark& l : landmarks)
    names.Place(image, l.landmark.name, view.ToPixel(l.enu.head<2>()));
  DrawColorBar(image, 0.0, 1.0, "membership");
  DrawFrameMarks(image, view, options);
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
