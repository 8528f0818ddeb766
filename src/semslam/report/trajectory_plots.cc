// The trajectory from above against the ground truth, and ATE / RPE along the drive (report/plots.h).

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <opencv2/imgproc.hpp>

#include "semslam/core/error.h"
#include "semslam/report/plot_drawing.h"
#include "semslam/report/plots.h"

namespace semslam {

using namespace plot;  // NOLINT: the drawing primitives of this module

namespace {

// Axis ticks: round steps (1, 2 or 5 times a power of ten), about `count` of them over [low, high].
std::vector<double> Ticks(double low, double high, int count) {
  std::vector<double> ticks;
  if (!(high > low)) return {low};
  const double raw = (high - low) / count;
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  double step = p;
  for (const double m : {1.0, 2.0, 5.0, 10.0}) {
    if (m * p >= raw) {
      step = m * p;
      break;
    }
  }
  for (double t = std::ceil(low / step) * step; t <= high + 1e-9 * step; t += step) ticks.push_back(t);
  return ticks;
}

std::string TickLabel(double value) {
  if (std::abs(value) < 1e-12) return "0";
  return fmt::format("{:g}", std::round(value * 1e6) / 1e6);
}

}  // namespace

cv::Mat RenderTrajectoryPlot(const TrajectoryPlotInput& input, const PlotOptions& options) {
  Require(input.errors.empty() || input.errors.size() == input.estimate.size(),
          "trajectory plot: one error per estimated pose");
  std::vector<Eigen::Vector2d> all = Horizontal(input.estimate);
  const std::vector<Eigen::Vector2d> truth = Horizontal(input.truth);
  all.insert(all.end(), truth.begin(), truth.end());
  const TopView view(all, options);
  cv::Mat image = view.NewImage();
  std::vector<LegendEntry> legend;
  std::vector<cv::Point2d> truth_px;
  for (const Eigen::Vector2d& p : truth) truth_px.push_back(view.ToPixelF(p));
  if (truth_px.size() >= 2) {
    DrawDashedPolyline(image, truth_px, PlotColors::Truth(), 2);
    legend.push_back({LegendEntry::Symbol::kDashedLine, PlotColors::Truth(), "ground truth"});
  }
  const bool colored = !input.errors.empty();
  double max_error = 0.0;
  for (const double e : input.errors) max_error = std::max(max_error, e);
  for (size_t i = 1; i < input.estimate.size(); ++i) {
    const Eigen::Vector3d& a = input.estimate[i - 1];
    const Eigen::Vector3d& b = input.estimate[i];
    if (!a.allFinite() || !b.allFinite()) continue;
    const cv::Scalar color =
        colored ? Viridis(max_error > 0 ? 0.5 * (input.errors[i - 1] + input.errors[i]) / max_error : 0.0)
                : PlotColors::Trajectory();
    cv::line(image, view.ToPixel(a.head<2>()), view.ToPixel(b.head<2>()), color, 3, cv::LINE_AA);
  }
  legend.push_back({LegendEntry::Symbol::kLine, colored ? Viridis(0.5) : PlotColors::Trajectory(),
                    input.estimate_label + (colored ? " (colour: ATE)" : "")});
  if (!input.estimate.empty() && input.estimate.front().allFinite()) {
    const cv::Point start = view.ToPixel(input.estimate.front().head<2>());
    cv::circle(image, start, 6, kBlack, 2, cv::LINE_AA);
    legend.push_back({LegendEntry::Symbol::kDot, kBlack, "start"});
  }
  if (colored) DrawColorBar(image, 0.0, max_error, options.metres ? "ATE (m)" : "ATE (map units)");
  DrawScaleBar(image, view.pixels_per_metre(), options.metres);
  if (options.north_up) DrawNorthArrow(image);
  DrawTitle(image, options.title);
  return WithLegend(image, legend);
}

cv::Mat RenderErrorPlot(const ErrorPlotInput& input, const PlotOptions& options) {
  options.Check();
  Require(input.distance_m.size() == input.error.size(), "error plot: one distance per error");
  const int width = options.max_side_px, height = std::max(300, options.max_side_px * 9 / 20);
  cv::Mat image(height, width, CV_8UC3, kWhite);
  const int left = 80, right = 20, top = 50, bottom = 60;
  const cv::Rect area(left, top, width - left - right, height - top - bottom);
  double x_max = 1.0, y_max = 0.0;
  for (size_t i = 0; i < input.error.size(); ++i) {
    x_max = std::max(x_max, input.distance_m[i]);
    y_max = std::max(y_max, input.error[i]);
  }
  y_max = y_max > 0 ? 1.08 * y_max : 1.0;
  const auto to_px = [&](double x, double y) {
    return cv::Point2d(area.x + x / x_max * area.width, area.y + area.height - y / y_max * area.height);
  };
  // Statistics as evo draws them: rmse, median, mean lines, mean +- std band.
  const size_t n = input.error.size();
  double mean = 0, rmse = 0, median = 0, stddev = 0;
  if (n > 0) {
    mean = std::accumulate(input.error.begin(), input.error.end(), 0.0) / static_cast<double>(n);
    double sq = 0;
    for (const double e : input.error) sq += e * e;
    rmse = std::sqrt(sq / static_cast<double>(n));
    stddev = std::sqrt(std::max(0.0, sq / static_cast<double>(n) - mean * mean));
    std::vector<double> sorted = input.error;
    std::sort(sorted.begin(), sorted.end());
    median = n % 2 == 1 ? sorted[n / 2] : 0.5 * (sorted[n / 2 - 1] + sorted[n / 2]);
  }
  const cv::Scalar band_color(235, 215, 200), rmse_color(40, 40, 200), median_color(40, 150, 40),
      mean_color(180, 90, 20), error_color(90, 90, 90);
  if (n > 0) {
    const cv::Point2d a = to_px(0, std::min(y_max, mean + stddev)), b = to_px(x_max, std::max(0.0, mean - stddev));
    cv::rectangle(image, cv::Point(cvRound(a.x), cvRound(a.y)), cv::Point(cvRound(b.x), cvRound(b.y)), band_color,
                  cv::FILLED);
  }
  // Grid and ticks.
  for (const double t : Ticks(0, x_max, 8)) {
    const cv::Point2d p = to_px(t, 0);
    cv::line(image, cv::Point(cvRound(p.x), area.y), cv::Point(cvRound(p.x), area.y + area.height),
             cv::Scalar(228, 228, 228), 1);
    const std::string label = TickLabel(t);
    DrawLabel(image, label, cv::Point(cvRound(p.x) - TextSize(label).width / 2, area.y + area.height + 20));
  }
  for (const double t : Ticks(0, y_max, 6)) {
    const cv::Point2d p = to_px(0, t);
    cv::line(image, cv::Point(area.x, cvRound(p.y)), cv::Point(area.x + area.width, cvRound(p.y)),
             cv::Scalar(228, 228, 228), 1);
    const std::string label = TickLabel(t);
    DrawLabel(image, label, cv::Point(area.x - 8 - TextSize(label).width, cvRound(p.y) + 5));
  }
  cv::rectangle(image, area, kBlack, 1);
  std::vector<cv::Point> line;
  for (size_t i = 0; i < n; ++i) {
    const cv::Point2d p = to_px(input.distance_m[i], input.error[i]);
    line.emplace_back(cvRound(p.x), cvRound(p.y));
  }
  if (line.size() >= 2) cv::polylines(image, line, false, error_color, 1, cv::LINE_AA);
  const auto hline = [&](double y, const cv::Scalar& color) {
    const cv::Point2d a = to_px(0, y), b = to_px(x_max, y);
    cv::line(image, cv::Point(cvRound(a.x), cvRound(a.y)), cv::Point(cvRound(b.x), cvRound(b.y)), color, 2,
             cv::LINE_AA);
  };
  if (n > 0) {
    hline(rmse, rmse_color);
    DrawDashedPolyline(image, {to_px(0, median), to_px(x_max, median)}, median_color, 2);  // often on the mean
    hline(mean, mean_color);
  }
  const std::string x_label = options.metres ? "distance travelled (m)" : "distance travelled (map units)";
  DrawLabel(image, x_label, cv::Point(area.x + area.width / 2 - TextSize(x_label).width / 2, height - 14));
  cv::Mat y_text(30, TextSize(input.y_label).width + 10, CV_8UC3, kWhite);
  DrawLabel(y_text, input.y_label, cv::Point(5, 20));
  cv::Mat rotated;
  cv::rotate(y_text, rotated, cv::ROTATE_90_COUNTERCLOCKWISE);
  if (rotated.rows <= height && rotated.cols + 4 <= left) {
    rotated.copyTo(image(cv::Rect(4, area.y + area.height / 2 - rotated.rows / 2, rotated.cols, rotated.rows)));
  }
  DrawTitle(image, options.title);
  const auto value = [](double v) { return fmt::format("{:.3g}", v); };
  return WithLegend(image, {{LegendEntry::Symbol::kLine, error_color, "per pose"},
                            {LegendEntry::Symbol::kLine, rmse_color, "rmse " + value(rmse)},
                            {LegendEntry::Symbol::kDashedLine, median_color, "median " + value(median)},
                            {LegendEntry::Symbol::kLine, mean_color, "mean " + value(mean)},
                            {LegendEntry::Symbol::kBand, band_color, "mean +- std " + value(stddev)}});
}

}  // namespace semslam
