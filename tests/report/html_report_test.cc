#include "semslam/report/html_report.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <set>
#include <sstream>
#include <tuple>

#include "report_run_folder.h"
#include "semslam/core/atomic_file.h"
#include "semslam/core/error.h"
#include "semslam/geo/georeference.h"
#include "semslam/io/trajectory_io.h"
#include "semslam/report/html_encoding.h"
#include "semslam/report/plots.h"
#include "semslam/semantics/class_table.h"
#include "semslam/semantics/semantic_outputs.h"
#include "support/test_support.h"

namespace semslam {
namespace {

using namespace report_test;

namespace fs = std::filesystem;
using json = nlohmann::json;
using testing::TempDir;

constexpr std::string_view kDataOpen = "<script type=\"application/json\" id=\"semslam-data\">";

std::string ReadText(const fs::path& file) {
  std::ifstream stream(file, std::ios::binary);
  std::ostringstream buffer;
  buffer << stream.rdbuf();
  return buffer.str();
}

std::string Base64Decode(std::string_view text) {
  static constexpr std::string_view kAlphabet =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  std::uint32_t buffer = 0;
  int bits = 0;
  for (const char c : text) {
    if (c == '=') break;
    const size_t v = kAlphabet.find(c);
    if (v == std::string_view::npos) ADD_FAILURE() << "not base64: " << c;
    buffer = (buffer << 6) | static_cast<std::uint32_t>(v);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out.push_back(static_cast<char>((buffer >> bits) & 0xffu));
    }
  }
  return out;
}

std::vector<float> DecodeFloats(const std::string& base64) {
  const std::string bytes = Base64Decode(base64);
  EXPECT_EQ(bytes.size() % 4, 0u);
  std::vector<float> values(bytes.size() / 4);
  for (size_t i = 0; i < values.size(); ++i) {
    std::uint32_t bits = 0;
    for (int k = 0; k < 4; ++k)
      bits |= std::uint32_t{static_cast<unsigned char>(bytes[4 * i + k])} << (8 * k);
    values[i] = std::bit_cast<float>(bits);
  }
  return values;
}

// The JSON of the 3D view, or null when the page has none.
json EmbeddedData(const std::string& html) {
  const size_t open = html.find(kDataOpen);
  if (open == std::string::npos) return nullptr;
  const size_t begin = open + kDataOpen.size();
  const size_t end = html.find("</script>", begin);
  EXPECT_NE(end, std::string::npos);
  return json::parse(html.substr(begin, end - begin));
}

std::string Between(const std::string& html, std::string_view from, std::string_view to) {
  const size_t begin = html.find(from);
  if (begin == std::string::npos) return "";
  const size_t end = html.find(to, begin);
  return html.substr(begin, end == std::string::npos ? std::string::npos : end - begin);
}

TEST(HtmlEncoding, Base64MatchesRfc4648) {
  EXPECT_EQ(Base64Encode(std::string_view("")), "");
  EXPECT_EQ(Base64Encode(std::string_view("f")), "Zg==");
  EXPECT_EQ(Base64Encode(std::string_view("fo")), "Zm8=");
  EXPECT_EQ(Base64Encode(std::string_view("foo")), "Zm9v");
  EXPECT_EQ(Base64Encode(std::string_view("foob")), "Zm9vYg==");
  EXPECT_EQ(Base64Encode(std::string_view("fooba")), "Zm9vYmE=");
  EXPECT_EQ(Base64Encode(std::string_view("foobar")), "Zm9vYmFy");
  const std::string binary("\x00\xff\x10\x80\x7f", 5);
  EXPECT_EQ(Base64Decode(Base64Encode(binary)), binary);
}

TEST(HtmlEncoding, EscapesHtmlAndScriptJson) {
  EXPECT_EQ(HtmlEscape("a<b>&\"c'"), "a&lt;b&gt;&amp;&quot;c&#39;");
  const json value = {{"name", "</script><!-- x"}};
  const std::string safe = JsonForScriptElement(value.dump());
  EXPECT_EQ(safe.find('<'), std::string::npos);
  EXPECT_EQ(json::parse(safe), value);
}

TEST(HtmlReport, FullRunHasEverySection) {
  const TempDir dir;
  WriteFullRun(dir.path());
  const HtmlReportResult result = WriteHtmlReport(dir.path());
  EXPECT_EQ(result.path, dir.path() / "report.html");
  ASSERT_TRUE(fs::exists(result.path));
  EXPECT_EQ(result.bytes, fs::file_size(result.path));
  EXPECT_EQ(result.sections, (std::vector<std::string>{"summary", "time-analysis", "modules", "map3d",
                                                       "plots", "landmarks", "objects"}));
  EXPECT_TRUE(result.notes.empty());
  EXPECT_EQ(result.map_points, 5000u);
  EXPECT_EQ(result.points_shown, 5000u);

  const std::string html = ReadText(result.path);
  EXPECT_EQ(html.rfind("<!DOCTYPE html>", 0), 0u);
  EXPECT_NE(html.find("</html>"), std::string::npos);
  for (const std::string& id : result.sections) {
    EXPECT_NE(html.find("<section id=\"" + id + "\">"), std::string::npos) << id;
    EXPECT_NE(html.find("href=\"#" + id + "\""), std::string::npos) << id;
  }
  // Named after the dataset folder, the sequence and the run folder ("KITTI 00" alone named two runs alike).
  EXPECT_NE(html.find("<title>semslam: city/00, "), std::string::npos);
  // Summary figures.
  const std::string summary = Between(html, "<section id=\"summary\">", "</section>");
  EXPECT_NE(summary.find("/data/city/sequences/00"), std::string::npos);
  EXPECT_NE(summary.find("98 (98.0&nbsp;%)"), std::string::npos);
  EXPECT_NE(summary.find("0.25&nbsp;m RMSE (Sim(3) alignment"), std::string::npos);
  EXPECT_NE(summary.find("refined: f 707.1 &rarr; 699.9&nbsp;px, k1 0.0148"), std::string::npos) << summary;
  // The map labels: the headline (the map placed by one alignment) first, then the kinder measures, each
  // named.
  EXPECT_NE(
      summary.find("92.0&nbsp;% of the map points carry the class of the surface they lie on (3D, the map "
                   "placed by one alignment, 4&#8239;100 evaluated); by each keyframe's own pose: "
                   "94.0&nbsp;%; the class at their keypoints (2D): 96.0&nbsp;%"),
      std::string::npos)
      << summary;
  EXPECT_NE(summary.find("Landmark position error"), std::string::npos);
  // The landmark's error from run.json is matched to its row by name.
  const std::string landmarks = Between(html, "<section id=\"landmarks\">", "</section>");
  EXPECT_NE(landmarks.find("0.80&nbsp;m (0.50&nbsp;m horiz.)"), std::string::npos);
  EXPECT_NE(landmarks.find("29.4&nbsp;m"), std::string::npos);
  // Two plots, embedded as PNG.
  size_t images = 0;
  for (size_t at = html.find("data:image/png;base64,"); at != std::string::npos;
       at = html.find("data:image/png;base64,", at + 1)) {
    ++images;
    const size_t begin = at + std::string_view("data:image/png;base64,").size();
    EXPECT_EQ(Base64Decode(html.substr(begin, 12)).substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  }
  EXPECT_EQ(images, 2u);
  // Self-contained: nothing is fetched from anywhere.
  EXPECT_EQ(html.find("src=\"http"), std::string::npos);
  EXPECT_EQ(html.find("<link"), std::string::npos);
  EXPECT_EQ(html.find("@import"), std::string::npos);
  // Written atomically: no temporary file left beside it.
  for (const auto& entry : fs::directory_iterator(dir.path())) {
    const std::string name = entry.path().filename().string();
    EXPECT_TRUE(name == "report.html" || name == "plots" || fs::path(name).has_extension()) << name;
    EXPECT_EQ(name.find("tmp"), std::string::npos) << name;
  }
}

TEST(HtmlReport, TimeAnalysisHasThePapersTableI) {
  const TempDir dir;
  WriteFullRun(dir.path());
  WriteHtmlReport(dir.path());
  const std::string html = ReadText(dir.path() / "report.html");
  const std::string table = Between(html, "<table class=\"data\" id=\"table-i\">", "</table>");
  ASSERT_FALSE(table.empty());
  // The paper's figures.
  EXPECT_NE(table.find("1.8 Hz (PSPNet-101)"), std::string::npos);
  EXPECT_NE(table.find("15.1 Hz (ORB-SLAM2)"), std::string::npos);
  EXPECT_NE(table.find("0.5 ms"), std::string::npos);
  // This run's: tracking median 25 ms -> 40 Hz; segmentation 40 ms from run.json -> 25 Hz; label fusion 0.04
  // ms; the whole system 100 frames in 5 s -> 20 Hz.
  const std::string tracking = Between(table, "<td>Tracking", "</tr>");
  EXPECT_NE(tracking.find(">25.0<"), std::string::npos) << tracking;
  EXPECT_NE(tracking.find(">50.0<"), std::string::npos) << tracking;  // p95
  EXPECT_NE(tracking.find(">40.0<"), std::string::npos) << tracking;
  const std::string segmentation = Between(table, "<td>Semantic segmentation", "</tr>");
  EXPECT_NE(segmentation.find(">40.0<"), std::string::npos) << segmentation;
  EXPECT_NE(segmentation.find(">25.0<"), std::string::npos) << segmentation;
  const std::string fusion = Between(table, "<td>Data association", "</tr>");
  EXPECT_NE(fusion.find(">0.040<"), std::string::npos) << fusion;
  const std::string whole = Between(table, "<td>Whole system", "</tr>");
  EXPECT_NE(whole.find(">20.0<"), std::string::npos) << whole;
  EXPECT_NE(Between(table, "<td>Local mapping", "</tr>").find(">200<"), std::string::npos);
  EXPECT_NE(Between(table, "<td>Loop closing", "</tr>").find(">0.500<"), std::string::npos);
  // Every module of timing.json in the full table.
  const std::string modules = Between(html, "<section id=\"modules\">", "</section>");
  const json timing = TimingJson();
  for (const auto& [name, entry] : timing.items()) {
    EXPECT_NE(modules.find("<code>" + name + "</code>"), std::string::npos) << name;
  }
}

TEST(HtmlReport, EmbeddedDataParsesAndHoldsEveryPoint) {
  const TempDir dir;
  WriteFullRun(dir.path(), 3000, 50);
  WriteHtmlReport(dir.path());
  const json data = EmbeddedData(ReadText(dir.path() / "report.html"));
  ASSERT_TRUE(data.is_object());
  const json& points = data.at("points");
  EXPECT_EQ(points.at("total").get<size_t>(), 3000u);
  EXPECT_EQ(points.at("count").get<size_t>(), 3000u);
  const std::vector<float> xyz = DecodeFloats(points.at("positions_b64").get<std::string>());
  const std::string labels = Base64Decode(points.at("labels_b64").get<std::string>());
  ASSERT_EQ(xyz.size(), 3u * 3000u);
  ASSERT_EQ(labels.size(), 3000u);

  // The same points with the same labels (in label order), in the level display frame without a georeference:
  // x right, y forward (the first camera's z), z up (its -y).
  EXPECT_EQ(data.at("frame"), "level");
  EXPECT_EQ(data.at("units"), "map units");
  std::multiset<std::tuple<float, float, float, int>> expected, got;
  const Sim3d level = LevelFromCameraWorld();
  for (const SemanticPoint& p : MapPoints(3000)) {
    const Eigen::Vector3d q = level * p.position;
    EXPECT_NEAR(q.y(), p.position.z(), 1e-12);
    EXPECT_NEAR(q.z(), -p.position.y(), 1e-12);
    expected.insert(
        {static_cast<float>(q.x()), static_cast<float>(q.y()), static_cast<float>(q.z()), p.label});
  }
  for (size_t i = 0; i < labels.size(); ++i) {
    got.insert({xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2], static_cast<unsigned char>(labels[i])});
  }
  EXPECT_EQ(got, expected);

  // Class ranges cover the points in order, one contiguous range per label.
  size_t next = 0;
  std::set<int> seen;
  for (const json& range : points.at("class_ranges")) {
    const int label = range.at(0).get<int>();
    const size_t first = range.at(1).get<size_t>(), count = range.at(2).get<size_t>();
    EXPECT_EQ(first, next);
    EXPECT_TRUE(seen.insert(label).second) << label;
    for (size_t i = first; i < first + count; ++i) ASSERT_EQ(static_cast<unsigned char>(labels[i]), label);
    next = first + count;
  }
  EXPECT_EQ(next, 3000u);
  EXPECT_EQ(seen, (std::set<int>{0, 2, 13, kNoLabel}));

  // The legend's classes: only those present (road, sidewalk, car) and "other", counts matching the map.
  const json& classes = data.at("classes");
  ASSERT_EQ(classes.size(), 4u);
  std::uint64_t total = 0;
  for (const json& c : classes) total += c.at("map_count").get<std::uint64_t>();
  EXPECT_EQ(total, 3000u);
  const auto car =
      std::find_if(classes.begin(), classes.end(), [](const json& c) { return c.at("id") == 13; });
  ASSERT_NE(car, classes.end());
  EXPECT_EQ(car->at("name"), "car");
  EXPECT_EQ(car->at("color"), json({0, 0, 142}));
  EXPECT_EQ(classes.back().at("id").get<int>(), kNoLabel);
  EXPECT_EQ(classes.back().at("map_count").get<int>(), 60);

  // Trajectory, keyframes, landmarks and a sensible initial view.
  EXPECT_EQ(data.at("trajectory").at("count").get<int>(), 50);
  const std::vector<float> trajectory =
      DecodeFloats(data.at("trajectory").at("positions_b64").get<std::string>());
  ASSERT_EQ(trajectory.size(), 150u);
  EXPECT_FLOAT_EQ(trajectory[3 * 49 + 1], 24.5f);  // forward is up the screen
  EXPECT_EQ(data.at("keyframes").at("count").get<int>(), 10);
  ASSERT_EQ(data.at("landmarks").size(), 2u);
  EXPECT_EQ(data.at("landmarks").at(1).at("name").get<std::string>(), kTrickyName);
  EXPECT_GT(data.at("view").at("radius").get<double>(), 1.0);
}

TEST(HtmlReport, SubsamplesToMaxPointsReproducibly) {
  const TempDir dir;
  WriteFullRun(dir.path(), 5000, 100);
  HtmlReportOptions options;
  options.max_points = 1200;
  options.max_trajectory_poses = 10;
  const HtmlReportResult result = WriteHtmlReport(dir.path(), options);
  EXPECT_EQ(result.map_points, 5000u);
  EXPECT_EQ(result.points_shown, 1200u);
  EXPECT_EQ(result.trajectory_poses, 10u);
  const std::string first = ReadText(result.path);
  const json data = EmbeddedData(first);
  EXPECT_EQ(data.at("points").at("count").get<size_t>(), 1200u);
  EXPECT_EQ(data.at("points").at("total").get<size_t>(), 5000u);
  const std::vector<float> xyz = DecodeFloats(data.at("points").at("positions_b64").get<std::string>());
  ASSERT_EQ(xyz.size(), 3u * 1200u);
  // A subset of the map without repeats, from all over it (not just its first points).
  std::set<std::tuple<float, float, float>> all, chosen;
  for (const SemanticPoint& p : MapPoints(5000)) {
    const Eigen::Vector3d q = LevelFromCameraWorld() * p.position;  // the display frame
    all.insert({static_cast<float>(q.x()), static_cast<float>(q.y()), static_cast<float>(q.z())});
  }
  float max_x = 0;
  for (size_t i = 0; i < 1200; ++i) {
    const std::tuple<float, float, float> p{xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]};
    EXPECT_TRUE(all.count(p)) << i;
    chosen.insert(p);
    max_x = std::max(max_x, xyz[3 * i]);
  }
  EXPECT_EQ(chosen.size(), 1200u);
  EXPECT_GT(max_x, 40.0f);
  // The legend keeps the map's counts and says how many are shown.
  std::uint64_t shown = 0, map = 0;
  for (const json& c : data.at("classes")) {
    shown += c.at("shown").get<std::uint64_t>();
    map += c.at("map_count").get<std::uint64_t>();
  }
  EXPECT_EQ(shown, 1200u);
  EXPECT_EQ(map, 5000u);
  // The trajectory is thinned evenly, keeping both ends.
  const std::vector<float> trajectory =
      DecodeFloats(data.at("trajectory").at("positions_b64").get<std::string>());
  ASSERT_EQ(trajectory.size(), 30u);
  EXPECT_FLOAT_EQ(trajectory[1], 0.0f);
  EXPECT_FLOAT_EQ(trajectory[28], 49.5f);

