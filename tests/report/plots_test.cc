#include "semslam/report/plots.h"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "semslam/core/error.h"
#include "semslam/semantics/class_table.h"
#include "support/test_support.h"

namespace semslam {
namespace {

using testing::TempDir;

cv::Vec3b Bgr(const cv::Scalar& s) {
  return cv::Vec3b(static_cast<uchar>(s[0]), static_cast<uchar>(s[1]), static_cast<uchar>(s[2]));
}

int NonWhite(const cv::Mat& image) {
  cv::Mat grey;
  cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  return static_cast<int>(image.total()) - cv::countNonZero(grey == 255);
}

// A 200 x 100 m rectangle driven anticlockwise.
Points3d Loop() {
  Points3d points;
  for (int i = 0; i <= 200; i += 2) points.emplace_back(i, 0, 0);
  for (int i = 2; i <= 100; i += 2) points.emplace_back(200, i, 0);
  for (int i = 198; i >= 0; i -= 2) points.emplace_back(i, 100, 0);
  for (int i = 98; i >= 0; i -= 2) points.emplace_back(0, i, 0);
  return points;
}

TEST(TopView, NorthUpEqualScale) {
  PlotOptions options;
  options.max_side_px = 600;
  options.margin_px = 50;
  const TopView view({Eigen::Vector2d(0, 0), Eigen::Vector2d(200, 100)}, options);
  EXPECT_DOUBLE_EQ(view.pixels_per_metre(), 2.5);
  EXPECT_EQ(view.width(), 600);
  EXPECT_EQ(view.height(), 350);
  EXPECT_EQ(view.ToPixel(Eigen::Vector2d(0, 0)), cv::Point(50, 300));      // south-west: bottom left
  EXPECT_EQ(view.ToPixel(Eigen::Vector2d(200, 100)), cv::Point(550, 50));  // north-east: top right
  EXPECT_NEAR((view.ToEnu(view.ToPixelF(Eigen::Vector2d(31, 47))) - Eigen::Vector2d(31, 47)).norm(), 0.0,
              1e-9);
  // A single point still gets min_extent_m around it.
  const TopView tiny({Eigen::Vector2d(5, 5)}, options);
  EXPECT_DOUBLE_EQ(tiny.pixels_per_metre(), 500.0 / options.min_extent_m);
  options.max_side_px = 10;
  EXPECT_THROW(TopView({}, options), InvalidArgument);
}

TEST(Plots, GpsFixesAndTrajectory) {
  GpsPlotInput input;
  input.trajectory_enu = Loop();
  input.gps_enu = {{0, 0, 0}, {100, 0, 0}, {200, 50, 0}, {100, 150, 0}};
  input.gps_inliers = {true, true, true, false};
  PlotOptions options;
  options.title = "GPS vs SLAM";
  const cv::Mat image = RenderGpsPlot(input, options);
  ASSERT_EQ(image.type(), CV_8UC3);
  const TopView view(std::vector<Eigen::Vector2d>{{0, 0}, {200, 150}}, options);
  EXPECT_EQ(view.width(), options.max_side_px);
  EXPECT_EQ(image.rows, view.height());
  EXPECT_GT(image.cols, view.width() + 100);  // the legend panel
  EXPECT_GT(NonWhite(image), 5000);
  EXPECT_EQ(image.at<cv::Vec3b>(view.ToPixel({100, 0})), Bgr(PlotColors::GpsInlier()));
  EXPECT_EQ(image.at<cv::Vec3b>(view.ToPixel({100, 150})), Bgr(PlotColors::GpsOutlier()));
  EXPECT_EQ(image.at<cv::Vec3b>(view.ToPixel({100, 100})), Bgr(PlotColors::Trajectory()));
  EXPECT_EQ(image.at<cv::Vec3b>(view.ToPixel({100, 50})), cv::Vec3b(255, 255, 255));  // inside the loop
  input.gps_inliers = {true};
  EXPECT_THROW(RenderGpsPlot(input), InvalidArgument);

  TempDir dir;
  WritePlot(dir / "plots" / "gps.png", image);
  const cv::Mat back = cv::imread((dir / "plots" / "gps.png").string(), cv::IMREAD_COLOR);
  ASSERT_EQ(back.size(), image.size());
  EXPECT_EQ(cv::norm(back, image, cv::NORM_INF), 0.0);  // PNG is lossless
}

TEST(Plots, SemanticMapInThePalette) {
  Points3d points;
  std::vector<int> labels;
  for (int i = 0; i < 50; ++i) {
    points.emplace_back(i, 30, 1);
    labels.push_back(TrainId(SemanticClass::kBuilding));
  }
  points.emplace_back(25, 10, 0);
  labels.push_back(TrainId(SemanticClass::kCar));
  points.emplace_back(10, 10, 50);
  labels.push_back(TrainId(SemanticClass::kSky));  // not drawn
  points.emplace_back(40, 10, 0);
  labels.push_back(kNoLabel);
  const Points3d trajectory = {{0, 0, 0}, {50, 0, 0}};
  PlotOptions options;
  options.max_side_px = 500;
  const cv::Mat image = RenderSemanticMapPlot(points, labels, trajectory, options);
  std::vector<Eigen::Vector2d> extent = {{0, 0}, {50, 30}};
  const TopView view(extent, options);
  const Rgb car = ClassColor(TrainId(SemanticClass::kCar));
  const Rgb building = ClassColor(TrainId(SemanticClass::kBuilding));
  EXPECT_EQ(image.at<cv::Vec3b>(view.ToPixel({25, 10})), cv::Vec3b(car.b, car.g, car.r));
  EXPECT_EQ(image.at<cv::Vec3b>(view.ToPixel({20, 30})), cv::Vec3b(building.b, building.g, building.r));
  EXPECT_EQ(image.at<cv::Vec3b>(view.ToPixel({10, 10})), cv::Vec3b(255, 255, 255));  // sky skipped
  EXPECT_EQ(image.at<cv::Vec3b>(view.ToPixel({40, 10})), cv::Vec3b(180, 180, 180));  // unlabelled
  EXPECT_THROW(RenderSemanticMapPlot(points, {}, trajectory), InvalidArgument);
}

TEST(Plots, TopologyNodesAndMembershipField) {
  const Georeference g(EnuFrame(Wgs84{49.0, 8.4, 100.0}), Sim3d());
  FramePositions keyframes;
  for (const Eigen::Vector3d& p : Loop()) keyframes.push_back(FramePosition{keyframes.size(), -1, 0.0, p});
  std::vector<Landmark> catalogue(2);
  catalogue[0].name = "Museum";
  catalogue[0].position = g.enu_frame.ToWgs84(Eigen::Vector3d(100, -10, 0));
  catalogue[1].name = "Station";
  catalogue[1].position = g.enu_frame.ToWgs84(Eigen::Vector3d(210, 100, 0));
  for (Landmark& l : catalogue) l.has_altitude = true;
  const auto placed = PlaceLandmarks(catalogue, g, keyframes);
  const TopologicalMap map = BuildTopologicalMap(keyframes, placed, g);
  ASSERT_EQ(map.NumLandmarkNodes(), 2);
  PlotOptions options;
  options.max_side_px = 800;
  const cv::Mat topo = RenderTopologyPlot(map, options);
  EXPECT_GT(NonWhite(topo), 5000);
  std::vector<Eigen::Vector2d> extent = {{0, -10}, {210, 100}};
  const TopView view(extent, options);
  EXPECT_EQ(topo.at<cv::Vec3b>(view.ToPixel({100, 0})), Bgr(PlotColors::LandmarkNode()));
  EXPECT_EQ(topo.at<cv::Vec3b>(view.ToPixel({200, 0})), Bgr(PlotColors::TurnNode()));
  EXPECT_EQ(topo.at<cv::Vec3b>(view.ToPixel({200, 100})),
            Bgr(PlotColors::LandmarkNode()));  // landmark + turn

  const MembershipRaster raster = RasterizeMembership(placed, {-20, -40}, {240, 140}, 2.0, 25.0);
  const cv::Mat field = RenderMembershipPlot(raster, placed, Loop(), options);
  std::vector<Eigen::Vector2d> field_extent = {{-20, -40}, {240, 140}};
  const TopView fview(field_extent, options);
  cv::Mat grey(1, 2, CV_8UC1), colored;
  grey.at<uchar>(0, 0) = 0;
  grey.at<uchar>(0, 1) = static_cast<uchar>(std::lround(255 * std::exp(-0.5)));
  cv::applyColorMap(grey, colored, cv::COLORMAP_VIRIDIS);
  // Far from both landmarks (185 m and more): membership 0; 25 m (one sigma) south of the museum: exp(-1/2),
  // up to the cell's quantization (2 m cells).
  EXPECT_EQ(field.at<cv::Vec3b>(fview.ToPixel({-15, 130})), colored.at<cv::Vec3b>(0, 0));
  const cv::Vec3b at_sigma = field.at<cv::Vec3b>(fview.ToPixel({101, -35}));
  EXPECT_LT(cv::norm(cv::Vec3d(at_sigma) - cv::Vec3d(colored.at<cv::Vec3b>(0, 1))), 30.0);
  EXPECT_EQ(field.at<cv::Vec3b>(fview.ToPixel({100, -10})), cv::Vec3b(255, 255, 255));  // the marker
}

}  // namespace
}  // namespace semslam
