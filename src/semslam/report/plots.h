#pragma once
// Plots a person would rather look at than read (OpenCV drawing, PNG): top views with a scale bar and a legend,
// in the ENU plane with north up when the map is georeferenced, else in the level map frame (the first camera
// looking up the page) with the scale in map units for a monocular map and no north arrow.
//  - GPS vs the transformed SLAM trajectory (the paper's Fig. 2),
//  - the topological map (Fig. 3): nodes with landmark names, edges, the trajectory faint behind,
//  - the semantic map: points coloured by the Cityscapes palette,
//  - the landmark membership field m(x, y) as a heat map with the landmarks and the trajectory.
// Each Render* returns the image (BGR, CV_8UC3): the TopView's drawing, whose pixels keep the TopView's
// coordinates, with a legend panel appended on the right when the plot has a legend.

#include <filesystem>
#include <opencv2/core/mat.hpp>
#include <optional>
#include <string>
#include <vector>

#include "semslam/geometry/eigen_types.h"
#include "semslam/report/class_colors.h"
#include "semslam/landmarks/landmark_map.h"
#include "semslam/topology/topological_map.h"

namespace semslam {

struct PlotOptions {
  int max_side_px = 1400;  // the longer side of the drawing area
  int margin_px = 60;
  double min_extent_m = 20.0;  // a smaller scene is shown at least this wide
  std::string title;           // drawn at the top when not empty
  bool north_up = true;        // the view is ENU: draw a north arrow
  bool metres = true;          // lengths are metres (else map units: a monocular map without GPS)

  void Check() const;  // throws InvalidArgument
};

// ENU (east, north) metres <-> pixels of a top view: north up, equal scale on both axes.
class TopView {
 public:
  // Covers the horizontal bounding box of `points` (at least min_extent_m wide) inside the margins.
  TopView(const std::vector<Eigen::Vector2d>& points, const PlotOptions& options);
  // Covers all of `always` and the bulk of `bulk`: its 1st to 99th percentile per axis, so that a few far
  // points (badly triangulated ones) do not shrink the rest into a corner.
  TopView(const std::vector<Eigen::Vector2d>& always, const std::vector<Eigen::Vector2d>& bulk,
          const PlotOptions& options);

  cv::Point ToPixel(const Eigen::Vector2d& enu) const;
  cv::Point2d ToPixelF(const Eigen::Vector2d& enu) const;
  Eigen::Vector2d ToEnu(const cv::Point2d& pixel) const;
  double pixels_per_metre() const { return pixels_per_metre_; }
  int width() const { return width_; }
  int height() const { return height_; }
  cv::Mat NewImage() const;  // white, width x height

 private:
  void Fit(Eigen::Vector2d lo, Eigen::Vector2d hi, const PlotOptions& options);
  Eigen::Vector2d min_ = Eigen::Vector2d::Zero();
  double pixels_per_metre_ = 1.0;
  int margin_ = 0, width_ = 0, height_ = 0;
};

// Colours (BGR) used in the plots, for tests and legends.
struct PlotColors {
  static cv::Scalar Trajectory() { return {160, 60, 20}; }     // dark blue
  static cv::Scalar SingleSim3() { return {0, 140, 255}; }     // orange, dashed over the trajectory
  static cv::Scalar Truth() { return {60, 60, 60}; }           // dark grey, dashed
  static cv::Scalar GpsInlier() { return {40, 160, 40}; }      // green
  static cv::Scalar GpsOutlier() { return {30, 30, 220}; }     // red
  static cv::Scalar LandmarkNode() { return {20, 110, 230}; }  // orange
  static cv::Scalar TurnNode() { return {170, 60, 150}; }      // purple
  static cv::Scalar Edge() { return {60, 60, 60}; }
};

struct GpsPlotInput {
  Points3d gps_enu;               // the sampled fixes
  std::vector<bool> gps_inliers;  // empty: all inliers
  Points3d trajectory_enu;        // the SLAM trajectory in ENU (fused or aligned)
  Points3d single_sim3_enu;       // optional: the trajectory through the single global similarity
};
cv::Mat RenderGpsPlot(const GpsPlotInput& input, const PlotOptions& options = {});

cv::Mat RenderTopologyPlot(const TopologicalMap& map, const PlotOptions& options = {});

// Points and labels (trainIds; points without a label, and classes under 0.5 % of the points, are drawn grey)
// in ENU (or the level map frame, see PlotOptions).
cv::Mat RenderSemanticMapPlot(const Points3d& points_enu, const std::vector<int>& labels,
                              const Points3d& trajectory_enu, const PlotOptions& options = {});

cv::Mat RenderMembershipPlot(const MembershipRaster& raster, const std::vector<PlacedLandmark>& landmarks,
                             const Points3d& trajectory_enu, const PlotOptions& options = {});

// The trajectory from above: the estimate aligned to the ground truth (coloured by its ATE) over the ground
// truth, in the level frame of the ground truth's first camera; or the estimate alone.
struct TrajectoryPlotInput {
  Points3d estimate;           // camera centres (aligned to the truth when there is one)
  Points3d truth;              // empty: no ground truth
  std::vector<double> errors;  // ATE per estimate point (with truth), metres
  std::string estimate_label = "estimate";
};
cv::Mat RenderTrajectoryPlot(const TrajectoryPlotInput& input, const PlotOptions& options = {});

// An error along the drive, as evo_ape / evo_rpe draw it: the error per pose over the distance travelled, with
// its RMSE, median and mean as lines and mean +- std as a band.
struct ErrorPlotInput {
  std::vector<double> distance_m;
  std::vector<double> error;
  std::string y_label = "error (m)";
};
cv::Mat RenderErrorPlot(const ErrorPlotInput& input, const PlotOptions& options = {});

// PNG, atomically (temp file + rename). Throws std::runtime_error when encoding or writing fails.
void WritePlot(const std::filesystem::path& path, const cv::Mat& image);

}  // namespace semslam