  // Same options, same bytes; another seed, another subset.
  WriteHtmlReport(dir.path(), options);
  EXPECT_EQ(ReadText(result.path), first);
  options.seed = 2;
  WriteHtmlReport(dir.path(), options);
  EXPECT_NE(EmbeddedData(ReadText(result.path)).at("points").at("positions_b64"),
            data.at("points").at("positions_b64"));

  // No points at all: the view keeps the trajectory.
  options.max_points = 0;
  const HtmlReportResult none = WriteHtmlReport(dir.path(), options);
  EXPECT_EQ(none.points_shown, 0u);
  const json empty = EmbeddedData(ReadText(result.path));
  EXPECT_EQ(empty.at("points").at("count").get<int>(), 0);
  EXPECT_EQ(empty.at("trajectory").at("count").get<int>(), 10);
}

// With georeference.json the view is ENU (north up, metres); keyframes are thinned to max_keyframes.
TEST(HtmlReport, GeoreferencedViewIsEnuAndKeyframesAreThinned) {
  const TempDir dir;
  WriteFullRun(dir.path(), 100, 2000);
  // enu = 2 * map + t (no rotation).
  const json georeference = {
      {"origin", {{"lat", 49.0}, {"lon", 8.4}, {"alt", 100.0}}},
      {"enu_from_map",
       {{"scale", 2.0}, {"rotation_wxyz", {1.0, 0.0, 0.0, 0.0}}, {"translation", {10.0, 20.0, 30.0}}}},
      {"local", json::array()}};
  std::ofstream(dir.path() / "georeference.json") << georeference.dump();
  HtmlReportOptions options;
  options.max_keyframes = 50;
  const HtmlReportResult result = WriteHtmlReport(dir.path(), options);
  EXPECT_EQ(result.keyframes_shown, 50u);
  const json data = EmbeddedData(ReadText(result.path));
  EXPECT_EQ(data.at("frame"), "enu");
  EXPECT_EQ(data.at("units"), "m");
  EXPECT_EQ(data.at("keyframes").at("count").get<int>(), 50);
  EXPECT_EQ(data.at("keyframes").at("total").get<int>(), 400);
  const std::vector<float> trajectory =
      DecodeFloats(data.at("trajectory").at("positions_b64").get<std::string>());
  ASSERT_GE(trajectory.size(), 6u);
  // Pose 1 is at map (0, 0, 0.5): 2 * (0, 0, 0.5) + t.
  EXPECT_FLOAT_EQ(trajectory[3], 10.0f);
  EXPECT_FLOAT_EQ(trajectory[4], 20.0f);
  EXPECT_FLOAT_EQ(trajectory[5], 31.0f);
}

