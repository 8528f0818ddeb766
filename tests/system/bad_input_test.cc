// Bad input to `semslam run`: each case exits non-zero without a crash and says why in exactly one line on
// stderr that names the file (and the line where there is one). Fixtures are small sequences copied from a
// 6-frame synthetic dataset and then broken.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>

#include "support/test_support.h"
#include "system_test_util.h"

namespace semslam::system_test {
namespace {

using ::testing::HasSubstr;

class BadInput : public ::testing::Test {
 protected:
  void SetUp() override {
    SEMSLAM_REQUIRE_BINARY();
    const Artifact tiny = TinyDataset();
    ASSERT_TRUE(tiny.ok()) << tiny.error;
    source_ = SequenceDir(tiny.dir);
    // A KITTI odometry sequence of its own: image_0, image_1, calib.txt, times.txt.
    fs::create_directories(sequence_);
    for (const char* folder : {"image_0", "image_1"}) fs::copy(source_ / folder, sequence_ / folder);
    for (const char* file : {"calib.txt", "times.txt"}) fs::copy_file(source_ / file, sequence_ / file);
  }

  CommandResult Run(const std::vector<std::string>& extra) const {
    std::vector<std::string> args = {
        "run",         "--sequence", sequence_.string(), "--out", (dir_ / "out").string(), "--pacing",
        "synchronous"};  // without -q: the warnings these tests look for are what -q silences
    args.insert(args.end(), extra.begin(), extra.end());
    return RunSemslam(args);
  }

  // Non-zero, no crash, and the reason names every one of `needles`.
  static void ExpectCleanFailure(const CommandResult& r, const std::vector<std::string>& needles) {
    EXPECT_FALSE(r.Crashed()) << r.Describe();
    EXPECT_NE(r.exit_code, 0) << r.Describe();
    for (const std::string& needle : needles) EXPECT_THAT(r.err, HasSubstr(needle)) << r.Describe();
  }
  // ... and in exactly one line.
  static void ExpectOneLineFailure(const CommandResult& r, const std::vector<std::string>& needles) {
    ExpectCleanFailure(r, needles);
    EXPECT_EQ(ErrorLines(r.err).size(), 1u) << r.Describe();
  }

