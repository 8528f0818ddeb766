// The camera a map was fitted to: a monocular map whose final BA refined the intrinsics keeps the refined
// camera (its keyframes, map.semslam), and a later session over the map (`localize`, `run --map-in`)
// undistorts its frames with it when its sequence's camera is the map's nominal one.

#include <gtest/gtest.h>

#include <cmath>

#include "semslam/io/kitti_odometry.h"
#include "semslam/map/map.h"
#include "semslam/map/map_file.h"
#include "semslam/system/slam_system.h"
#include "support/kitti_camera.h"
#include "support/test_support.h"
#include "system_test_util.h"

namespace semslam::system_test {
namespace {

PinholeCamera Refined() {
  PinholeCamera c = KittiCamera();
  c.fx = c.fy = 712.8;
  c.cx = 609.5;
  c.distortion.k1 = -0.02;
  c.distortion.k2 = 0.01;
  return c;
}

TEST(ChooseTrackingCamera, TheRefinedCameraOfTheMapWhenTheSequenceHasItsNominalOne) {
  const std::map<std::uint32_t, MapCamera> cameras = {{0, {KittiCamera(), Refined()}}};
  bool other_sensor = true;
  const TrackingCameraChoice choice =
      ChooseTrackingCamera(KittiCamera(), false, cameras, {{0, 40}}, &other_sensor);
  ASSERT_TRUE(choice.map_id.has_value()) << choice.reason;
  EXPECT_EQ(*choice.map_id, 0u);
  EXPECT_EQ(choice.camera.fx, 712.8);
  EXPECT_EQ(choice.camera.distortion.k1, -0.02);
  EXPECT_FALSE(other_sensor);
  // Within the tolerance (a calibration printed with fewer digits), the same sensor.
  PinholeCamera rounded = KittiCamera();
  rounded.cx = 607.193;
  EXPECT_TRUE(ChooseTrackingCamera(rounded, false, cameras, {{0, 40}}).map_id.has_value());
}

TEST(ChooseTrackingCamera, TheSequencesOwnOtherwise) {
  const std::map<std::uint32_t, MapCamera> refined = {{0, {KittiCamera(), Refined()}}};
  // Another sensor: 1 px off in the principal point, another image size, or another lens.
  PinholeCamera shifted = KittiCamera();
  shifted.cx += 1.0;
  PinholeCamera cropped = KittiCamera();
  cropped.width = 1226;
  PinholeCamera distorted = KittiCamera();
  distorted.distortion.k1 = -0.1;
  for (const PinholeCamera& other : {shifted, cropped, distorted}) {
    bool other_sensor = false;
    const TrackingCameraChoice choice = ChooseTrackingCamera(other, false, refined, {{0, 40}}, &other_sensor);
    EXPECT_FALSE(choice.map_id.has_value()) << other.ToString();
    EXPECT_EQ(choice.camera.cx, other.cx);
    EXPECT_EQ(choice.camera.width, other.width);
    EXPECT_EQ(choice.camera.distortion.k1, other.distortion.k1);
    EXPECT_TRUE(other_sensor);
    EXPECT_NE(choice.reason.find("another camera"), std::string::npos) << choice.reason;
  }
  // A map that kept its nominal camera (of a version-2 file: no distortion known), and a stereo session.
  bool other_sensor = true;
  const TrackingCameraChoice nominal = ChooseTrackingCamera(
      KittiCamera(), false, {{0, {KittiCamera(), KittiCamera()}}}, {{0, 40}}, &other_sensor);
  EXPECT_FALSE(nominal.map_id.has_value());
  EXPECT_FALSE(other_sensor);
  EXPECT_NE(nominal.reason.find("nominal"), std::string::npos) << nominal.reason;
  const TrackingCameraChoice lens =
      ChooseTrackingCamera(distorted, false, {{0, {KittiCamera(), KittiCamera()}}}, {{0, 40}}, &other_sensor);
  EXPECT_FALSE(lens.map_id.has_value());
  EXPECT_EQ(lens.camera.distortion.k1, -0.1);
  EXPECT_FALSE(other_sensor);
  const TrackingCameraChoice stereo = ChooseTrackingCamera(KittiCamera(), true, refined, {{0, 40}});
  EXPECT_FALSE(stereo.map_id.has_value());
  EXPECT_TRUE(stereo.camera.distortion.IsZero());
  EXPECT_NE(stereo.reason.find("stereo"), std::string::npos) << stereo.reason;
}

TEST(ChooseTrackingCamera, TheMapOfMostKeyFramesDecides) {
  PinholeCamera other_refinement = Refined();
  other_refinement.fx = other_refinement.fy = 716.0;
  const std::map<std::uint32_t, MapCamera> cameras = {{0, {KittiCamera(), Refined()}},
                                                      {3, {KittiCamera(), other_refinement}}};
  const TrackingCameraChoice choice = ChooseTrackingCamera(KittiCamera(), false, cameras, {{0, 40}, {3, 90}});
  ASSERT_TRUE(choice.map_id.has_value());
  EXPECT_EQ(*choice.map_id, 3u);
  EXPECT_EQ(choice.camera.fx, 716.0);
}

// The 200-frame city read through a calib.txt whose focal length is 4 % long (747.6 px for the 718.9 px of
// its images), as a published calibration can be a little off (2 % was refined, to 720.8 px, but lowered the
// cost by 0.8 % only, which the final BA does not take from noise). The dataset links the city's images and
// copies its times, truth and scene; `out` is a monocular run of it.
constexpr double kClaimedFocalScale = 1.04;

// A copy of the run's sequence whose calibration says another camera: the principal point 0.02 px off.
fs::path AnotherSensor(const fs::path& run, const fs::path& dir) {
  const fs::path sequence = dir / "sequences" / "00", original = SequenceDir(run / "dataset");
  fs::create_directories(sequence);
  fs::create_symlink(fs::read_symlink(original / "image_0"), sequence / "image_0");
  fs::copy_file(original / "times.txt", sequence / "times.txt");
  fs::create_directories(dir / "poses");
  fs::copy_file(run / "dataset" / "poses" / "00.txt", dir / "poses" / "00.txt");
  fs::copy_file(run / "dataset" / "scene.json", dir / "scene.json");
  KittiCalibration calibration = ReadKittiCalibration(original / "calib.txt");
  for (Eigen::Matrix3x4d& p : calibration.projection) p(0, 2) += 0.02;
  WriteKittiCalibration(sequence / "calib.txt", calibration);
  return sequence;
}

Artifact OffCalibrationRun() {
  const Artifact city = SyntheticDataset();
  if (!city.ok()) return city;
  const std::vector<std::string> args = {"run", "--mode", "mono", "--pacing", "synchronous", "-q"};
  std::vector<std::string> recipe = args;
  recipe.push_back(city.dir.string());
  recipe.push_back("focal x " + std::to_string(kClaimedFocalScale));
  return SharedArtifact("off_calibration_run", recipe, [&](const fs::path& dir) -> std::string {
    const fs::path data = dir / "dataset";
    const fs::path sequence = SequenceDir(data), original = SequenceDir(city.dir);
    fs::create_directories(sequence);
    fs::create_directories(data / "poses");
    fs::create_symlink(fs::absolute(original / "image_0"), sequence / "image_0");
    fs::copy_file(original / "times.txt", sequence / "times.txt");
    fs::copy_file(city.dir / "poses" / "00.txt", data / "poses" / "00.txt");
    fs::copy_file(city.dir / "scene.json", data / "scene.json");
    KittiCalibration calibration = ReadKittiCalibration(original / "calib.txt");
    for (Eigen::Matrix3x4d& p : calibration.projection) {
      p(0, 0) *= kClaimedFocalScale;
      p(1, 1) *= kClaimedFocalScale;
      p(0, 3) *= kClaimedFocalScale;  // fx * tx: the baseline stays
    }
    WriteKittiCalibration(sequence / "calib.txt", calibration);
    std::vector<std::string> full = args;
    full.insert(full.begin() + 1, {"--sequence", sequence.string(), "--out", (dir / "out").string()});
    const CommandResult r = RunSemslam(full);
    return r.Succeeded() ? "" : r.Describe();
  });
}

TEST(MapCamera, AMapRefinedInItsFinalBundleAdjustmentLocalizesItsOwnDriveWithTheCameraItWasRefinedTo) {
  SEMSLAM_REQUIRE_BINARY();
  SEMSLAM_ASSERT_ARTIFACT(run, OffCalibrationRun());
  const fs::path sequence = SequenceDir(run / "dataset"), out = run / "out";
  const nlohmann::json j = ReadJson(out / "run.json");
  ASSERT_TRUE(j.is_object()) << ReadText(out / "run.json");
  const std::uint32_t main = j["maps"].value("main_map", 0u);
  nlohmann::json refinement;
  for (const nlohmann::json& r : j["intrinsics_refinement"]) {
    if (r.value("map", -1) == static_cast<int>(main)) refinement = r;
  }
  ASSERT_TRUE(refinement.is_object()) << j["intrinsics_refinement"].dump(2);
  ASSERT_TRUE(refinement.value("accepted", false)) << refinement.dump(2);
  const double claimed_fx = refinement["nominal"]["fx"].get<double>();
  const double refined_fx = refinement["refined"]["fx"].get<double>();
  const double true_fx = claimed_fx / kClaimedFocalScale;
  // The refinement goes most of the way back to the focal length of the images (measured: 747.6 -> 722.3 for
  // 718.9; the cost 2.9 % lower).
  EXPECT_LT(std::abs(refined_fx - true_fx), 0.25 * (claimed_fx - true_fx)) << refinement.dump(2);

  // map.semslam records the refined camera for that map, beside the nominal one, and its keyframes carry it.
  {
    Map map;
    auto lock = map.WriteLock();
    const MapFileContents contents = ReadMapFile(out / "map.semslam", map);
    ASSERT_TRUE(contents.cameras.count(main));
    const MapCamera& camera = contents.cameras.at(main);
    EXPECT_TRUE(camera.refined());
    EXPECT_EQ(camera.nominal.fx, claimed_fx);
    EXPECT_EQ(camera.camera.fx, refined_fx);
    EXPECT_EQ(camera.camera.distortion.k1, refinement["refined"]["k1"].get<double>());
    for (const KeyFrame* kf : map.KeyFramesOfMap(main)) {
      ASSERT_EQ(kf->camera().fx, refined_fx) << "keyframe " << kf->id();
      ASSERT_TRUE(kf->camera().distortion.IsZero()) << "keyframe " << kf->id();
    }
  }

  // `localize` over the same drive: with the map's camera, as localize.json says.
  testing::TempDir dir;
  const fs::path localized = dir / "localize";
  const CommandResult r = RunSemslam({"localize", "--map", (out / "map.semslam").string(), "--sequence",
                                      sequence.string(), "--out", localized.string(), "-q"});
  ASSERT_TRUE(r.Succeeded()) << r.Describe();
  const nlohmann::json l = ReadJson(localized / "localize.json");
  ASSERT_TRUE(l.is_object()) << ReadText(localized / "localize.json");
  ASSERT_TRUE(l.contains("camera")) << l.dump(2);
  EXPECT_EQ(l["camera"].value("source", ""), "map") << l["camera"].dump(2);
  EXPECT_EQ(l["camera"].value("map", -1), static_cast<int>(main));
  EXPECT_EQ(l["camera"]["fx"].get<double>(), refined_fx);
  EXPECT_EQ(l["camera"]["k1"].get<double>(), refinement["refined"]["k1"].get<double>());
  // Measured: all 200 frames localized, all within 1 m of the truth after a Sim(3) alignment, median 0.145 m.
  EXPECT_GE(l.value("localized", 0), kSyntheticFrames * 95 / 100);
  EXPECT_GE(l.value("within_1m", 0.0), 0.95);

  // The same drive read as another camera (the nominal one but for 0.02 px): its own camera, with a warning,
  // and the error of a map fitted to another camera (measured: median 0.267 m, 200 frames localized).
  const fs::path other = AnotherSensor(run, dir / "other");
  const CommandResult o = RunSemslam({"localize", "--map", (out / "map.semslam").string(), "--sequence",
                                      other.string(), "--out", (dir / "other_localize").string()});
  ASSERT_TRUE(o.Succeeded()) << o.Describe();
  size_t warnings = 0;
  for (const std::string& line : Lines(o.err))
    warnings += line.find("[warning]") != std::string::npos &&
                line.find("another camera than map") != std::string::npos;
  EXPECT_EQ(warnings, 1u) << o.err;
  const nlohmann::json lo = ReadJson(dir / "other_localize" / "localize.json");
  ASSERT_TRUE(lo.is_object() && lo.contains("camera")) << lo.dump(2);
  EXPECT_EQ(lo["camera"].value("source", ""), "sequence") << lo["camera"].dump(2);
  EXPECT_EQ(lo["camera"]["fx"].get<double>(), claimed_fx);
  EXPECT_EQ(lo["camera"]["k1"].get<double>(), 0.0);
  EXPECT_GE(lo.value("localized", 0), kSyntheticFrames * 90 / 100);
  EXPECT_LT(l.value("error_median_m", 1e9), 0.8 * lo.value("error_median_m", 0.0))
      << "the map's camera: " << l.dump(2) << "\nthe sequence's: " << lo.dump(2);
}

}  // namespace
}  // namespace semslam::system_test