TEST(HtmlReport, MissingOptionalInputsLeaveTheirSectionsOut) {
  const TempDir dir;
  WriteJson(dir.path() / "run.json",
            {{"sequence", "/x/07"}, {"mode", "stereo"}, {"frames", 10}, {"tracked", 10}});
  const HtmlReportResult result = WriteHtmlReport(dir.path());
  EXPECT_EQ(result.sections, (std::vector<std::string>{"summary", "time-analysis", "notes"}));
  EXPECT_EQ(result.map_points, 0u);
  const std::string html = ReadText(result.path);
  EXPECT_EQ(html.find(kDataOpen), std::string::npos);
  EXPECT_EQ(html.find("id=\"map3d\""), std::string::npos);
  EXPECT_EQ(html.find("id=\"plots\""), std::string::npos);
  EXPECT_EQ(html.find("id=\"landmarks\""), std::string::npos);
  EXPECT_EQ(html.find("id=\"objects\""), std::string::npos);
  EXPECT_EQ(html.find("Trajectory error"), std::string::npos);  // no ATE in run.json
  EXPECT_EQ(html.find("Label accuracy"), std::string::npos);
  const std::string notes = Between(html, "<section id=\"notes\">", "</section>");
  for (const char* file : {"timing.json", "semantic_map.ply", "trajectory.tum", "keyframes.tum"}) {
    EXPECT_NE(notes.find(file), std::string::npos) << file;
  }

  // Only a trajectory: the 3D view, without map points.
  WriteTumTrajectory(dir.path() / "trajectory.tum", Poses(20));
  const HtmlReportResult with_trajectory = WriteHtmlReport(dir.path());
  EXPECT_EQ(with_trajectory.sections,
            (std::vector<std::string>{"summary", "time-analysis", "map3d", "notes"}));
  const json data = EmbeddedData(ReadText(with_trajectory.path));
  EXPECT_FALSE(data.contains("points"));
  EXPECT_FALSE(data.contains("keyframes"));
  EXPECT_EQ(data.at("trajectory").at("count").get<int>(), 20);
}

