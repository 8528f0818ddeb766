// The files a run leaves for other tools (issue 12): trajectory.kitti read as evo and the KITTI devkit read it
// (line i = frame i), run.json's record of how the run was made, docs/formats.md naming every file of the run
// folder, the CLI's logs and suggestions. On a 150-frame synthetic city run with GPS, landmarks and a segmenter.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include "semslam/io/trajectory_io.h"
#include "system_test_util.h"

namespace semslam::system_test {
namespace {

constexpr int kFrames = 150;

// `semslam synth --frames 150 --seed 1`.
Artifact City150() { return SyntheticTown("city150", kFrames, 1); }

// Then `semslam run ... --gps --landmarks --segmenter truth-noisy:0.25`.
Artifact Run150() {
  const Artifact data = City150();
  if (!data.ok()) return data;
  const fs::path dataset = data.dir;
  const std::vector<std::string> run = {"run", "--sequence", SequenceDir(dataset).string(), "--mode", "mono",
                                        "--pacing", "synchronous", "--gps", (dataset / "oxts").string(),
                                        "--landmarks", (dataset / "landmarks.csv").string(), "--segmenter",
                                        "truth-noisy:0.25"};
  Artifact out = SharedArtifact("run150", run, [&](const fs::path& dir) -> std::string {
    std::vector<std::string> full = run;
    full.insert(full.end(), {"--out", (dir / "out").string()});
    const CommandResult r = RunSemslam(full);
    std::ofstream(dir / "stdout.txt") << r.out;
    std::ofstream(dir / "stderr.txt") << r.err;
    return r.Succeeded() ? "" : r.Describe();
  });
  if (out.ok()) out.dir /= "out";
  return out;
}

fs::path Dataset150() { return City150().dir; }

// evo's readers, re-implemented from their documented conventions (evo itself is not needed): numbers
// separated by whitespace, '#' lines skipped; TUM "timestamp tx ty tz qx qy qz qw", KITTI 12 numbers per line.
std::vector<std::vector<double>> EvoRows(const fs::path& file, size_t columns) {
  std::vector<std::vector<double>> rows;
  std::istringstream text(ReadText(file));
  std::string line;
  while (std::getline(text, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream values(line);
    std::vector<double> row;
    double v = 0;
    while (values >> v) row.push_back(v);
    EXPECT_EQ(row.size(), columns) << file << ": " << line;
    rows.push_back(row);
  }
  return rows;
}

TEST(Outputs, TrajectoryKittiHasOneLinePerFrameAsEvoReadsIt) {
  SEMSLAM_ASSERT_ARTIFACT(run, Run150());
  const std::vector<std::vector<double>> kitti = EvoRows(run / "trajectory.kitti", 12);
  ASSERT_EQ(kitti.size(), static_cast<size_t>(kFrames));  // the bar: exactly 150 lines
  const std::vector<std::vector<double>> tum = EvoRows(run / "trajectory.tum", 8);
  const std::vector<double> times = ReadTimes(SequenceDir(Dataset150()) / "times.txt");
  // Every tracked frame's TUM pose is on the KITTI line of its frame (evo pairs line i with frame i).
  std::vector<double> stamps;
  for (const auto& row : tum) stamps.push_back(row[0]);
  const std::vector<int> frames = FrameIndices(stamps, times);
  ASSERT_GE(tum.size(), static_cast<size_t>(kFrames) * 9 / 10);
  for (size_t k = 0; k < tum.size(); ++k) {
    ASSERT_GE(frames[k], 0) << "pose at " << tum[k][0] << " s is not a frame's";
    const auto& line = kitti[static_cast<size_t>(frames[k])];
    const Eigen::Vector3d kitti_t(line[3], line[7], line[11]);
    const Eigen::Vector3d tum_t(tum[k][1], tum[k][2], tum[k][3]);
    EXPECT_LT((kitti_t - tum_t).norm(), 1e-6) << "frame " << frames[k];
    const Eigen::Quaterniond q(tum[k][7], tum[k][4], tum[k][5], tum[k][6]);
    Eigen::Matrix3d r;
    r << line[0], line[1], line[2], line[4], line[5], line[6], line[8], line[9], line[10];
    EXPECT_LT((q.normalized().toRotationMatrix() - r).cwiseAbs().maxCoeff(), 1e-6) << "frame " << frames[k];
  }
  // run.json says where each line came from.
  const nlohmann::json j = ReadJson(run / "run.json");
  const nlohmann::json& filled = j.at("trajectory_kitti");
  EXPECT_EQ(filled.at("frames").get<size_t>(), static_cast<size_t>(kFrames));
  EXPECT_EQ(filled.at("own_pose").get<size_t>(), tum.size());
  EXPECT_EQ(filled.at("own_pose").get<size_t>() + filled.at("first_pose").get<size_t>() +
                filled.at("interpolated").get<size_t>() + filled.at("motion_model").get<size_t>() +
                filled.at("held").get<size_t>(),
            static_cast<size_t>(kFrames));
}

TEST(Outputs, EvalAcceptsTheKittiFileAndRefusesOneWithAFrameMissing) {
  SEMSLAM_ASSERT_ARTIFACT(run, Run150());
  const fs::path truth = Dataset150() / "poses" / "00.txt";
  const CommandResult ok = RunSemslam({"eval", "--estimate", (run / "trajectory.kitti").string(), "--truth",
                                       truth.string()});
  ASSERT_TRUE(ok.Succeeded()) << ok.Describe();
  const nlohmann::json e = nlohmann::json::parse(ok.out, nullptr, false);
  ASSERT_TRUE(e.is_object()) << ok.out;
  EXPECT_EQ(e.at("matched").get<int>(), kFrames);
  // The same ATE as run.json's (from the tracked frames), within what the filled lines add.
  const nlohmann::json j = ReadJson(run / "run.json");
  EXPECT_LT(e.at("ate_rmse").get<double>(), 2.0 * j.at("ate_rmse").get<double>() + 0.05);

  std::vector<std::string> lines = Lines(ReadText(run / "trajectory.kitti"));
  lines.erase(lines.begin() + 1);
  testing::TempDir dir;
  std::ofstream(dir / "gap.kitti") << [&] {
    std::string text;
    for (const std::string& l : lines) text += l + "\n";
    return text;
  }();
  const CommandResult refused = RunSemslam({"eval", "--estimate", (dir / "gap.kitti").string(), "--truth",
                                            truth.string()});
  EXPECT_EQ(refused.exit_code, 1) << refused.Describe();
  EXPECT_NE(refused.err.find("holds 149 poses"), std::string::npos) << refused.err;
  EXPECT_NE(refused.err.find("one line per frame"), std::string::npos) << refused.err;
}

TEST(Outputs, RunJsonRecordsHowTheRunWasMade) {
  SEMSLAM_ASSERT_ARTIFACT(run, Run150());
  const nlohmann::json j = ReadJson(run / "run.json");
  const nlohmann::json& p = j.at("provenance");
  const std::vector<std::string> command = p.at("command").get<std::vector<std::string>>();
  ASSERT_GE(command.size(), 2u);
  EXPECT_EQ(command[1], "run");
  EXPECT_NE(std::find(command.begin(), command.end(), "truth-noisy:0.25"), command.end());
  EXPECT_NE(p.at("command_line").get<std::string>().find("--segmenter truth-noisy:0.25"), std::string::npos);
  EXPECT_FALSE(p.at("version").get<std::string>().empty());
  EXPECT_FALSE(p.at("commit").get<std::string>().empty());
  EXPECT_EQ(p.at("date").get<std::string>().size(), 20u);  // 2026-01-01T00:00:00Z
  EXPECT_GE(p.at("host_cores").get<int>(), 1);
  const nlohmann::json& c = j.at("config");
  EXPECT_EQ(c.at("pacing").get<std::string>(), "synchronous");
  EXPECT_EQ(c.at("mode").get<std::string>(), "mono");
  EXPECT_EQ(c.at("gps_every").get<int>(), 30);
  EXPECT_EQ(c.at("frames").at(1).get<int>(), kFrames);
  EXPECT_TRUE(fs::path(c.at("sequence").get<std::string>()).is_absolute());
  EXPECT_TRUE(c.at("slam").at("features").at("num_features").is_number_integer());
  EXPECT_EQ(c.at("slam").at("tracking").at("pacing").get<std::string>(), "synchronous");
  // config.yaml holds the same options in the format --config reads.
  EXPECT_NE(ReadText(run / "config.yaml").find("num_features:"), std::string::npos);
  // run.log holds the log (the version first); stderr had it too, not stdout.
  const std::string log = ReadText(run / "run.log");
  EXPECT_NE(log.find("semslam " + p.at("version").get<std::string>()), std::string::npos) << log;
  EXPECT_NE(log.find("report:"), std::string::npos) << log;
  EXPECT_EQ(ReadText(run.parent_path() / "stdout.txt"), "");
}

// docs/formats.md names every file a run writes.
TEST(Outputs, FormatsDocNamesEveryFileOfTheRunFolder) {
  SEMSLAM_ASSERT_ARTIFACT(run, Run150());
  const std::string formats = ReadText(fs::path(SEMSLAM_SOURCE_DIR) / "docs" / "formats.md");
  ASSERT_FALSE(formats.empty());
  size_t files = 0;
  for (const auto& entry : fs::recursive_directory_iterator(run)) {
    if (!entry.is_regular_file()) continue;
    const std::string relative = fs::relative(entry.path(), run).generic_string();
    ++files;
    EXPECT_NE(formats.find("`" + relative + "`"), std::string::npos)
        << relative << " is not named (in backquotes) in docs/formats.md";
  }
  // Not an empty folder: 26 files with a georeference; a run whose 5 GPS samples do not fix one (the clang build's
  // monocular run) writes 18.
  EXPECT_GE(files, 15u);
}

TEST(Outputs, ReportCommandRebuildsTheReport) {
  SEMSLAM_ASSERT_ARTIFACT(run, Run150());
  testing::TempDir dir;
  for (const auto& entry : fs::directory_iterator(run)) {
    if (entry.path().filename() != "report.html") fs::copy(entry.path(), dir / entry.path().filename().string(),
                                                           fs::copy_options::recursive);
  }
  const CommandResult r = RunSemslam({"report", dir.path().string(), "-q"});
  ASSERT_TRUE(r.Succeeded()) << r.Describe();
  EXPECT_EQ(r.err, "");  // -q: nothing but errors
  const std::string html = ReadText(dir / "report.html");
  EXPECT_NE(html.find("<title>semslam: dataset/00, "), std::string::npos) << html.substr(0, 400);
  EXPECT_NE(html.find("id=\"provenance\""), std::string::npos);
  EXPECT_NE(html.find("plots/trajectory.png"), std::string::npos);
  EXPECT_NE(html.find("plots/ate.png"), std::string::npos);
}

TEST(Outputs, MistypedCommandsAndOptionsGetSuggestions) {
  const CommandResult command = RunSemslam({"rnu"});
  EXPECT_EQ(command.exit_code, 2);
  EXPECT_NE(command.err.find("did you mean run?"), std::string::npos) << command.err;
  const CommandResult option = RunSemslam({"run", "--sequense", "x", "--out", "y"});
  EXPECT_EQ(option.exit_code, 2);
  EXPECT_NE(option.err.find("did you mean --sequence?"), std::string::npos) << option.err;
  const CommandResult renamed = RunSemslam({"localize", "--landmarks", "3"});
  EXPECT_NE(renamed.err.find("did you mean --nearest-landmarks?"), std::string::npos) << renamed.err;
  const CommandResult version = RunSemslam({"--version"});
  EXPECT_NE(version.out.find("commit "), std::string::npos) << version.out;
}

}  // namespace
}  // namespace semslam::system_test
