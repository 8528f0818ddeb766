// KML GPS tracks: a gx:Track (timed <when> + <gx:coord> pairs), timed Placemark points (<TimeStamp><when>
// with a <Point>), or an untimed LineString whose k-th coordinate is frame k of the sequence (as the
// published RTK tracks of the KITTI odometry sequences are). Parsed with expat.

#include <expat.h>
#include <fmt/format.h>

#include <cmath>
#include <fstream>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "semslam/core/text_reader.h"
#include "semslam/geo/gps.h"
#include "semslam/geo/gps_internal.h"

namespace semslam {

namespace fs = std::filesystem;
using gps_internal::FixCollector;

namespace {

// The local part of an XML name ("gx:coord" -> "coord").
std::string_view LocalName(const char* name) {
  const std::string_view full(name);
  const size_t colon = full.rfind(':');
  return colon == std::string_view::npos ? full : full.substr(colon + 1);
}

// Days since 1970-01-01 of a proleptic Gregorian civil date (H. Hinnant's days_from_civil).
long long DaysFromCivil(int year, int month, int day) {
  year -= month <= 2 ? 1 : 0;
  const int era = (year >= 0 ? year : year - 399) / 400;
  const int yoe = year - era * 400;
  const int doy = (153 * (month + (month > 2 ? -3 : 9)) + 2) / 5 + day - 1;
  const int doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
  return static_cast<long long>(era) * 146097 + doe - 719468;
}

}  // namespace

std::optional<double> ParseIso8601Utc(std::string_view text) {
  text = Trim(text);
  int year = 0, month = 0, day = 0, hour = 0, minute = 0;
  double second = 0.0;
  char tail[16] = {0};
  const std::string copy(text);
  const int n = std::sscanf(copy.c_str(), "%4d-%2d-%2dT%2d:%2d:%lf%15s", &year, &month, &day, &hour, &minute,
                            &second, tail);
  if (n < 6 || month < 1 || month > 12 || day < 1 || day > 31 || hour < 0 || hour > 23 || minute < 0 ||
      minute > 59 || !(second >= 0.0 && second < 61.0)) {
    return std::nullopt;
  }
  double offset_s = 0.0;
  const std::string_view zone(tail);
  if (n == 7 && zone != "Z") {
    int zh = 0, zm = 0;
    if (zone.size() != 6 || (zone[0] != '+' && zone[0] != '-') ||
        std::sscanf(tail + 1, "%2d:%2d", &zh, &zm) != 2) {
      return std::nullopt;
    }
    offset_s = (zone[0] == '+' ? 1.0 : -1.0) * (zh * 3600.0 + zm * 60.0);
  }
  return static_cast<double>(DaysFromCivil(year, month, day)) * 86400.0 + hour * 3600.0 + minute * 60.0 +
         second - offset_s;
}

namespace {

// Collects the positions and times of a KML document as expat reports its elements.
class KmlParser {
 public:
  struct Point {
    Wgs84 position;
    std::optional<double> time;
    int line = 0;
  };

  explicit KmlParser(const fs::path& file) : file_(file) {}

  void Parse() {
    std::ifstream stream(file_, std::ios::binary);
    if (!stream) throw InputError(file_, "cannot open the KML file");
    XML_Parser parser = XML_ParserCreate(nullptr);
    if (parser == nullptr) throw InputError(file_, "cannot create an XML parser");
    XML_SetUserData(parser, this);
    XML_SetElementHandler(parser, &KmlParser::Start, &KmlParser::End);
    XML_SetCharacterDataHandler(parser, &KmlParser::Text);
    parser_ = parser;
    std::vector<char> buffer(1 << 16);
    bool done = false;
    while (!done) {
      stream.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
      const auto got = static_cast<int>(stream.gcount());
      done = got == 0 || stream.eof();
      if (XML_Parse(parser, buffer.data(), got, done ? 1 : 0) == XML_STATUS_ERROR) {
        const SourceLocation where{file_, static_cast<int>(XML_GetCurrentLineNumber(parser))};
        const std::string message = XML_ErrorString(XML_GetErrorCode(parser));
        XML_ParserFree(parser);
        throw InputError(where, "xml", "not a well-formed KML file: " + message);
      }
      if (error_) {
        const InputError error = *error_;
        XML_ParserFree(parser);
        throw error;
      }
    }
    XML_ParserFree(parser);
  }

  const std::vector<Point>& timed() const { return timed_; }
  const std::vector<Point>& untimed() const { return untimed_; }

 private:
  static void Start(void* self, const char* name, const char** /*attributes*/) {
    static_cast<KmlParser*>(self)->OnStart(LocalName(name));
  }
  static void End(void* self, const char* name) { static_cast<KmlParser*>(self)->OnEnd(LocalName(name)); }
  static void Text(void* self, const char* text, int length) {
    auto* parser = static_cast<KmlParser*>(self);
    if (parser->collecting_) parser->text_.append(text, static_cast<size_t>(length));
  }

  int Line() const { return static_cast<int>(XML_GetCurrentLineNumber(static_cast<XML_Parser>(parser_))); }

  void OnStart(std::string_view name) {
    if (name == "Placemark") {
      placemark_time_.reset();
      placemark_points_.clear();
    } else if (name == "Track") {
      track_times_.clear();
      track_coords_.clear();
      in_track_ = true;
    }
    if (name == "when" || name == "coord" || name == "coordinates") {
      collecting_ = true;
      text_.clear();
      text_line_ = Line();
    }
  }