TEST(HtmlReport, MissingRunJsonIsAnInputErrorNamingIt) {
  const TempDir dir;
  WriteTumTrajectory(dir.path() / "trajectory.tum", Poses(5));
  try {
    WriteHtmlReport(dir.path());
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where().file, dir.path() / "run.json");
    EXPECT_NE(std::string(e.what()).find("run.json"), std::string::npos);
  }
  EXPECT_FALSE(fs::exists(dir.path() / "report.html"));
}

TEST(HtmlReport, MalformedInputsAreInputErrorsNamingFileAndField) {
  const TempDir dir;
  WriteFullRun(dir.path(), 100, 10);
  auto expect_error = [&](const fs::path& file, const std::string& text, const std::string& fragment) {
    const std::string original = ReadText(file);
    WriteFileAtomically(file, text);
    try {
      WriteHtmlReport(dir.path());
      ADD_FAILURE() << "no error for " << text;
    } catch (const InputError& e) {
      EXPECT_EQ(e.where().file, file);
      EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    }
    WriteFileAtomically(file, original);
  };
  expect_error(dir.path() / "run.json", "{\"frames\": 10,", "json");
  expect_error(dir.path() / "run.json", "[1, 2]", "expected a JSON object");
  expect_error(dir.path() / "run.json", R"({"frames": "many"})", "frames");
  expect_error(dir.path() / "run.json", R"({"geo": {"gps_fixes": 1.5, "georeferenced": true}})",
               "geo.gps_fixes");
  expect_error(
      dir.path() / "run.json",
      R"({"intrinsics_refinement": [{"map": 0, "nominal": {"fx": "f"}, "refined": {"fx": 1, "k1": 0}}]})",
      "intrinsics_refinement.nominal.fx");
  expect_error(dir.path() / "timing.json", R"({"tracking": {"count": 3}})", "tracking.median_ms");
  expect_error(dir.path() / "landmarks.geojson", R"({"features": [{"properties": {"name": 3}}]})",
               "features[0].properties.name");
  expect_error(dir.path() / "objects.json", R"({"objects": [{"id": 0, "size_m": [1, 2]}]})",
               "objects[0].size_m");
  expect_error(dir.path() / "plots" / "gps.png", "not an image", "not a PNG");
  expect_error(dir.path() / "trajectory.tum", "0 1 2 3\n", "trajectory.tum");
  // Restored, the folder gives a report again.
  EXPECT_NO_THROW(WriteHtmlReport(dir.path()));
}

