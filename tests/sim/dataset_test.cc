// The dataset on disk: layout, identical bytes for identical arguments, GPS round trip through the io reader,
// scene.json contents, and the `semslam synth` command line.

#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "semslam/io/kitti_odometry.h"
#include "semslam/io/kitti_raw.h"
#include "semslam/io/sequence.h"
#include "semslam/io/trajectory_io.h"
#include "semslam/sim/dataset_writer.h"
#include "semslam/sim/gps_sim.h"
#include "semslam/sim/synthetic_city.h"
#include "support/test_support.h"

namespace semslam::sim {
namespace {
namespace fs = std::filesystem;

SynthOptions Tiny(int frames = 4) {
  SynthOptions o = PresetOptions("default");
  o.route.frames = frames;
  o.camera.width = 310;
  o.camera.height = 94;
  o.camera.focal = 718.856 / 4;
  return o;
}

std::map<std::string, std::string> Tree(const fs::path& root) {
  std::map<std::string, std::string> files;
  for (const auto& e : fs::recursive_directory_iterator(root)) {
    if (e.is_regular_file()) files[fs::relative(e.path(), root).string()] = testing::ReadText(e.path());
  }
  return files;
}

TEST(Dataset, LayoutAndIdenticalBytes) {
  const SyntheticCity sim(Tiny());
  testing::TempDir a, b;
  DatasetOptions options;
  options.progress = false;
  WriteDataset(sim, a.path(), options);
  WriteDataset(SyntheticCity(Tiny()), b.path(), options);
  const auto files_a = Tree(a.path());
  EXPECT_EQ(files_a, Tree(b.path()));
  for (const char* name : {"scene.json", "landmarks.csv", "poses/00.txt", "oxts/timestamps.txt",
                           "oxts/data/0000000003.txt", "sequences/00/calib.txt", "sequences/00/times.txt",
                           "sequences/00/image_0/000003.png", "sequences/00/image_1/000003.png",
                           "sequences/00/label_0/000003.png", "sequences/00/depth_0/000003.png"}) {
    EXPECT_TRUE(files_a.count(name)) << name;
  }
  EXPECT_FALSE(files_a.count("sequences/00/image_0/000004.png"));
  // Images as rendered; depth as 16 bits.
  const RenderedFrame r = sim.Render(2);
  const fs::path seq = a.path() / "sequences" / "00";
  EXPECT_EQ(cv::norm(cv::imread((seq / "image_0" / "000002.png").string(), cv::IMREAD_UNCHANGED), r.left,
                     cv::NORM_INF),
            0);
  EXPECT_EQ(cv::norm(cv::imread((seq / "label_0" / "000002.png").string(), cv::IMREAD_UNCHANGED), r.labels,
                     cv::NORM_INF),
            0);
  const cv::Mat depth = cv::imread((seq / "depth_0" / "000002.png").string(), cv::IMREAD_UNCHANGED);
  EXPECT_EQ(depth.type(), CV_16UC1);
  EXPECT_EQ(cv::norm(depth, r.depth, cv::NORM_INF), 0);
  // A shorter run into the same folder leaves no stale frames behind, when asked to replace it.
  try {
    WriteDataset(SyntheticCity(Tiny(2)), a.path(), options);
    ADD_FAILURE() << "an earlier dataset replaced without overwrite";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("pass --overwrite"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(fs::exists(seq / "image_0" / "000002.png"));
  options.overwrite = true;
  WriteDataset(SyntheticCity(Tiny(2)), a.path(), options);
  EXPECT_FALSE(fs::exists(seq / "image_0" / "000002.png"));
  EXPECT_FALSE(fs::exists(a.path() / "oxts" / "data" / "0000000002.txt"));
}

TEST(Dataset, ReadsBackAsAKittiSequence) {
  const SyntheticCity sim(Tiny(5));
  testing::TempDir dir;
  DatasetOptions options;
  options.progress = false;
  WriteDataset(sim, dir.path(), options);
  const auto sequence = OpenSequence(dir.path());
  ASSERT_EQ(sequence->size(), 5u);
  EXPECT_NEAR(sequence->Timestamp(3), 0.3, 1e-9);
  EXPECT_EQ(sequence->camera().width, 310);
  ASSERT_TRUE(sequence->stereo().has_value());
  EXPECT_NEAR(sequence->stereo()->baseline, 0.54, 1e-9);
  const auto truth = sequence->GroundTruth();
  ASSERT_TRUE(truth.has_value());
  ASSERT_EQ(truth->size(), 5u);
  for (size_t f = 0; f < 5; ++f) {
    EXPECT_LT(((*truth)[f].world_from_camera.translation - sim.WorldFromCamera(f).translation).norm(), 1e-6);
  }
  EXPECT_TRUE(sequence->LabelDirectory().has_value());
  EXPECT_TRUE(sequence->DepthDirectory().has_value());
}

TEST(Dataset, GpsRoundTripWithinNoise) {
  SynthOptions o = Tiny(300);
  o.gps.noise = 1.0;
  o.gps.every = 3;
  const SyntheticCity sim(o);
  testing::TempDir dir;
  WriteOxtsFolder(dir / "oxts", SimulateOxts(sim));
  const std::vector<StampedOxts> readings = ReadOxtsFolder(dir / "oxts");
  ASSERT_EQ(readings.size(), 100u);
  double sum2 = 0;
  for (const StampedOxts& r : readings) {
    const int frame = OxtsFrame(sim, r);
    ASSERT_EQ(frame % 3, 0);
    const Eigen::Vector3d truth =
        sim.EnuFromWorld() * sim.WorldFromCamera(static_cast<size_t>(frame)).translation;
    const Eigen::Vector3d measured = sim.enu().ToEnu({r.record.lat, r.record.lon, r.record.alt});
    const double error = (measured.head<2>() - truth.head<2>()).norm();
    EXPECT_LT(error, 5.0);
    sum2 += error * error;
    EXPECT_NEAR(r.record.vf, sim.route().speed[static_cast<size_t>(frame)], 1e-3);
    EXPECT_EQ(r.record.pos_accuracy, 1.0);
  }
  // Horizontal error of a 2D Gaussian with sigma 1: RMS sqrt(2).
  EXPECT_NEAR(std::sqrt(sum2 / readings.size()), std::sqrt(2.0), 0.35);

  // Dropouts never take the first fix; outliers are 50 m off.
  o.gps.every = 1;
  o.gps.dropout = 0.5;
  o.gps.outliers = 0.2;
  o.gps.noise = 0.0;
  const SyntheticCity noisy(o);
  const std::vector<StampedOxts> sparse = SimulateOxts(noisy);
  ASSERT_FALSE(sparse.empty());
  EXPECT_EQ(OxtsFrame(noisy, sparse.front()), 0);
  EXPECT_GT(sparse.size(), 100u);
  EXPECT_LT(sparse.size(), 200u);
  int outliers = 0;
  for (const StampedOxts& r : sparse) {
    const Eigen::Vector3d truth =
        noisy.route().town_from_camera[static_cast<size_t>(OxtsFrame(noisy, r))].translation;
    const double error = (noisy.enu().ToEnu({r.record.lat, r.record.lon, r.record.alt}) - truth).norm();
    if (error > 1.0) {
      EXPECT_NEAR(error, 50.0, 0.01);
      ++outliers;
    }
  }
  EXPECT_GT(outliers, 5);
}

TEST(Dataset, SceneJsonDescribesTheTown) {
  SynthOptions o = Tiny(1200);
  const SyntheticCity sim(o);
  const auto j = nlohmann::json::parse(SceneJson(sim));
  EXPECT_EQ(j["seed"], 1);
  EXPECT_EQ(j["frames"], 1200);
  EXPECT_EQ(j["start_epoch"], 1600000000.0);
  EXPECT_EQ(j["route"]["positions"].size(), 1200u);
  EXPECT_FALSE(j["route"]["revisits"].empty());
  EXPECT_FALSE(j["route"]["turns"].empty());
  EXPECT_EQ(j["landmarks"].size(), sim.Landmarks().size());
  EXPECT_EQ(j["surfaces"].size(), sim.city().primitives.size());
  // enu_from_world maps the last camera centre onto its ENU position.
  Eigen::Matrix3d r;
  for (int a = 0; a < 3; ++a) {
    for (int b = 0; b < 3; ++b) r(a, b) = j["enu_from_world"]["rotation"][a][b];
  }
  const Eigen::Vector3d t(j["enu_from_world"]["translation"][0], j["enu_from_world"]["translation"][1],
                          j["enu_from_world"]["translation"][2]);
  const Eigen::Vector3d last(j["route"]["positions"][1199][0], j["route"]["positions"][1199][1],
                             j["route"]["positions"][1199][2]);
  EXPECT_LT((r * last + t - sim.route().town_from_camera[1199].translation).norm(), 0.01);
  // Street graph: segment lengths are the distances between their intersections; driven segments exist.
  std::map<int, Eigen::Vector3d> nodes;
  for (const auto& n : j["street_graph"]["intersections"]) {
    nodes[n["id"]] = Eigen::Vector3d(n["position"][0], n["position"][1], n["position"][2]);
  }
  int driven = 0;
  for (const auto& s : j["street_graph"]["segments"]) {
    EXPECT_NEAR((nodes[s["from"]] - nodes[s["to"]]).norm(), s["length"].get<double>(), 0.01);
    driven += s["driven"].get<int>() > 0;
  }
  EXPECT_GE(driven, 8);
  // The landmarks file lists the same places.
  const std::string csv = LandmarksCsv(sim);
  EXPECT_EQ(csv.rfind("name,lat,lon,alt,category\n", 0), 0u);
  for (const auto& l : j["landmarks"])
    EXPECT_NE(csv.find(l["name"].get<std::string>() + ","), std::string::npos);
}

TEST(SynthCli, WritesADatasetAndRejectsBadArguments) {
  SEMSLAM_REQUIRE_BINARY();
  testing::TempDir dir;
  // Errors are reported on stderr.
  testing::CommandResult r =
      testing::RunSemslam({"synth", "--out", (dir / "neg").string(), "--frames", "-5"});
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("--frames"), std::string::npos) << r.err;
  r = testing::RunSemslam({"synth", "--out", (dir / "x").string(), "--preset", "nowhere"});
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("preset"), std::string::npos) << r.err;
  EXPECT_NE(testing::RunSemslam({"synth", "--out", (dir / "x").string(), "--gps-noise", "-1"}).exit_code, 0);
  // A file where the folder should be.
  std::ofstream(dir / "file") << "x";
  r = testing::RunSemslam({"synth", "--out", (dir / "file" / "sub").string(), "--frames", "2"});
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("output folder"), std::string::npos) << r.err;
  // A small run with the GPS options.
  r = testing::RunSemslam({"synth", "--out", (dir / "ok").string(), "--frames", "2", "--preset", "small",
                           "--gps-every", "2", "--seed", "3", "-q"});
  ASSERT_EQ(r.exit_code, 0) << r.Describe();
  EXPECT_TRUE(fs::exists(dir / "ok" / "sequences" / "00" / "image_1" / "000001.png"));
  EXPECT_EQ(ReadOxtsFolder(dir / "ok" / "oxts").size(), 1u);
  const auto j = nlohmann::json::parse(testing::ReadText(dir / "ok" / "scene.json"));
  EXPECT_EQ(j["seed"], 3);
  EXPECT_EQ(j["options"]["preset"], "small");
  EXPECT_FALSE(j["options"]["route"].contains("route_seed"));
  // Another drive through the same town: the same origin and places, another start.
  r = testing::RunSemslam({"synth", "--out", (dir / "drive2").string(), "--frames", "1", "--preset", "small",
                           "--seed", "3", "--route-seed", "2", "-q"});
  ASSERT_EQ(r.exit_code, 0) << r.Describe();
  const auto j2 = nlohmann::json::parse(testing::ReadText(dir / "drive2" / "scene.json"));
  EXPECT_EQ(j2["options"]["route"]["route_seed"], 2);
  EXPECT_EQ(j2["origin"], j["origin"]);
  EXPECT_NE(j2["enu_from_world"]["translation"], j["enu_from_world"]["translation"]);
  // A folder of other files is never written into, an earlier dataset only with --overwrite.
  fs::create_directories(dir / "kitti" / "sequences" / "00");
  std::ofstream(dir / "kitti" / "sequences" / "00" / "times.txt") << "0.0\n";
  r = testing::RunSemslam({"synth", "--out", (dir / "kitti").string(), "--frames", "1", "--overwrite", "-q"});
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("holds no synthetic dataset"), std::string::npos) << r.err;
  EXPECT_EQ(testing::ReadText(dir / "kitti" / "sequences" / "00" / "times.txt"), "0.0\n");
  r = testing::RunSemslam(
      {"synth", "--out", (dir / "ok").string(), "--frames", "1", "--preset", "small", "-q"});
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("pass --overwrite"), std::string::npos) << r.err;
  EXPECT_TRUE(fs::exists(dir / "ok" / "sequences" / "00" / "image_1" / "000001.png"));
  r = testing::RunSemslam({"synth", "--out", (dir / "x").string(), "--route-seed", "0"});
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("--route-seed"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace semslam::sim