  testing::TempDir dir_;
  fs::path source_;
  fs::path sequence_ = dir_ / "sequence";
};

TEST_F(BadInput, TheIntactFixtureRuns) {
  // The fixtures below differ from this one by one broken thing.
  const CommandResult r = Run({"--mode", "stereo"});
  ASSERT_TRUE(r.Succeeded()) << r.Describe();
  EXPECT_TRUE(fs::exists(dir_ / "out" / "run.json"));
}

TEST_F(BadInput, MissingCalibration) {
  fs::remove(sequence_ / "calib.txt");
  ExpectOneLineFailure(Run({}), {(sequence_ / "calib.txt").string()});
}

TEST_F(BadInput, MalformedP0Line) {
  // A letter in the middle of P0 (line 1).
  std::string calib = ReadText(source_ / "calib.txt");
  const size_t first_space = calib.find(' ', calib.find(' ', 4) + 1);
  calib.replace(first_space + 1, calib.find(' ', first_space + 1) - first_space - 1, "abc");
  std::ofstream(sequence_ / "calib.txt", std::ios::trunc) << calib;
  ExpectOneLineFailure(Run({}), {"calib.txt:1"});

  // Eleven numbers instead of twelve.
  std::string shortened = ReadText(source_ / "calib.txt");
  const size_t end_of_p0 = shortened.find('\n');
  const size_t last_space = shortened.rfind(' ', end_of_p0);
  shortened.erase(last_space, end_of_p0 - last_space);
  std::ofstream(sequence_ / "calib.txt", std::ios::trunc) << shortened;
  ExpectOneLineFailure(Run({}), {"calib.txt:1"});

  // A NaN focal length.
  std::string nan = ReadText(source_ / "calib.txt");
  nan.replace(nan.find(' ') + 1, nan.find(' ', nan.find(' ') + 1) - nan.find(' ') - 1, "nan");
  std::ofstream(sequence_ / "calib.txt", std::ios::trunc) << nan;
  ExpectOneLineFailure(Run({}), {"calib.txt:1"});
}

// A damaged frame in the middle of a sequence is skipped with one line naming it, and the run goes on (the
// first frame gives the sequence its image size, so a damaged first frame stops the run before it starts).
TEST_F(BadInput, CorruptPngIsSkippedWithOneLineNamingIt) {
  const fs::path image = sequence_ / "image_0" / "000003.png";
  const std::string bytes = ReadText(image);
  const auto expect_skipped = [&](const std::string& what) {
    SCOPED_TRACE(what);
    const CommandResult r = Run({"--overwrite"});
    ASSERT_TRUE(r.Succeeded()) << r.Describe();
    std::vector<std::string> naming;
    for (const std::string& line : Lines(r.out + r.err)) {
      if (line.find(image.string()) != std::string::npos) naming.push_back(line);
    }
    EXPECT_EQ(naming.size(), 1u) << r.Describe();
    EXPECT_EQ(ReadJson(dir_ / "out" / "run.json")["bad_frames"].value("count", 0), 1);
  };
  std::ofstream(image, std::ios::binary | std::ios::trunc) << bytes.substr(0, 500);
  expect_skipped("truncated");
  std::ofstream(image, std::ios::binary | std::ios::trunc) << "this is not a PNG\n";
  expect_skipped("not a PNG");
  std::ofstream(image, std::ios::binary | std::ios::trunc);
  expect_skipped("empty");
}

TEST_F(BadInput, CorruptFirstFrameStopsTheRunInOneLine) {
  const fs::path image = sequence_ / "image_0" / "000000.png";
  const std::string bytes = ReadText(image);
  std::ofstream(image, std::ios::binary | std::ios::trunc) << bytes.substr(0, 500);
  ExpectOneLineFailure(Run({}), {image.string()});
}

TEST_F(BadInput, EmptyFrameRange) {
  ExpectOneLineFailure(Run({"--frames", "5:2"}), {"5:2"});
  // Beyond the sequence's 6 frames.
  ExpectOneLineFailure(Run({"--frames", "10:20"}), {"10"});
  ExpectOneLineFailure(Run({"--frames", "x:3"}), {"x:3"});
}

TEST_F(BadInput, MissingMapNamesTheFile) {
  const fs::path missing = dir_ / "nowhere" / "map.semslam";
  const CommandResult r = Run({"--map-in", missing.string()});
  ExpectCleanFailure(r, {missing.string()});
  EXPECT_FALSE(fs::exists(dir_ / "out" / "run.json"));
}

// DISABLED: a missing --map-in (like every option CLI11 checks: --config, --gps, --landmarks, --vocabulary)
// prints two lines, "--map-in: File does not exist: ..." and "Run with --help for more information.", and
// exits with CLI11's code 105 (apps/semslam/main.cc returns app.exit(e)).
TEST_F(BadInput, MissingMapGivesOneLine) {
  const fs::path missing = dir_ / "nowhere" / "map.semslam";
  ExpectOneLineFailure(Run({"--map-in", missing.string()}), {missing.string()});
}

TEST_F(BadInput, TruncatedMap) {
  const Artifact tiny_run = TinyStereoRun();
  ASSERT_TRUE(tiny_run.ok()) << tiny_run.error;
  const std::string bytes = ReadText(tiny_run.dir / "map.semslam");
  ASSERT_GT(bytes.size(), 1000u);
  const fs::path map = dir_ / "map.semslam";
  // Inside the header, just after it, in the middle of the sections, one byte short.
  for (const size_t size :
       {size_t{0}, size_t{12}, size_t{40}, size_t{1000}, bytes.size() / 2, bytes.size() - 1}) {
    std::ofstream(map, std::ios::binary | std::ios::trunc) << bytes.substr(0, size);
    SCOPED_TRACE("map truncated to " + std::to_string(size) + " of " + std::to_string(bytes.size()) +
                 " bytes");
    ExpectOneLineFailure(Run({"--map-in", map.string()}), {map.string()});
  }
}

TEST_F(BadInput, StereoOnAMonocularFolder) {
  // No image_1/ (calib.txt still has P0..P3, as KITTI's do).
  fs::remove_all(sequence_ / "image_1");
  ExpectOneLineFailure(Run({"--mode", "stereo"}), {sequence_.string()});
  // No image_1/ and only P0.
  const std::string calib = ReadText(source_ / "calib.txt");
  std::ofstream(sequence_ / "calib.txt", std::ios::trunc) << calib.substr(0, calib.find('\n') + 1);
  ExpectOneLineFailure(Run({"--mode", "stereo"}), {sequence_.string()});
  // The same folder runs monocular.
  const CommandResult mono = Run({"--mode", "mono"});
  EXPECT_TRUE(mono.Succeeded()) << mono.Describe();
}

TEST_F(BadInput, MalformedTimes) {
  const std::string times = ReadText(source_ / "times.txt");
  std::vector<std::string> lines = Lines(times);
  ASSERT_GE(lines.size(), 6u);
  const auto write = [&](const std::vector<std::string>& rows) {
    std::ofstream out(sequence_ / "times.txt", std::ios::trunc);
    for (const std::string& row : rows) out << row << "\n";
  };
  std::vector<std::string> nan = lines;
  nan[2] = "nan";
  write(nan);
  ExpectOneLineFailure(Run({}), {"times.txt:3"});
  write({lines[0], lines[1], lines[2]});  // fewer stamps than images
  ExpectOneLineFailure(Run({}), {(sequence_ / "times.txt").string()});
}

TEST_F(BadInput, MalformedGpsLog) {
  const fs::path oxts = dir_ / "oxts";
  fs::copy(source_.parent_path().parent_path() / "oxts", oxts, fs::copy_options::recursive);
  const fs::path fix = oxts / "data" / "0000000002.txt";
  std::string text = ReadText(fix);
  text.replace(0, text.find(' '), "abc");  // the latitude
  std::ofstream(fix, std::ios::trunc) << text;
  ExpectOneLineFailure(Run({"--gps", oxts.string()}), {fix.string() + ":1"});
}

// DISABLED: a malformed --landmarks catalogue is accepted with exit status 0 when the GPS does not
// georeference the map (here: 6 frames, fewer than one GPS sample every 30 frames): the catalogue is only
// read after SLAM, in WriteGeoOutputs, and not at all without a georeference. With enough GPS it is read, but
// only after the whole run, which is then lost (no run.json, no map.semslam).
TEST_F(BadInput, MalformedLandmarkCatalogue) {
  const fs::path catalogue = dir_ / "landmarks.csv";
  std::vector<std::string> rows = Lines(ReadText(source_.parent_path().parent_path() / "landmarks.csv"));
  ASSERT_GE(rows.size(), 3u);
  rows[2] = rows[2].substr(0, rows[2].find(',')) + ",xyz" +
            rows[2].substr(rows[2].find(',', rows[2].find(',') + 1));
  {
    std::ofstream out(catalogue);
    for (const std::string& row : rows) out << row << "\n";
  }
  ExpectOneLineFailure(Run({"--gps", (source_.parent_path().parent_path() / "oxts").string(), "--landmarks",
                            catalogue.string()}),
                       {catalogue.string() + ":3"});
}

}  // namespace
}  // namespace semslam::system_test
