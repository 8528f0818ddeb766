// GPS as the thread between maps (system/atlas_georeference.h) and localization that knows where it is not
// (system/localizer.h), in process, on real KITTI 07 frames with their real RTK GPS track: a drive whose
// tracking is cut, so that two maps never merge visually.

#include "semslam/system/atlas_georeference.h"

#include <gtest/gtest.h>

#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "semslam/geo/gps.h"
#include "semslam/io/sequence.h"
#include "semslam/report/geo_outputs.h"
#include "semslam/system/localizer.h"
#include "semslam/system/slam_system.h"
#include "support/test_support.h"

namespace semslam {
namespace {

struct CutDrive {
  std::unique_ptr<ImageSequence> sequence;
  std::vector<size_t> frames;  // the sequence frame of each frame of the drive
  std::vector<double> times;
};

// Frames [a0, a1) of KITTI 07, then 2 s later frames [b0, b1): the second part starts where the first map has
// no points, and no loop closing merges the two.
CutDrive MakeCutDrive(const std::filesystem::path& kitti, size_t a0, size_t a1, size_t b0, size_t b1) {
  CutDrive d{OpenSequence(kitti / "sequences" / "07"), {}, {}};
  for (size_t i = a0; i < a1; ++i) {
    d.frames.push_back(i);
    d.times.push_back(d.sequence->Timestamp(i));
  }
  const double offset = d.sequence->Timestamp(a1 - 1) + 2.0 - d.sequence->Timestamp(b0);
  for (size_t i = b0; i < b1; ++i) {
    d.frames.push_back(i);
    d.times.push_back(d.sequence->Timestamp(i) + offset);
  }
  return d;
}

// The RTK track's positions at the drive's frames (those for which `keep(k)`), at the drive's times.
GpsLog TrackAtDriveTimes(const GpsLog& track, const CutDrive& d, const std::function<bool(size_t)>& keep) {
  GpsLog log;
  log.source = track.source;
  log.format = track.format;
  for (size_t k = 0; k < d.frames.size(); ++k) {
    if (!keep(k)) continue;
    GpsFix fix = track.fixes[d.frames[k]];
    fix.timestamp = d.times[k];
    log.fixes.push_back(fix);
  }
  return log;
}

std::unique_ptr<SlamSystem> RunDrive(const CutDrive& d) {
  SlamOptions options;
  options.mode = SensorMode::kMonocular;
  options.pacing = Pacing::kSynchronous;
  options.loop.merge_maps = false;
  auto slam = std::make_unique<SlamSystem>(options, d.sequence->camera(), std::nullopt);
  for (size_t k = 0; k < d.frames.size(); ++k)
    slam->ProcessFrame(k, d.times[k], d.sequence->LoadImage(d.frames[k]));
  slam->Finish();
  return slam;
}

// Frames 0-99, then 60-159 again after a cut: two maps over the same street, never merged visually. With GPS
// on both, each is placed in the world and they are joined: the places both passed agree there.
TEST(AtlasGeoreference, JoinsMapsThatNoPlaceTiedTogether) {
  SEMSLAM_REQUIRE_SHARED_DATA(kitti, "kitti_odom_07_3dv");
  SEMSLAM_REQUIRE_SHARED_DATA(rtk, "kitti_odom_gps_rtk/RTK_GPS_kitti_07.kml");
  const CutDrive d = MakeCutDrive(kitti, 0, 100, 60, 160);
  const std::unique_ptr<SlamSystem> slam = RunDrive(d);
  const std::map<std::uint32_t, size_t> before = slam->TrackedFramesPerMap();
  ASSERT_EQ(before.size(), 2u) << "the cut must leave two maps";

  const GpsLog gps = TrackAtDriveTimes(ReadGpsKml(rtk), d, [](size_t) { return true; });
  AtlasGeoreferenceOptions options;
  options.fusion.sampling.every_n_frames = 5;
  const AtlasGeoreference placed = GeoreferenceAtlas(*slam, gps, {}, options);
  ASSERT_EQ(placed.maps.size(), 2u);
  for (const MapGeoreferenceSummary& m : placed.maps) {
    EXPECT_TRUE(m.in_world) << "map " << m.map_id << ": " << m.reason;
    EXPECT_EQ(m.inliers, m.samples) << "map " << m.map_id;  // real RTK fixes are all kept
  }
  ASSERT_EQ(placed.world_maps.size(), 1u);
  const std::map<std::uint32_t, size_t> after = slam->TrackedFramesPerMap();
  ASSERT_EQ(after.size(), 1u) << "the maps in the world are joined";
  EXPECT_EQ(after.begin()->second, before.begin()->second + std::next(before.begin())->second);

  // Frames 60-99 were driven in both parts: the same place in the world, from two maps.
  std::map<size_t, std::vector<Eigen::Vector3d>> at_frame;
  for (const FramePose& pose : slam->FramePoses())
    at_frame[d.frames[pose.frame_index]].push_back(pose.world_from_camera.translation);
  double worst = 0.0;
  int both = 0;
  for (size_t f = 60; f < 100; ++f) {
    if (at_frame[f].size() != 2) continue;
    ++both;
    worst = std::max(worst, (at_frame[f][0] - at_frame[f][1]).norm());
  }
  std::printf("frames 60-99 in both maps: %d, the two places at most %.2f m apart\n", both, worst);
  // Measured (synchronous, reproducible): the second map starts at frame 71, so frames 71-99 are in both, at
  // most 0.80 m apart.
  EXPECT_GE(both, 28);
  EXPECT_LT(worst, 0.85);
}

// Frames 50-119, 54 m of straight street: the fixes lie on one line and leave the roll about it free; the
// cameras' down axis sets it, and the drive is placed in the world, level.
TEST(AtlasGeoreference, AStraightDriveIsPlacedLevelByItsCameras) {
  SEMSLAM_REQUIRE_SHARED_DATA(kitti, "kitti_odom_07_3dv");
  SEMSLAM_REQUIRE_SHARED_DATA(rtk, "kitti_odom_gps_rtk/RTK_GPS_kitti_07.kml");
  CutDrive d{OpenSequence(kitti / "sequences" / "07"), {}, {}};
  for (size_t i = 50; i < 120; ++i) {
    d.frames.push_back(i);
    d.times.push_back(d.sequence->Timestamp(i));
  }
  const std::unique_ptr<SlamSystem> slam = RunDrive(d);
  const GpsLog gps = TrackAtDriveTimes(ReadGpsKml(rtk), d, [](size_t) { return true; });
  AtlasGeoreferenceOptions options;
  options.fusion.sampling.every_n_frames = 10;
  // The OXTS in the camera frame (KITTI raw's calibration of this car).
  options.fusion.antenna_in_camera_m = Eigen::Vector3d(-0.314, 0.719, -1.089);
  const AtlasGeoreference placed = GeoreferenceAtlas(*slam, gps, {}, options);
  ASSERT_EQ(placed.maps.size(), 1u);
  const MapGeoreferenceSummary& m = placed.maps.front();
  ASSERT_TRUE(m.in_world) << m.reason;
  EXPECT_TRUE(m.roll_from_cameras);

  // Every frame's antenna against its own fix (most of them fixes the fusion never saw), and the cameras'
  // mean down axis against the world's.
  const EnuFrame& enu = *placed.enu;
  double sum = 0.0;
  Eigen::Vector3d down = Eigen::Vector3d::Zero(), right = Eigen::Vector3d::Zero();
  const std::vector<FramePose> poses = slam->FramePoses();
  for (const FramePose& pose : poses) {
    const Eigen::Vector3d antenna = pose.world_from_camera * options.fusion.antenna_in_camera_m;
    sum += (antenna - enu.ToEnu(gps.fixes[pose.frame_index].position)).squaredNorm();
    down += pose.world_from_camera.rotation * Eigen::Vector3d::UnitY();
    right += pose.world_from_camera.rotation * Eigen::Vector3d::UnitX();
  }
  const double rmse = std::sqrt(sum / static_cast<double>(poses.size()));
  const double tilt_deg = std::acos(-down.normalized().z()) * 180.0 / M_PI;
  // The roll alone: how far the image rows' mean direction climbs out of the horizontal.
  const double roll_deg = std::asin(right.normalized().z()) * 180.0 / M_PI;
  std::printf(
      "straight frames 50-119: %zu frames in the world, %.3f m RMSE against the RTK fixes, cameras "
      "tilted %.2f deg, rolled %.2f deg\n",
      poses.size(), rmse, tilt_deg, roll_deg);
  // Measured (synchronous, reproducible): 70 frames, 0.037 m, tilted 1.00 deg (the camera's pitch on the
  // car), rolled -0.02 deg.
  EXPECT_EQ(poses.size(), 70u);
  EXPECT_LT(rmse, 0.05);
  EXPECT_LT(tilt_deg, 1.5);
  EXPECT_LT(std::abs(roll_deg), 0.25);
}

// Frames 0-79 with GPS, then 100-159 without: the second map is not in the world. Localizing in it gives
// poses in that map and never a WGS84 position; frames of the first map get one.
TEST(AtlasGeoreference, LocalizationInAMapThatIsNotInTheWorldGivesNoWgs84) {
  SEMSLAM_REQUIRE_SHARED_DATA(kitti, "kitti_odom_07_3dv");
  SEMSLAM_REQUIRE_SHARED_DATA(rtk, "kitti_odom_gps_rtk/RTK_GPS_kitti_07.kml");
  const CutDrive d = MakeCutDrive(kitti, 0, 80, 100, 160);
  const std::unique_ptr<SlamSystem> slam = RunDrive(d);
  ASSERT_EQ(slam->TrackedFramesPerMap().size(), 2u) << "the cut must leave two maps";
  const GpsLog gps = TrackAtDriveTimes(ReadGpsKml(rtk), d, [&](size_t k) { return d.frames[k] < 80; });
  AtlasGeoreferenceOptions options;
  options.fusion.sampling.every_n_frames = 5;
  const AtlasGeoreference placed = GeoreferenceAtlas(*slam, gps, {}, options);
  GeoContext geo;
  std::uint32_t outside = 0;
  for (const MapGeoreferenceSummary& m : placed.maps) {
    if (m.in_world) {
      geo.maps.emplace(m.map_id, Georeference(*placed.enu, Sim3d()));
    } else {
      outside = m.map_id;
    }
  }
  ASSERT_EQ(geo.maps.size(), 1u);
  ASSERT_EQ(geo.maps.count(outside), 0u);

  testing::TempDir dir;
  MapFileContents sections;
  sections.extra_sections["geo"] = GeoSectionJson(geo);
  slam->SaveMap(dir / "map.semslam", sections);
  for (const auto& [first, end, name] :
       {std::tuple<size_t, size_t, const char*>{110, 160, "outside"}, {20, 70, "inside"}}) {
    LocalizeOptions localize;
    localize.map = dir / "map.semslam";
    localize.sequence = kitti / "sequences" / "07";
    localize.output = dir / name;
    localize.first_frame = first;
    localize.end_frame = end;
    localize.show_progress = false;
    const LocalizeSummary summary = LocalizeSequence(localize);
    std::printf("frames %zu-%zu: %zu of %zu localized, %zu in the world\n", first, end - 1, summary.localized,
                summary.frames, summary.in_world);
    EXPECT_GE(summary.localized, 45u) << name;
    std::ifstream csv(dir / name / "localization.csv");
    std::string line;
    std::getline(csv, line);
    int rows = 0, with_wgs84 = 0, in_outside = 0;
    while (std::getline(csv, line)) {
      ++rows;
      std::vector<std::string> fields;
      std::stringstream stream(line);
      for (std::string field; std::getline(stream, field, ',');) fields.push_back(field);
      ASSERT_GE(fields.size(), 12u);
      const bool map_outside = std::stoul(fields[3]) == outside;
      in_outside += map_outside ? 1 : 0;
      with_wgs84 += fields[11].empty() ? 0 : 1;
      if (map_outside) {
        EXPECT_TRUE(fields[11].empty()) << "a pose in a map out of the world has a latitude";
      }
    }
    if (std::string(name) == "outside") {
      EXPECT_EQ(in_outside, rows);
      EXPECT_EQ(with_wgs84, 0);
      EXPECT_EQ(summary.in_world, 0u);
    } else {
      EXPECT_EQ(in_outside, 0);
      EXPECT_EQ(with_wgs84, rows);
      EXPECT_EQ(summary.in_world, summary.localized);
    }
  }
}

}  // namespace
}  // namespace semslam