  void OnEnd(std::string_view name) {
    if (error_) return;
    if (name == "when") {
      const std::optional<double> time = ParseIso8601Utc(text_);
      if (!time) return Fail("when", fmt::format("'{}' is not an ISO 8601 time", std::string(Trim(text_))));
      if (in_track_) {
        track_times_.push_back(*time);
      } else {
        placemark_time_ = *time;
      }
    } else if (name == "coord" && in_track_) {
      // gx:coord: "lon lat alt", space-separated.
      std::vector<std::string_view> fields;
      for (std::string_view rest = Trim(text_); !rest.empty();) {
        const size_t space = rest.find_first_of(" \t\r\n");
        fields.push_back(rest.substr(0, space));
        rest = space == std::string_view::npos ? std::string_view() : Trim(rest.substr(space));
      }
      if (fields.size() < 2 || fields.size() > 3) return Fail("coord", "expected 'lon lat [alt]'");
      track_coords_.push_back(ParsePosition(fields));
    } else if (name == "coordinates") {
      // "lon,lat[,alt]" tuples separated by white space.
      for (std::string_view rest = Trim(text_); !rest.empty();) {
        const size_t space = rest.find_first_of(" \t\r\n");
        const std::vector<std::string_view> fields = SplitFields(rest.substr(0, space), ',');
        if (fields.size() < 2 || fields.size() > 3)
          return Fail("coordinates", "expected 'lon,lat[,alt]' tuples");
        placemark_points_.push_back(ParsePosition(fields));
        if (error_) return;
        rest = space == std::string_view::npos ? std::string_view() : Trim(rest.substr(space));
      }
    } else if (name == "Track") {
      in_track_ = false;
      if (track_times_.size() != track_coords_.size()) {
        return Fail("Track", fmt::format("a gx:Track with {} <when> and {} <gx:coord>", track_times_.size(),
                                         track_coords_.size()));
      }
      for (size_t i = 0; i < track_times_.size(); ++i)
        timed_.push_back({track_coords_[i], track_times_[i], text_line_});
    } else if (name == "Placemark") {
      if (placemark_time_ && placemark_points_.size() == 1) {
        timed_.push_back({placemark_points_.front(), placemark_time_, text_line_});
      } else {
        for (const Wgs84& p : placemark_points_) untimed_.push_back({p, std::nullopt, text_line_});
      }
    }
    if (name == "when" || name == "coord" || name == "coordinates") collecting_ = false;
  }

  Wgs84 ParsePosition(const std::vector<std::string_view>& fields) {
    const SourceLocation where{file_, text_line_};
    Wgs84 p;
    try {
      p.longitude_deg = ParseDoubleAllowNonFinite(Trim(fields[0]), where, "lon");
      p.latitude_deg = ParseDoubleAllowNonFinite(Trim(fields[1]), where, "lat");
      if (fields.size() > 2) p.altitude_m = ParseDoubleAllowNonFinite(Trim(fields[2]), where, "alt");
    } catch (const InputError& e) {
      error_ = e;
    }
    return p;
  }

  void Fail(const char* field, const std::string& message) {
    error_ = InputError(SourceLocation{file_, text_line_}, field, message);
  }

  fs::path file_;
  void* parser_ = nullptr;
  bool collecting_ = false;
  std::string text_;
  int text_line_ = 0;
  bool in_track_ = false;
  std::vector<double> track_times_;
  std::vector<Wgs84> track_coords_;
  std::optional<double> placemark_time_;
  std::vector<Wgs84> placemark_points_;
  std::vector<Point> timed_;
  std::vector<Point> untimed_;
  std::optional<InputError> error_;
};

}  // namespace

GpsLog ReadGpsKml(const fs::path& file, const GpsReadOptions& options) {
  options.Check();
  KmlParser parser(file);
  parser.Parse();
  GpsLog log;
  log.source = file;
  log.format = "kml";
  FixCollector collector(log, options);
  // Timed positions are fixes in Unix time; a document without any is one position per frame.
  const bool by_frame = parser.timed().empty();
  const auto& points = by_frame ? parser.untimed() : parser.timed();
  if (points.empty()) throw InputError(file, "the KML file holds no coordinates");
  log.times_are_frames = by_frame;
  for (size_t k = 0; k < points.size(); ++k) {
    GpsFix fix;
    fix.timestamp = by_frame ? static_cast<double>(k) : *points[k].time;
    fix.position = points[k].position;
    fix.sigma_m = options.default_sigma_m;
    fix.source = SourceLocation{file, points[k].line};
    collector.Add(std::move(fix));
  }
  return log;
}

void TimeFixesByFrame(GpsLog& log, const std::vector<double>& frame_times) {
  if (!log.times_are_frames) return;
  std::vector<GpsFix> timed;
  size_t beyond = 0;
  for (GpsFix& fix : log.fixes) {
    const auto frame = static_cast<size_t>(fix.timestamp);
    if (frame >= frame_times.size()) {
      ++beyond;
      continue;
    }
    fix.timestamp = frame_times[frame];
    if (!timed.empty() && !(fix.timestamp > timed.back().timestamp)) {
      log.skipped.push_back({fix.source, fmt::format("frame {}'s time {:.6f} is not after the frame before's",
                                                     frame, fix.timestamp)});
      continue;
    }
    timed.push_back(std::move(fix));
  }
  if (beyond > 0) {
    log.notes.push_back(
        fmt::format("{} positions beyond the sequence's {} frames are not used", beyond, frame_times.size()));
  }
  log.fixes = std::move(timed);
  log.times_are_frames = false;
}

}  // namespace semslam
