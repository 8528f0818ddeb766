#include "semslam/report/plots.h"
#include "semslam/report/plot_drawing.h"

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
  const Rgb other = ClassDisplay{}.other;
  EXPECT_EQ(image.at<cv::Vec3b>(view.ToPixel({40, 10})), cv::Vec3b(other.b, other.g, other.r));  // unlabelled
  EXPECT_THROW(RenderSemanticMapPlot(points, {}, trajectory), InvalidArgument);
}

// Present classes keep the Cityscapes palette unless two look alike: then the rarer one gets a distinct colour.
TEST(ClassColors, PresentClassesAreDistinct) {
  std::array<long long, kNumClasses> counts{};
  const int car = TrainId(SemanticClass::kCar), bus = TrainId(SemanticClass::kBus),
            train = TrainId(SemanticClass::kTrain), road = TrainId(SemanticClass::kRoad),
            pole = TrainId(SemanticClass::kPole);
  counts[static_cast<size_t>(road)] = 5000;
  counts[static_cast<size_t>(car)] = 900;
  counts[static_cast<size_t>(bus)] = 300;
  counts[static_cast<size_t>(train)] = 200;
  counts[static_cast<size_t>(pole)] = 100;
  counts[static_cast<size_t>(TrainId(SemanticClass::kTruck))] = 3;  // under 0.5 %: "other"
  const ClassDisplay display = MakeClassDisplay(counts);
  EXPECT_TRUE(display.listed[static_cast<size_t>(train)]);
  EXPECT_FALSE(display.listed[static_cast<size_t>(TrainId(SemanticClass::kTruck))]);
  EXPECT_FALSE(display.listed[static_cast<size_t>(TrainId(SemanticClass::kSidewalk))]);  // absent
  EXPECT_EQ(display.color[static_cast<size_t>(road)], ClassColor(road));
  EXPECT_EQ(display.color[static_cast<size_t>(bus)], ClassColor(bus));  // the commoner keeps its colour
  EXPECT_LT(DeltaE(ClassColor(bus), ClassColor(train)), 20.0);          // Cityscapes: near-identical blues
  EXPECT_NE(display.color[static_cast<size_t>(train)], ClassColor(train));
  EXPECT_LT(DeltaE(ClassColor(pole), display.other), 20.0);  // pole grey is the "other" grey
  EXPECT_NE(display.color[static_cast<size_t>(pole)], ClassColor(pole));
  std::vector<Rgb> listed;
  for (int c = 0; c < kNumClasses; ++c) {
    if (display.listed[static_cast<size_t>(c)]) listed.push_back(display.color[static_cast<size_t>(c)]);
  }
  ASSERT_EQ(listed.size(), 5u);
  for (size_t i = 0; i < listed.size(); ++i) {
    EXPECT_GE(DeltaE(listed[i], display.other), 20.0) << i;
    for (size_t j = i + 1; j < listed.size(); ++j) EXPECT_GE(DeltaE(listed[i], listed[j]), 20.0) << i << " " << j;
  }
}

// Labels placed by LabelPlacer never overlap, even for landmarks at one spot.
TEST(Plots, LabelsDoNotOverlap) {
  cv::Mat image(400, 600, CV_8UC3, cv::Scalar(255, 255, 255));
  plot::LabelPlacer placer(image.size());
  placer.ReserveAround(cv::Point(300, 200), 7);  // the node's marker
  std::vector<cv::Rect> boxes;
  for (const char* name : {"Opera House", "Guild Hall", "Town Hall", "Central Library", "Observatory"}) {
    const cv::Rect box = placer.Place(image, name, cv::Point(300, 200));
    EXPECT_GT(box.area(), 0) << name;
    EXPECT_EQ((box & cv::Rect(293, 193, 15, 15)).area(), 0) << name << " covers the marker";
    for (const cv::Rect& other : boxes) EXPECT_EQ((box & other).area(), 0) << name;
    boxes.push_back(box);
  }
}

TEST(Plots, ErrorPlotAndTrajectoryPlotWithoutNorth) {
  ErrorPlotInput errors;
  for (int i = 0; i < 100; ++i) {
    errors.distance_m.push_back(i);
    errors.error.push_back(0.1 + 0.05 * std::sin(0.1 * i));
  }
  const cv::Mat chart = RenderErrorPlot(errors);
  EXPECT_GT(NonWhite(chart), 2000);
  errors.error.pop_back();
  EXPECT_THROW(RenderErrorPlot(errors), InvalidArgument);

  TrajectoryPlotInput input;
  input.estimate = Loop();
  PlotOptions options;
  options.north_up = false;
  options.metres = false;
  const cv::Mat plain = RenderTrajectoryPlot(input, options);
  options.north_up = true;
  const cv::Mat north = RenderTrajectoryPlot(input, options);
  ASSERT_EQ(plain.size(), north.size());
  // The north arrow is the only difference, at the top left.
  cv::Mat diff;
  cv::absdiff(plain, north, diff);
  cv::cvtColor(diff, diff, cv::COLOR_BGR2GRAY);
  const cv::Rect changed = cv::boundingRect(diff);
  EXPECT_GT(changed.area(), 0);
  EXPECT_LT(changed.x + changed.width, 80);
  EXPECT_LT(changed.y + changed.height, 90);
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