TEST(HtmlReport, EscapesNamesAndLimitsTables) {
  const TempDir dir;
  WriteFullRun(dir.path(), 100, 10);
  HtmlReportOptions options;
  options.max_table_rows = 1;
  options.max_plot_bytes = 10;  // every plot is larger
  const HtmlReportResult result = WriteHtmlReport(dir.path(), options);
  const std::string html = ReadText(result.path);
  // The landmark called "Café </script><b>&" is text in the table and a string in the data, never markup.
  EXPECT_EQ(html.find("</script><b>"), std::string::npos);
  EXPECT_NE(html.find("Caf\xC3\xA9 &lt;/script&gt;&lt;b&gt;&amp;"), std::string::npos);
  // One object row of three.
  const std::string objects = Between(html, "<section id=\"objects\">", "</section>");
  EXPECT_NE(objects.find("3 objects: 1 building, 2 car"), std::string::npos) << objects;
  EXPECT_NE(objects.find("2 more objects"), std::string::npos);
  EXPECT_NE(objects.find("centroid (ENU, m)"), std::string::npos);
  // The plots are too large: left out, and said so.
  EXPECT_EQ(html.find("data:image/png"), std::string::npos);
  EXPECT_EQ(std::count(result.sections.begin(), result.sections.end(), "plots"), 0);
  ASSERT_EQ(result.notes.size(), 2u);
  EXPECT_NE(result.notes[0].find("plots/gps.png"), std::string::npos);
  EXPECT_NE(html.find("max_plot_bytes"), std::string::npos);
}

