// `semslam merge` (system/session_merge.h) end to end: two monocular drives through the synthetic town (the
// suite's 200-frame run and the same streets with other traffic, each with GPS and landmarks) merged into one
// map, a session each.

#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <string>

#include "semslam/map/map.h"
#include "semslam/map/map_file.h"
#include "system_test_util.h"

namespace semslam::system_test {
namespace {

// `semslam merge --maps RUNS... --out <artifact>/out EXTRA...`, once per binary.
Artifact Merge(const std::string& name, const std::vector<Artifact>& runs,
               const std::vector<std::string>& extra) {
  std::vector<std::string> args = {"merge", "-q", "--maps"};
  for (const Artifact& run : runs) {
    if (!run.ok()) return {{}, run.error};
    args.push_back(run.dir.string());
  }
  args.insert(args.end(), extra.begin(), extra.end());
  Artifact merged = SharedArtifact(name, args, [&](const fs::path& dir) -> std::string {
    std::vector<std::string> full = args;
    full.insert(full.end(), {"--out", (dir / "out").string()});
    const CommandResult r = RunSemslam(full);
    return r.Succeeded() ? "" : r.Describe();
  });
  if (merged.ok()) merged.dir /= "out";
  return merged;
}

Artifact TwoDrives() { return Merge("merge_two_drives", {MonoRun(), SecondDriveMonoRun()}, {}); }

// Each session of a merge: every frame of its drive's run in the one map, and in the world nearer the truth
// than its own run put it: the merged map is fused with both drives' GPS (measured: 0.45-0.50 times its own
// run's error, which is 1.64 m from 7 fixes of 1 m noise).
void ExpectEverySessionWhole(const nlohmann::json& run, const std::vector<Artifact>& drives) {
  const nlohmann::json& sessions = run["maps"]["sessions"];
  ASSERT_EQ(sessions.size(), drives.size());
  for (size_t k = 0; k < drives.size(); ++k) {
    const nlohmann::json own = ReadJson(drives[k].dir / "run.json");
    const nlohmann::json& s = sessions[k];
    EXPECT_EQ(s["source"].get<std::string>(), own["sequence"].get<std::string>()) << k;
    EXPECT_EQ(s["frames"].get<int>(), own["with_pose"].get<int>()) << k;
    EXPECT_TRUE(s["in_main_map"].get<bool>()) << k;
    EXPECT_EQ(s["frames_without_keyframe"].get<int>(), 0) << k;
    ASSERT_TRUE(s.contains("world_rmse_m")) << k;
    EXPECT_LE(s["world_rmse_m"].get<double>(),
              0.55 * own["geo_evaluation"]["trajectory_ate_rmse_m"].get<double>())
        << k;
  }
}

TEST(SessionMerge, TwoDrivesThroughOneTownBecomeOneMapWithASessionEach) {
  const Artifact first = MonoRun(), second = SecondDriveMonoRun();
  const Artifact merged = TwoDrives();
  ASSERT_TRUE(merged.ok()) << merged.error;
  const nlohmann::json run = ReadJson(merged.dir / "run.json");
  EXPECT_EQ(run["command"], "merge");
  EXPECT_EQ(run["status"], "ok");
  EXPECT_EQ(run["maps"]["count"], 1);
  // The drives share their streets: places recognized across the maps merged them, not their GPS.
  EXPECT_EQ(run["maps"]["place_merges"], 1);
  EXPECT_EQ(run["maps"]["merges_not_confirmed"], 0);
  // A map in the world is held together by its drives' GPS, not by loops between them.
  EXPECT_EQ(run["maps"]["session_loops"], 0);
  // The town's 8 landmarks, each once, placed as well as both drives' GPS place the map: median error 1.33 m
  // against 4.35 m and 4.30 m in the drives' own runs (7 fixes each).
  const nlohmann::json& landmarks = run["landmark_evaluation"];
  ASSERT_TRUE(landmarks.is_object()) << landmarks;
  EXPECT_EQ(landmarks["landmarks"], 8);
  double best_own = 1e9;
  for (const Artifact& drive : {MonoRun(), SecondDriveMonoRun()}) {
    best_own =
        std::min(best_own,
                 ReadJson(drive.dir / "run.json")["geo_evaluation"]["landmark_error_median_m"].get<double>());
  }
  EXPECT_LE(landmarks["landmark_error_median_m"].get<double>(), 0.4 * best_own);
  EXPECT_TRUE(run["maps"]["gps_joins"].empty());
  ExpectEverySessionWhole(run, {first, second});
  // Against one alignment of both drives together, each is near where its own alignment puts it. A drive's
  // own run bends its map's scale to its fixes; the merge's global BA relaxes that shape to what vision sees
  // and its fusion, holding the merged map's scale stiff, places the drives without bending them again
  // (measured: 1.13 and 2.54 times, 0.096 m and 0.069 m; the bound is 5 % above the larger).
  for (const nlohmann::json& s : run["maps"]["sessions"]) {
    const double own = ReadJson(fs::path(s["run"].get<std::string>()) / "run.json")["ate_rmse"].get<double>();
    EXPECT_LE(s["ate_rmse_city"].get<double>(), 2.67 * own) << s["name"];
  }
  for (const char* file :
       {"map.semslam", "semantic_map.ply", "landmarks.geojson", "topology.json", "report.html"})
    EXPECT_TRUE(fs::exists(merged.dir / file)) << file;
  // The merged map loads, with both drives as its sessions.
  Map map;
  auto lock = map.WriteLock();
  ReadMapFile(merged.dir / "map.semslam", map);
  ASSERT_EQ(map.sessions().size(), 2u);
  EXPECT_EQ(map.MapIds().size(), 1u);
}

// Two stereo drives through the same streets, neither with GPS: merged by a recognized place, then held
// together by loops between them along the streets they share. Each drive's ATE in the merged map under one
// alignment, against its own run's: 1.16 and 0.66 times (without the loop between them, 1.51 and 0.65);
// issue 43's bar for stereo is 1.2.
TEST(SessionMerge, TwoStereoDrivesWithoutGpsMergeByAPlaceAndCloseLoopsBetweenThem) {
  const Artifact merged = Merge("merge_two_stereo_drives", {StereoRun(), SecondDriveStereoRun()}, {});
  ASSERT_TRUE(merged.ok()) << merged.error;
  const nlohmann::json run = ReadJson(merged.dir / "run.json");
  EXPECT_EQ(run["maps"]["count"], 1);
  EXPECT_EQ(run["maps"]["place_merges"], 1);
  EXPECT_GE(run["maps"]["session_loops"], 1);
  for (const nlohmann::json& s : run["maps"]["sessions"]) {
    const double own = ReadJson(fs::path(s["run"].get<std::string>()) / "run.json")["ate_rmse"].get<double>();
    EXPECT_LE(s["ate_rmse_city"].get<double>(), 1.2 * own) << s["name"];
  }
}

// Two cameras of one real drive (KITTI raw 0005, colour image_02 and grey image_00) as two monocular drives.
// Place recognition ranks a keyframe by the share of its words it has in common with the query
// (map/place_candidates.h): by their number, the colour map's second keyframe (an initialization frame, with
// twice the features) crowded out the places of the grey drive, and the maps stayed two. Measured, each
// drive's ATE in the merged map (one alignment) against its own run's: 1.006 and 0.979 times.
TEST(SessionMerge, TwoCamerasOfARealDriveBecomeOneMap) {
  SEMSLAM_REQUIRE_BINARY();
  SEMSLAM_REQUIRE_SHARED_DATA(drive, "kitti_raw_2011_09_26_drive_0005/2011_09_26/2011_09_26_drive_0005_sync");
  testing::TempDir dir;
  for (const char* camera : {"image_02", "image_00"}) {
    const CommandResult r =
        RunSemslam({"run", "--sequence", drive.string(), "--camera", camera, "--mode", "mono", "--pacing",
                    "synchronous", "--out", (dir / camera).string(), "-q"});
    ASSERT_TRUE(r.Succeeded()) << r.Describe();
  }
  const CommandResult r = RunSemslam({"merge", "--maps", (dir / "image_02").string(),
                                      (dir / "image_00").string(), "--out", (dir / "merged").string(), "-q"});
  ASSERT_TRUE(r.Succeeded()) << r.Describe();
  const nlohmann::json run = ReadJson(dir / "merged" / "run.json");
  EXPECT_EQ(run["maps"]["count"], 1);
  EXPECT_EQ(run["maps"]["place_merges"], 1);
  for (const nlohmann::json& s : run["maps"]["sessions"]) {
    const double own = ReadJson(fs::path(s["run"].get<std::string>()) / "run.json")["ate_rmse"].get<double>();
    EXPECT_LE(s["ate_rmse_city"].get<double>(), 1.05 * own) << s["name"];
    EXPECT_EQ(s["camera_height_m"].get<double>(), 1.65) << s["name"];
  }
}

TEST(SessionMerge, AMergedMapMergesAgainAsARunDoes) {
  const Artifact first = MonoRun(), second = SecondDriveMonoRun();
  const Artifact merged = TwoDrives();
  ASSERT_TRUE(merged.ok()) << merged.error;
  // A tree of merges: the output of one is an input of the next, its sessions' frames carried along.
  const Artifact again = Merge("merge_of_a_merge", {merged}, {});
  ASSERT_TRUE(again.ok()) << again.error;
  const nlohmann::json run = ReadJson(again.dir / "run.json");
  EXPECT_EQ(run["maps"]["count"], 1);
  ExpectEverySessionWhole(run, {first, second});
}

TEST(SessionMerge, WithoutPlaceRecognitionMapsInTheWorldJoinThroughTheirGps) {
  const Artifact first = MonoRun(), second = SecondDriveMonoRun();
  const Artifact merged = Merge("merge_two_drives_gps", {first, second}, {"--no-place-recognition"});
  ASSERT_TRUE(merged.ok()) << merged.error;
  const nlohmann::json run = ReadJson(merged.dir / "run.json");
  EXPECT_EQ(run["maps"]["count"], 1);
  EXPECT_EQ(run["maps"]["place_merges"], 0);
  EXPECT_EQ(run["maps"]["gps_joins"].size(), 1u);
  ExpectEverySessionWhole(run, {first, second});
}

TEST(SessionMerge, RefusesMonocularAndStereoMapsTogether) {
  const Artifact mono = MonoRun(), stereo = StereoRun();
  ASSERT_TRUE(mono.ok() && stereo.ok()) << mono.error << stereo.error;
  testing::TempDir out;
  const CommandResult r = RunSemslam(
      {"merge", "--maps", mono.dir.string(), stereo.dir.string(), "--out", (out / "merged").string()});
  EXPECT_FALSE(r.Succeeded());
  EXPECT_NE(r.err.find("monocular and stereo maps are not merged"), std::string::npos) << r.err;
}

TEST(SessionMerge, AFolderWithoutAMapIsNamed) {
  const Artifact mono = MonoRun();
  ASSERT_TRUE(mono.ok()) << mono.error;
  testing::TempDir dir;
  fs::create_directories(dir / "not_a_run");
  const CommandResult r = RunSemslam({"merge", "--maps", mono.dir.string(), (dir / "not_a_run").string(),
                                      "--out", (dir / "merged").string()});
  EXPECT_FALSE(r.Succeeded());
  EXPECT_NE(r.err.find((dir / "not_a_run" / "map.semslam").string()), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "merged" / "run.json"));
  // One drive twice (once through a detour) is refused, and so is an output folder that is an input.
  const CommandResult twice = RunSemslam(
      {"merge", "--maps", mono.dir.string(), (mono.dir / ".").string(), "--out", (dir / "merged").string()});
  EXPECT_FALSE(twice.Succeeded());
  EXPECT_NE(twice.err.find("twice"), std::string::npos) << twice.err;
  fs::copy(mono.dir, dir / "copy", fs::copy_options::recursive);
  const CommandResult into = RunSemslam({"merge", "--maps", mono.dir.string(), (dir / "copy").string(),
                                         "--out", (dir / "copy").string(), "--overwrite"});
  EXPECT_FALSE(into.Succeeded());
  EXPECT_NE(into.err.find("which this merge reads"), std::string::npos) << into.err;
  EXPECT_TRUE(fs::exists(dir / "copy" / "map.semslam"));
}

TEST(SessionMerge, ACameraHeightThatIsNoLengthIsNamed) {
  const Artifact mono = MonoRun();
  ASSERT_TRUE(mono.ok()) << mono.error;
  testing::TempDir dir;
  fs::copy(mono.dir, dir / "copy", fs::copy_options::recursive);
  nlohmann::json j = ReadJson(dir / "copy" / "run.json");
  j["config"]["camera_height_m"] = -1.65;
  std::ofstream(dir / "copy" / "run.json") << j.dump(2);
  const CommandResult r = RunSemslam(
      {"merge", "--maps", mono.dir.string(), (dir / "copy").string(), "--out", (dir / "merged").string()});
  EXPECT_FALSE(r.Succeeded());
  EXPECT_NE(r.err.find((dir / "copy" / "run.json").string()), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("camera_height_m"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace semslam::system_test
