// `semslam route` on a topology.json and on a map.semslam whose extra section holds it.

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>

#include "semslam/map/map_file.h"
#include "semslam/topology/topological_map.h"
#include "support/test_support.h"

namespace semslam {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

int RunSemslam(const std::string& args, const fs::path& out, const fs::path& err) {
  const std::string command =
      testing::SemslamBinary().string() + " " + args + " > " + out.string() + " 2> " + err.string();
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string Read(const fs::path& p) {
  std::ifstream in(p);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// An L-shaped drive: 100 m east past the Bakery, left, 80 m north to the School.
TopologicalMap SmallMap() {
  const Georeference g(EnuFrame(Wgs84{49.0, 8.4, 110.0}), Sim3d());
  FramePositions keyframes;
  for (int i = 0; i <= 90; ++i) {
    FramePosition k;
    k.frame_index = static_cast<size_t>(i);
    k.keyframe_id = i;
    k.map_position = i <= 50 ? Eigen::Vector3d(2.0 * i, 0, 0) : Eigen::Vector3d(100, 2.0 * (i - 50), 0);
    keyframes.push_back(k);
  }
  std::vector<PlacedLandmark> landmarks(2);
  landmarks[0].landmark.name = "Bakery";
  landmarks[0].enu = Eigen::Vector3d(30, -8, 0);
  landmarks[1].landmark.name = "Old School";
  landmarks[1].enu = Eigen::Vector3d(108, 80, 0);
  for (PlacedLandmark& l : landmarks) {
    l.landmark.position = g.enu_frame.ToWgs84(l.enu);
    l.landmark.has_altitude = true;
    l.map_position = l.enu;
  }
  return BuildTopologicalMap(keyframes, landmarks, g);
}

class RouteCli : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!fs::exists(testing::SemslamBinary())) GTEST_SKIP() << "semslam binary not built";
  }
  testing::TempDir dir_;
  fs::path out_ = dir_ / "out.txt";
  fs::path err_ = dir_ / "err.txt";
};

TEST_F(RouteCli, PrintsStepsAndWritesGeoJson) {
  const TopologicalMap map = SmallMap();
  WriteTopologyJson(dir_ / "topology.json", map);
  ASSERT_EQ(RunSemslam("route --map " + (dir_ / "topology.json").string() +
                           " --from bakery --to 'Old School' --out " + (dir_ / "route.geojson").string(),
                       out_, err_),
            0)
      << Read(err_);
  const std::string text = Read(out_);
  EXPECT_THAT(text, HasSubstr("Route from Bakery to Old School, 150 m:"));
  EXPECT_THAT(text, HasSubstr("1. Start at Bakery, heading east."));
  EXPECT_THAT(text, HasSubstr("2. Drive 70 m."));
  EXPECT_THAT(text, HasSubstr("3. Turn left."));
  EXPECT_THAT(text, HasSubstr("4. Drive 80 m to Old School (on your right)."));
  const nlohmann::json route = nlohmann::json::parse(Read(dir_ / "route.geojson"));
  EXPECT_EQ(route["features"][0]["properties"]["to"], "Old School");

  ASSERT_EQ(RunSemslam("route --json --map " + (dir_ / "topology.json").string() +
                           " --from Bakery --to 'Old School'",
                       out_, err_),
            0);
  EXPECT_NEAR(nlohmann::json::parse(Read(out_))["length_m"].get<double>(), 150.0, 2.0);

  EXPECT_EQ(RunSemslam("route --map " + (dir_ / "topology.json").string() + " --from Bakery --to Cinema",
                       out_, err_),
            2);
  EXPECT_THAT(Read(err_), HasSubstr("unknown landmark 'Cinema'"));
  EXPECT_EQ(RunSemslam("route --map " + (dir_ / "missing.json").string() + " --from A --to B", out_, err_),
            1);
}

TEST_F(RouteCli, ReadsTheMapFileSection) {
  const TopologicalMap topology = SmallMap();
  Map empty;
  MapFileContents contents;
  contents.extra_sections["topology"] = TopologyJsonString(topology);
  WriteMapFile(dir_ / "map.semslam", empty, contents);
  ASSERT_EQ(RunSemslam("route --map " + (dir_ / "map.semslam").string() + " --from Bakery --to 'Old School'",
                       out_, err_),
            0)
      << Read(err_);
  EXPECT_THAT(Read(out_), HasSubstr("Drive 80 m to Old School"));

  WriteMapFile(dir_ / "bare.semslam", empty, {});
  EXPECT_EQ(RunSemslam("route --map " + (dir_ / "bare.semslam").string() + " --from A --to B", out_, err_),
            1);
  EXPECT_THAT(Read(err_), HasSubstr("no topological map"));
}

}  // namespace
}  // namespace semslam
