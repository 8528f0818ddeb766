// Runs that keep the user's work (issue 11): a signal, bad frames, a reused or unusable --out, text that is not
// UTF-8, timestamp gaps and implausible inputs, each through the `semslam` binary on small synthetic datasets.

#include <fcntl.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/file.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <opencv2/core.hpp>
#include <regex>
#include <sstream>
#include <thread>

#include "semslam/core/interrupt.h"
#include "semslam/geometry/trajectory.h"
#include "semslam/io/sequence.h"
#include "semslam/io/trajectory_io.h"
#include "semslam/system/localizer.h"
#include "support/test_support.h"
#include "system_test_util.h"

extern char** environ;

namespace semslam::system_test {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

// How many times `needle` occurs in `text`.
size_t Count(const std::string& text, const std::string& needle) {
  size_t n = 0;
  for (size_t at = text.find(needle); at != std::string::npos; at = text.find(needle, at + needle.size())) ++n;
  return n;
}

std::string fmt_double(double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.6f", value);
  return buffer;
}

size_t TrajectoryLines(const fs::path& tum) {
  size_t n = 0;
  for (const std::string& line : Lines(ReadText(tum))) n += !line.empty() && line[0] != '#';
  return n;
}

// A `semslam` process started in the background, with stdout and stderr going to files.
class BackgroundRun {
 public:
  BackgroundRun(const std::vector<std::string>& args, const fs::path& log_dir) : err_(log_dir / "stderr.txt") {
    std::vector<std::string> strings = {testing::SemslamBinary().string()};
    strings.insert(strings.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (std::string& s : strings) argv.push_back(s.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
    posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, (log_dir / "stdout.txt").c_str(),
                                     O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, err_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (posix_spawn(&pid_, argv[0], &actions, nullptr, argv.data(), environ) != 0) pid_ = -1;
    posix_spawn_file_actions_destroy(&actions);
  }
  ~BackgroundRun() {
    if (pid_ > 0 && !exited_) {
      ::kill(pid_, SIGKILL);
      Wait();
    }
  }
  bool started() const { return pid_ > 0; }
  // The highest frame count of the progress lines ("run: 37/200 ...") so far.
  size_t FramesReported() const {
    static const std::regex progress("run: ([0-9]+)/");
    size_t best = 0;
    const std::string text = ReadText(err_);
    for (auto it = std::sregex_iterator(text.begin(), text.end(), progress); it != std::sregex_iterator(); ++it) {
      best = std::max<size_t>(best, std::stoul((*it)[1]));
    }
    return best;
  }
  // Waits until the progress reports `frames` frames (false if the process ended or 300 s passed first).
  bool WaitForFrames(size_t frames) {
    for (int i = 0; i < 3000; ++i) {
      if (FramesReported() >= frames) return true;
      int status = 0;
      if (::waitpid(pid_, &status, WNOHANG) == pid_) {
        exited_ = true;
        status_ = status;
        return false;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    return false;
  }
  // Waits until stderr holds `text` (false after 300 s).
  bool WaitForText(const std::string& text) const {
    for (int i = 0; i < 30000; ++i) {
      if (ReadText(err_).find(text) != std::string::npos) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return false;
  }
  void Signal(int signal_number) const { ::kill(pid_, signal_number); }
  // The exit status (-1 when a signal ended it).
  int Wait() {
    if (!exited_) {
      while (::waitpid(pid_, &status_, 0) < 0 && errno == EINTR) {
      }
      exited_ = true;
    }
    return WIFEXITED(status_) ? WEXITSTATUS(status_) : -1;
  }
  std::string err() const { return ReadText(err_); }

 private:
  fs::path err_;
  pid_t pid_ = -1;
  bool exited_ = false;
  int status_ = 0;
};

class Robustness : public ::testing::Test {
 protected:
  void SetUp() override {
    SEMSLAM_REQUIRE_BINARY();
    const Artifact tiny = TinyDataset();
    ASSERT_TRUE(tiny.ok()) << tiny.error;
    dataset_ = tiny.dir;
    source_ = SequenceDir(tiny.dir);
    CopySequence(sequence_);
  }

  void CopySequence(const fs::path& to) const {
    fs::create_directories(to);
    for (const char* folder : {"image_0", "image_1"}) fs::copy(source_ / folder, to / folder);
    for (const char* file : {"calib.txt", "times.txt"}) fs::copy_file(source_ / file, to / file);
  }

  // Without -q: the warnings these tests look for are what -q silences.
  CommandResult Run(const std::vector<std::string>& extra, const fs::path& sequence = {}) const {
    std::vector<std::string> args = {"run", "--sequence", (sequence.empty() ? sequence_ : sequence).string()};
    if (std::find(extra.begin(), extra.end(), "--pacing") == extra.end()) {
      args.insert(args.end(), {"--pacing", "synchronous"});
    }
    if (std::find(extra.begin(), extra.end(), "--out") == extra.end()) {
      args.insert(args.end(), {"--out", out_.string()});
    }
    args.insert(args.end(), extra.begin(), extra.end());
    return RunSemslam(args);
  }

  static void ExpectOneLineFailure(const CommandResult& r, const std::vector<std::string>& needles) {
    EXPECT_FALSE(r.Crashed()) << r.Describe();
    EXPECT_NE(r.exit_code, 0) << r.Describe();
    for (const std::string& needle : needles) EXPECT_THAT(r.err, HasSubstr(needle)) << r.Describe();
    EXPECT_EQ(ErrorLines(r.err).size(), 1u) << r.Describe();
  }

  void WriteLines(const fs::path& file, const std::vector<std::string>& lines) const {
    std::ofstream out(file, std::ios::binary | std::ios::trunc);
    for (const std::string& line : lines) out << line << "\n";
  }

  testing::TempDir dir_;
  fs::path dataset_;
  fs::path source_;
  fs::path sequence_ = dir_ / "sequence";
  fs::path out_ = dir_ / "out";
};

// --- Ctrl-C and SIGTERM ---

TEST(Interruption, SigintSavesTheFramesDoneAndAMapThatLocalizeLoads) {
  SEMSLAM_REQUIRE_BINARY();
  SEMSLAM_ASSERT_ARTIFACT(data, SyntheticDataset());
  testing::TempDir dir;
  const fs::path out = dir / "out";
  // Realtime pacing (10 Hz): 200 frames take 20 s, long enough to be interrupted in the middle.
  BackgroundRun run({"run", "--sequence", SequenceDir(data).string(), "--out", out.string(), "--mode", "mono",
                     "--pacing", "realtime"},
                    dir.path());
  ASSERT_TRUE(run.started());
  ASSERT_TRUE(run.WaitForFrames(40)) << run.err();
  run.Signal(SIGINT);
  EXPECT_EQ(run.Wait(), 128 + SIGINT) << run.err();
  EXPECT_THAT(run.err(), HasSubstr("interrupted by SIGINT"));

  const nlohmann::json json = ReadJson(out / "run.json");
  EXPECT_EQ(json.value("status", ""), "interrupted");
  const size_t frames = json.value("frames", size_t{0});
  EXPECT_GE(frames, 40u);
  EXPECT_LT(frames, static_cast<size_t>(kSyntheticFrames));
  const size_t poses = TrajectoryLines(out / "trajectory.tum");
  EXPECT_GT(poses, 0u);
  EXPECT_LE(poses, frames);
  ASSERT_TRUE(fs::exists(out / "map.semslam"));

  const CommandResult localize =
      RunSemslam({"localize", "--map", (out / "map.semslam").string(), "--sequence", SequenceDir(data).string(),
                  "--out", (dir / "localize").string(), "--frames", "0:10", "-q"});
  EXPECT_TRUE(localize.Succeeded()) << localize.Describe();
}

// A localization stopped before its first frame reports the frames it read, not those it was asked for.
TEST(StoppedLocalization, ReportsTheFramesItRead) {
  SEMSLAM_REQUIRE_BINARY();
  SEMSLAM_ASSERT_ARTIFACT(data, SyntheticDataset());
  testing::TempDir dir;
  const fs::path out = dir / "out";
  const CommandResult run = RunSemslam({"run", "--sequence", SequenceDir(data).string(), "--out",
                                        out.string(), "--frames", "0:30", "--pacing", "synchronous", "-q"});
  ASSERT_TRUE(run.Succeeded()) << run.Describe();
  LocalizeOptions stopped;
  stopped.map = out / "map.semslam";
  stopped.sequence = SequenceDir(data);
  stopped.output = dir / "localize_stopped";
  stopped.end_frame = 10;
  stopped.show_progress = false;
  RequestInterrupt(SIGINT);
  EXPECT_THROW(LocalizeSequence(stopped), Interrupted);
  ClearInterrupt();
  const nlohmann::json stopped_json = ReadJson(dir / "localize_stopped" / "localize.json");
  EXPECT_EQ(stopped_json.value("status", ""), "interrupted");
  EXPECT_EQ(stopped_json.value("frames", size_t{99}), 0u);
}

TEST(Interruption, ASecondSignalQuitsAtOnceAndTheNextRunCleansUp) {
  SEMSLAM_REQUIRE_BINARY();
  SEMSLAM_ASSERT_ARTIFACT(data, SyntheticDataset());
  testing::TempDir dir;
  const fs::path out = dir / "out";
  BackgroundRun run({"run", "--sequence", SequenceDir(data).string(), "--out", out.string(), "--mode", "mono",
                     "--pacing", "realtime"},
                    dir.path());
  ASSERT_TRUE(run.started());
  ASSERT_TRUE(run.WaitForFrames(5)) << run.err();
  run.Signal(SIGTERM);
  // Signals of one kind do not queue: the second is sent once the first was seen (while outputs are written).
  ASSERT_TRUE(run.WaitForText("stopping after the current frame")) << run.err();
  run.Signal(SIGTERM);
  EXPECT_EQ(run.Wait(), 128 + SIGTERM) << run.err();
  EXPECT_THAT(run.err(), HasSubstr("quitting at once"));
  // A temporary file as a write cut short by the second signal leaves one; the next run removes it.
  std::ofstream(out / ".trajectory.tum.tmp999999999.0") << "partial";
  const CommandResult next = RunSemslam({"run", "--sequence", SequenceDir(data).string(), "--out", out.string(),
                                         "--frames", "0:8", "--pacing", "fast", "-q", "--overwrite"});
  ASSERT_TRUE(next.Succeeded()) << next.Describe();
  for (const auto& entry : fs::recursive_directory_iterator(out)) {
    EXPECT_THAT(entry.path().filename().string(), Not(HasSubstr(".tmp"))) << entry.path();
  }
}

// --- Bad frames ---

TEST_F(Robustness, AZeroByteFrameIsSkippedAndTheRunSavesItsWork) {
  const fs::path frame = sequence_ / "image_0" / "000003.png";
  std::ofstream(frame, std::ios::trunc);
  const CommandResult r = Run({});
  ASSERT_TRUE(r.Succeeded()) << r.Describe();
  EXPECT_EQ(Count(r.out + r.err, frame.string()), 1u) << "one warning naming the file\n" << r.Describe();
  const nlohmann::json json = ReadJson(out_ / "run.json");
  EXPECT_EQ(json.value("status", ""), "complete");
  EXPECT_EQ(json["bad_frames"].value("count", 0), 1);
  EXPECT_EQ(json["bad_frames"]["first"][0].value("frame", 0), 3);
  EXPECT_TRUE(fs::exists(out_ / "trajectory.tum"));
  EXPECT_TRUE(fs::exists(out_ / "map.semslam"));
  EXPECT_THAT(ReadText(out_ / "tracking.csv"), HasSubstr("\n3,bad_frame,"));
  // One line per frame of the sequence, the skipped one's and those after it included.
  const std::string kitti = ReadText(out_ / "trajectory.kitti");
  EXPECT_EQ(Count(kitti, "\n"), Count(ReadText(sequence_ / "times.txt"), "\n"));
}

TEST_F(Robustness, TruncatedAndOddSizedFramesAreSkipped) {
  const fs::path truncated = sequence_ / "image_0" / "000002.png";
  const std::string bytes = ReadText(truncated);
  std::ofstream(truncated, std::ios::binary | std::ios::trunc) << bytes.substr(0, 500);
  const fs::path odd = sequence_ / "image_0" / "000004.png";
  fs::remove(odd);
  WritePng(odd, cv::Mat(37, 51, CV_8UC1, cv::Scalar(128)));
  const CommandResult r = Run({"--mode", "stereo"});
  ASSERT_TRUE(r.Succeeded()) << r.Describe();
  EXPECT_EQ(Count(r.out + r.err, truncated.string()), 1u) << r.Describe();
  EXPECT_EQ(Count(r.out + r.err, odd.string()), 1u) << r.Describe();
  EXPECT_EQ(ReadJson(out_ / "run.json")["bad_frames"].value("count", 0), 2);
}

TEST_F(Robustness, TooManyBadFramesInARowStopTheRunWithItsWorkSaved) {
  for (const char* name : {"000002.png", "000003.png", "000004.png"}) {
    std::ofstream(sequence_ / "image_0" / name, std::ios::trunc);
  }
  const CommandResult r = Run({"--max-bad-frames", "2"});
  EXPECT_EQ(r.exit_code, 1) << r.Describe();
  EXPECT_THAT(r.err, HasSubstr("3 bad frames in a row"));
  const nlohmann::json json = ReadJson(out_ / "run.json");
  EXPECT_EQ(json.value("status", ""), "stopped_bad_frames");
  EXPECT_EQ(json.value("last_frame", 0), 4);
  EXPECT_TRUE(fs::exists(out_ / "trajectory.tum"));
  EXPECT_TRUE(fs::exists(out_ / "report.html"));
  // With a higher limit the same sequence runs to its end.
  EXPECT_TRUE(Run({"--max-bad-frames", "3", "--overwrite"}).Succeeded());
}

// --- The output folder ---

TEST_F(Robustness, AReusedOutNeedsOverwriteAndThenHoldsNothingOfTheEarlierRun) {
  ASSERT_TRUE(Run({}).Succeeded());
  std::ofstream(out_ / "landmarks.geojson") << "{}";  // as an earlier run with landmarks leaves
  const std::string earlier_run_json = ReadText(out_ / "run.json");
  const CommandResult refused = Run({});
  EXPECT_EQ(refused.exit_code, 2) << refused.Describe();
  EXPECT_THAT(refused.err, HasSubstr("--overwrite"));
  EXPECT_EQ(ReadText(out_ / "run.json"), earlier_run_json) << "a refused run changes nothing";
  const CommandResult replaced = Run({"--overwrite", "--frames", "0:5"});
  ASSERT_TRUE(replaced.Succeeded()) << replaced.Describe();
  EXPECT_FALSE(fs::exists(out_ / "landmarks.geojson"));
  EXPECT_EQ(ReadJson(out_ / "run.json").value("frames", 0), 5);
}

TEST_F(Robustness, ASecondRunIntoTheSameFolderIsRefused) {
  fs::create_directories(out_);
  // Another run holds the folder's lock.
  const int fd = ::open((out_ / ".semslam.lock").c_str(), O_RDWR | O_CREAT, 0644);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::flock(fd, LOCK_EX), 0);
  const CommandResult r = Run({});
  ::close(fd);
  ExpectOneLineFailure(r, {out_.string(), "another semslam command"});
  EXPECT_FALSE(fs::exists(out_ / "run.json"));
}

TEST_F(Robustness, AnUnusableOutIsFoundBeforeTheFirstFrame) {
  std::ofstream(dir_ / "file") << "x";
  ExpectOneLineFailure(Run({"--out", (dir_ / "file" / "out").string()}), {"Not a directory"});
  // A full disk: a 100 KiB tmpfs in a mount namespace of its own (needs root or user namespaces).
  if (std::system("unshare -m true 2>/dev/null") != 0) GTEST_SKIP() << "no mount namespaces here";
  const fs::path small = dir_ / "small";
  fs::create_directories(small);
  const std::string script = "mount -t tmpfs -o size=100k tmpfs '" + small.string() + "' || exit 77; exec '" +
                             testing::SemslamBinary().string() + "' run --sequence '" + sequence_.string() +
                             "' --out '" + (small / "out").string() + "' -q";
  const int status = std::system(("unshare -m sh -c \"" + script + "\" 2>" + (dir_ / "err.txt").string()).c_str());
  if (WIFEXITED(status) && WEXITSTATUS(status) == 77) GTEST_SKIP() << "cannot mount a tmpfs here";
  EXPECT_EQ(WEXITSTATUS(status), 1);
  EXPECT_THAT(ReadText(dir_ / "err.txt"), HasSubstr("No space left on device"));
}

// --- Text that is not UTF-8 ---

TEST_F(Robustness, ALatin1LandmarkNameIsRefusedUpFront) {
  std::vector<std::string> rows = Lines(ReadText(dataset_ / "landmarks.csv"));
  ASSERT_GE(rows.size(), 3u);
  rows[2] = "Caf\xE9 M\xFCller" + rows[2].substr(rows[2].find(','));
  const fs::path catalogue = dir_ / "landmarks.csv";
  WriteLines(catalogue, rows);
  ExpectOneLineFailure(Run({"--gps", (dataset_ / "oxts").string(), "--landmarks", catalogue.string()}),
                       {catalogue.string() + ":3", "UTF-8"});
  EXPECT_FALSE(fs::exists(out_)) << "refused before the output folder is made";
}

TEST_F(Robustness, ALatin1SequencePathIsRefusedUpFront) {
  const fs::path latin1 = dir_ / "s\xE9q";
  CopySequence(latin1);
  const CommandResult r = Run({}, latin1);
  ExpectOneLineFailure(r, {"--sequence", "not UTF-8"});
  EXPECT_EQ(r.exit_code, 2);
}

// --- Timestamps that would stall realtime pacing (a stall shows as the test's timeout) ---

TEST_F(Robustness, ATimestampGapDoesNotStallRealtimePacing) {
  std::vector<std::string> times = Lines(ReadText(sequence_ / "times.txt"));
  for (size_t i = 3; i < times.size(); ++i) times[i] = fmt_double(std::stod(times[i]) + 100000.0);
  WriteLines(sequence_ / "times.txt", times);
  const CommandResult r = Run({"--pacing", "realtime"});
  ASSERT_TRUE(r.Succeeded()) << r.Describe();
  EXPECT_EQ(Count(r.out + r.err, "re-anchored"), 1u) << r.Describe();
}

TEST_F(Robustness, NanosecondTimestampsDoNotStallRealtimePacing) {
  std::vector<std::string> times = Lines(ReadText(sequence_ / "times.txt"));
  for (std::string& t : times) t = fmt_double(1.3e18 + std::stod(t) * 1e9);
  WriteLines(sequence_ / "times.txt", times);
  const CommandResult r = Run({"--pacing", "realtime"});
  ASSERT_TRUE(r.Succeeded()) << r.Describe();
  EXPECT_EQ(Count(r.out + r.err, "re-anchored"), 1u) << "warned once\n" << r.Describe();
}

// --- Implausible inputs get a clear error or warning ---

TEST_F(Robustness, AbsurdIntrinsicsAreRefused) {
  fs::remove_all(sequence_ / "image_1");
  const std::vector<std::string> calib = Lines(ReadText(source_ / "calib.txt"));
  auto with_p0 = [&](const std::string& fx, const std::string& cx) {
    std::vector<std::string> rows = calib;
    std::vector<std::string> tokens;
    std::istringstream in(rows[0]);
    for (std::string t; in >> t;) tokens.push_back(t);
    tokens[1] = fx;  // P0: f 0 cx 0 / 0 f cy 0 / 0 0 1 0
    tokens[6] = fx;
    tokens[3] = cx;
    rows[0].clear();
    for (const std::string& t : tokens) rows[0] += (rows[0].empty() ? "" : " ") + t;
    WriteLines(sequence_ / "calib.txt", {rows[0]});  // P0 only: a monocular sequence
  };
  std::istringstream p0(calib[0]);
  std::string name, f, zero, cx;
  p0 >> name >> f >> zero >> cx;
  with_p0("1e-300", cx);
  ExpectOneLineFailure(Run({}), {(sequence_ / "calib.txt").string(), "focal length"});
  with_p0(f, "9e4");
  ExpectOneLineFailure(Run({}), {(sequence_ / "calib.txt").string(), "principal point"});
}

TEST_F(Robustness, TooFewFeaturesToEverStartAMapAreRefused) {
  const fs::path config = dir_ / "config.yaml";
  WriteLines(config, {"features:", "  num_features: 10"});
  ExpectOneLineFailure(Run({"--config", config.string()}), {config.string() + ":2", "num_features"});
}

TEST_F(Robustness, RepeatedConfigKeysAreRefused) {
  const fs::path config = dir_ / "config.yaml";
  WriteLines(config, {"loop:", "  enabled: false", "  enabled: true"});
  ExpectOneLineFailure(Run({"--config", config.string()}), {config.string() + ":3", "repeated"});
}

TEST_F(Robustness, AGpsLogWithoutAUsableFixIsRefused) {
  const fs::path gps = dir_ / "gps.csv";
  WriteLines(gps, {"t,lat,lon", "0.0,nan,11.5", "0.1,95.0,11.5"});
  ExpectOneLineFailure(Run({"--gps", gps.string()}), {gps.string(), "no usable GPS fix"});
}

TEST_F(Robustness, SkippedGpsFixesAreReportedOnce) {
  const fs::path gps = dir_ / "gps.csv";
  WriteLines(gps, {"t,lat,lon", "0.0,49.00030,8.40150", "0.1,95.0,8.40151", "0.2,49.00032,8.40152",
                   "0.3,49.00033,8.40153", "0.4,49.00034,8.40154", "0.5,49.00035,8.40155"});
  const CommandResult r = Run({"--gps", gps.string()});
  ASSERT_TRUE(r.Succeeded()) << r.Describe();
  EXPECT_EQ(Count(r.out + r.err, gps.string() + ":3"), 1u) << r.Describe();
}

TEST_F(Robustness, LandmarksFarFromTheDriveAreReported) {
  const fs::path catalogue = dir_ / "far.csv";
  WriteLines(catalogue, {"name,lat,lon", "Null Island,0.0,0.0", "South Pole,-89.9,0.0"});
  const CommandResult r = Run({"--gps", (dataset_ / "oxts").string(), "--landmarks", catalogue.string()});
  ASSERT_TRUE(r.Succeeded()) << r.Describe();
  EXPECT_THAT(r.out + r.err, HasSubstr("none of the 2 landmarks lies within 50 km of the GPS track"));
}

TEST_F(Robustness, AnOutOfRangeGeoJsonNumberNamesTheFile) {
  const fs::path catalogue = dir_ / "landmarks.geojson";
  WriteLines(catalogue, {R"({"type": "FeatureCollection", "features": [)",
                         R"({"type": "Feature", "properties": {"name": "A"},)",
                         R"( "geometry": {"type": "Point", "coordinates": [11.5, 1e309]}}]})"});
  ExpectOneLineFailure(Run({"--gps", (dataset_ / "oxts").string(), "--landmarks", catalogue.string()}),
                       {catalogue.string()});
}

// --- Figures of a --frames range ---

TEST(FrameRange, PathLengthIsThatOfTheFramesRun) {
  SEMSLAM_REQUIRE_BINARY();
  SEMSLAM_ASSERT_ARTIFACT(data, SyntheticDataset());
  testing::TempDir dir;
  const CommandResult r = RunSemslam({"run", "--sequence", SequenceDir(data).string(), "--out",
                                      (dir / "out").string(), "--mode", "stereo", "--frames", "0:60", "--pacing",
                                      "synchronous", "-q"});
  ASSERT_TRUE(r.Succeeded()) << r.Describe();
  const auto sequence = OpenSequence(SequenceDir(data));
  const auto truth = sequence->GroundTruth();
  ASSERT_TRUE(truth.has_value());
  ASSERT_GE(truth->size(), 60u);
  const Trajectory first60(truth->begin(), truth->begin() + 60);
  const nlohmann::json json = ReadJson(dir / "out" / "run.json");
  ASSERT_TRUE(json.contains("path_length_m")) << json.dump(2);
  EXPECT_NEAR(json.value("path_length_m", 0.0), PathLength(first60), 1e-6);
  EXPECT_LT(json.value("path_length_m", 0.0), 0.5 * PathLength(*truth));
}

}  // namespace
}  // namespace semslam::system_test