// Object sizes are metres only where objects.json says the map's scale is known.
TEST(HtmlReport, ObjectSizesSayTheirUnit) {
  const TempDir dir;
  WriteFullRun(dir.path(), 100, 10);
  const auto objects_section = [&](const std::string& source) {
    nlohmann::json objects = nlohmann::json::parse(ReadText(dir / "objects.json"));
    objects["scale_source"] = source;
    objects["metres_per_map_unit"] = source == "road" ? 19.6 : 1.0;
    WriteFileAtomically(dir / "objects.json", objects.dump());
    return Between(ReadText(WriteHtmlReport(dir.path()).path), "<section id=\"objects\">", "</section>");
  };
  std::string section = objects_section("road");
  EXPECT_NE(section.find("a map unit is 19.60 m, from the camera's height above the road"), std::string::npos)
      << section;
  EXPECT_NE(section.find("size (m)"), std::string::npos);
  section = objects_section("map");
  EXPECT_NE(section.find("Sizes in map units"), std::string::npos) << section;
  EXPECT_NE(section.find("size (map units)"), std::string::npos);
  section = objects_section("georeference");
  EXPECT_NE(section.find("Sizes in metres, by the GPS"), std::string::npos) << section;
  EXPECT_NE(section.find("size (m)"), std::string::npos);
}

TEST(HtmlReport, OptionsAreChecked) {
  HtmlReportOptions options;
  EXPECT_NO_THROW(options.Check());
  options.max_trajectory_poses = 1;
  EXPECT_THROW(options.Check(), InvalidArgument);
  options = {};
  options.max_plot_bytes = 0;
  EXPECT_THROW(options.Check(), InvalidArgument);
  const TempDir dir;
  WriteFullRun(dir.path(), 10, 10);
  EXPECT_THROW(WriteHtmlReport(dir.path(), options), InvalidArgument);
}

}  // namespace
}  // namespace semslam
