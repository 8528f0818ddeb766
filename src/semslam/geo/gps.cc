#include "semslam/geo/gps.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>

#include "semslam/core/text_reader.h"
#include "semslam/geo/csv.h"
#include "semslam/geo/gps_internal.h"

namespace semslam {

namespace fs = std::filesystem;
using gps_internal::FixCollector;

void GpsReadOptions::Check() const {
  Require(std::isfinite(default_sigma_m) && default_sigma_m > 0, "GPS default_sigma_m must be positive");
  Require(std::isfinite(min_sigma_m) && min_sigma_m > 0, "GPS min_sigma_m must be positive");
  Require(std::isfinite(nmea_uere_m) && nmea_uere_m > 0, "GPS nmea_uere_m must be positive");
  Require(!nmea_day_start_unix || std::isfinite(*nmea_day_start_unix),
          "GPS nmea_day_start_unix must be finite");
  Require(std::isfinite(min_altitude_m) && std::isfinite(max_altitude_m) && min_altitude_m < max_altitude_m,
          "GPS altitude range must be finite and non-empty");
}

namespace {

// ---- CSV ----

enum class CsvColumn { kTime, kLat, kLon, kAlt, kSigma, kIgnored };

CsvColumn ColumnFromName(const std::string& raw) {
  const std::string name = NormalizeColumnName(raw);
  static const std::map<std::string, CsvColumn> names = {
      {"t", CsvColumn::kTime},     {"time", CsvColumn::kTime},     {"timestamp", CsvColumn::kTime},
      {"times", CsvColumn::kTime}, {"lat", CsvColumn::kLat},       {"latitude", CsvColumn::kLat},
      {"latdeg", CsvColumn::kLat}, {"lon", CsvColumn::kLon},       {"lng", CsvColumn::kLon},
      {"long", CsvColumn::kLon},   {"longitude", CsvColumn::kLon}, {"londeg", CsvColumn::kLon},
      {"alt", CsvColumn::kAlt},    {"altitude", CsvColumn::kAlt},  {"height", CsvColumn::kAlt},
      {"altm", CsvColumn::kAlt},   {"sigma", CsvColumn::kSigma},   {"accuracy", CsvColumn::kSigma},
      {"std", CsvColumn::kSigma},  {"sigmam", CsvColumn::kSigma},  {"stddev", CsvColumn::kSigma}};
  const auto it = names.find(name);
  return it == names.end() ? CsvColumn::kIgnored : it->second;
}

bool LooksNumeric(std::string_view s) {
  s = Trim(s);
  if (s.empty()) return false;
  const char c = s.front();
  return (c >= '0' && c <= '9') || c == '-' || c == '+' || c == '.' || s == "nan" || s == "NaN" || s == "inf";
}

// ---- NMEA ----

int HexDigit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  return -1;
}

// Unix seconds of 00:00 UTC on a civil date (proleptic Gregorian; H. Hinnant's days_from_civil algorithm).
double UnixDayStart(int year, int month, int day) {
  year -= month <= 2 ? 1 : 0;
  const int era = (year >= 0 ? year : year - 399) / 400;
  const int yoe = year - era * 400;
  const int doy = (153 * (month + (month > 2 ? -3 : 9)) + 2) / 5 + day - 1;
  const int doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
  const long long days = static_cast<long long>(era) * 146097 + doe - 719468;
  return static_cast<double>(days) * 86400.0;
}

struct NmeaSentence {
  std::string type;                      // "GGA", "RMC", ... (talker removed)
  std::vector<std::string_view> fields;  // fields[0] is the address ("GPGGA")
};

// Verifies framing and checksum; returns nullopt (with `reason`) when the line must be skipped.
std::optional<NmeaSentence> ParseNmeaSentence(std::string_view line, bool require_checksum,
                                              std::string& reason) {
  line = Trim(line);
  if (line.empty() || line.front() != '$') {
    reason = "not an NMEA sentence (does not start with '$')";
    return std::nullopt;
  }
  std::string_view body = line.substr(1);
  const size_t star = body.find('*');
  if (star == std::string_view::npos) {
    if (require_checksum) {
      reason = "NMEA sentence without a checksum";
      return std::nullopt;
    }
  } else {
    const std::string_view given = body.substr(star + 1);
    body = body.substr(0, star);
    if (given.size() != 2 || HexDigit(given[0]) < 0 || HexDigit(given[1]) < 0) {
      reason = fmt::format("malformed NMEA checksum '{}'", given);
      return std::nullopt;
    }
    unsigned computed = 0;
    for (const char c : body) computed ^= static_cast<unsigned char>(c);
    const unsigned expected = static_cast<unsigned>(HexDigit(given[0]) * 16 + HexDigit(given[1]));
    if (computed != expected) {
      reason = fmt::format("bad NMEA checksum: computed {:02X}, sentence says {}", computed, given);
      return std::nullopt;
    }
  }
  NmeaSentence sentence;
  sentence.fields = SplitFields(body, ',');
  const std::string_view address = sentence.fields[0];
  if (address.size() < 3) {
    reason = fmt::format("NMEA address '{}' too short", address);
    return std::nullopt;
  }
  // Proprietary sentences ($P...) have no 3-letter type; they are ignored anyway.
  sentence.type = std::string(address.substr(address.size() - 3));
  return sentence;
}

// ddmm.mmmm (or dddmm.mmmm) with hemisphere -> signed degrees; nullopt when malformed.
std::optional<double> ParseNmeaAngle(std::string_view value, std::string_view hemisphere, int degree_digits,
                                     char positive, char negative) {
  value = Trim(value);
  if (value.size() < static_cast<size_t>(degree_digits) + 2 || hemisphere.size() != 1) return std::nullopt;
  const SourceLocation nowhere;
  double degrees = 0, minutes = 0;
  try {
    degrees = ParseDouble(value.substr(0, degree_digits), nowhere, "");
    minutes = ParseDouble(value.substr(degree_digits), nowhere, "");
  } catch (const InputError&) {
    return std::nullopt;
  }
  if (degrees < 0 || minutes < 0 || minutes >= 60.0) return std::nullopt;
  const double angle = degrees + minutes / 60.0;
  if (hemisphere[0] == positive) return angle;
  if (hemisphere[0] == negative) return -angle;
  return std::nullopt;
}

// hhmmss(.sss) -> seconds of day.
std::optional<double> ParseNmeaTime(std::string_view value) {
  value = Trim(value);
  if (value.size() < 6) return std::nullopt;
  const SourceLocation nowhere;
  try {
    const double h = ParseDouble(value.substr(0, 2), nowhere, "");
    const double m = ParseDouble(value.substr(2, 2), nowhere, "");
    const double s = ParseDouble(value.substr(4), nowhere, "");
    if (h < 0 || h >= 24 || m < 0 || m >= 60 || s < 0 || s >= 61) return std::nullopt;
    return h * 3600 + m * 60 + s;
  } catch (const InputError&) {
    return std::nullopt;
  }
}

std::optional<double> ParseOptionalNumber(std::string_view value) {
  value = Trim(value);
  if (value.empty()) return std::nullopt;
  try {
    return ParseDouble(value, SourceLocation{}, "");
  } catch (const InputError&) {
    return std::nullopt;
  }
}

}  // namespace

GpsLog ReadGpsCsv(const fs::path& file, const GpsReadOptions& options) {
  options.Check();
  GpsLog log;
  log.source = file;
  log.format = "csv";
  FixCollector collector(log, options);
  TextReader reader(file);
  std::vector<CsvColumn> columns = {CsvColumn::kTime, CsvColumn::kLat, CsvColumn::kLon, CsvColumn::kAlt,
                                    CsvColumn::kSigma};
  bool has_header = false;
  bool first_record = true;
  while (const auto line = reader.NextLine()) {
    const std::string_view text = Trim(*line);
    if (text.empty() || text.front() == '#') continue;
    const SourceLocation where = reader.Where();
    const std::vector<std::string> fields = SplitCsvRecord(text, where);
    if (first_record) {
      first_record = false;
      if (!LooksNumeric(fields[0])) {
        has_header = true;
        columns.clear();
        for (const std::string& name : fields) columns.push_back(ColumnFromName(name));
        for (const CsvColumn needed : {CsvColumn::kTime, CsvColumn::kLat, CsvColumn::kLon}) {
          if (std::find(columns.begin(), columns.end(), needed) == columns.end()) {
            throw InputError(
                where, "header",
                "a GPS CSV header must name the columns t, lat and lon (found '" + std::string(text) + "')");
          }
        }
        continue;
      }
    }
    if (has_header ? fields.size() != columns.size() : (fields.size() < 3 || fields.size() > 5)) {
      throw InputError(
          where, "columns",
          has_header
              ? fmt::format("expected {} fields as in the header, found {}", columns.size(), fields.size())
              : fmt::format("expected t,lat,lon[,alt,sigma] (3 to 5 fields), found {}", fields.size()));
    }
    GpsFix fix;
    fix.sigma_m = options.default_sigma_m;
    fix.source = where;
    for (size_t i = 0; i < fields.size(); ++i) {
      const std::string_view value = Trim(fields[i]);
      switch (columns[i]) {
        case CsvColumn::kTime:
          fix.timestamp = ParseDoubleAllowNonFinite(value, where, "t");
          break;
        case CsvColumn::kLat:
          fix.position.latitude_deg = ParseDoubleAllowNonFinite(value, where, "lat");
          break;
        case CsvColumn::kLon:
          fix.position.longitude_deg = ParseDoubleAllowNonFinite(value, where, "lon");
          break;
        case CsvColumn::kAlt:
          if (!value.empty()) fix.position.altitude_m = ParseDoubleAllowNonFinite(value, where, "alt");
          break;
        case CsvColumn::kSigma:
          if (!value.empty()) fix.sigma_m = ParseDoubleAllowNonFinite(value, where, "sigma");
          break;
        case CsvColumn::kIgnored:
          break;
      }
    }
    collector.Add(std::move(fix));
  }
  return log;
}

GpsLog ReadGpsNmea(const fs::path& file, const GpsReadOptions& options) {
  options.Check();
  GpsLog log;
  log.source = file;
  log.format = "nmea";
  FixCollector collector(log, options);

  struct Line {
    SourceLocation where;
    std::string text;
  };
  std::vector<Line> lines;
  {
    TextReader reader(file);
    while (const auto line = reader.NextLine()) {
      if (Trim(*line).empty()) continue;
      lines.push_back({reader.Where(), *line});
    }
  }

  // The date, from the options or the first valid RMC sentence.
  std::optional<double> day_start = options.nmea_day_start_unix;
  std::optional<double> rmc_time_of_day;
  if (!day_start) {
    for (const Line& line : lines) {
      std::string reason;
      const auto s = ParseNmeaSentence(line.text, options.nmea_require_checksum, reason);
      if (!s || s->type != "RMC" || s->fields.size() < 10) continue;
      const std::string_view date = Trim(s->fields[9]);
      const auto time = ParseNmeaTime(s->fields[1]);
      if (date.size() != 6 || !time) continue;
      const auto d = ParseOptionalNumber(date.substr(0, 2));
      const auto m = ParseOptionalNumber(date.substr(2, 2));
      const auto y = ParseOptionalNumber(date.substr(4, 2));
      if (!d || !m || !y || *d < 1 || *d > 31 || *m < 1 || *m > 12) continue;
      const int year = static_cast<int>(*y) + (*y < 80 ? 2000 : 1900);
      day_start = UnixDayStart(year, static_cast<int>(*m), static_cast<int>(*d));
      rmc_time_of_day = time;
      break;
    }
  }

  std::optional<double> previous_time_of_day;
  double day_offset = 0.0;
  bool first_gga = true;
  for (const Line& line : lines) {
    std::string reason;
    const auto s = ParseNmeaSentence(line.text, options.nmea_require_checksum, reason);
    if (!s) {
      collector.Skip(line.where, reason);
      continue;
    }
    if (s->type != "GGA") continue;
    const auto& f = s->fields;
    if (f.size() < 10) {
      collector.Skip(line.where, fmt::format("GGA sentence with {} fields, expected at least 10", f.size()));
      continue;
    }
    const auto time_of_day = ParseNmeaTime(f[1]);
    if (!time_of_day) {
      collector.Skip(line.where, fmt::format("GGA time '{}' is malformed", f[1]));
      continue;
    }
    if (first_gga) {
      first_gga = false;
      // A GGA just before midnight with the RMC date of just after it belongs to the previous day.
      if (rmc_time_of_day && *time_of_day - *rmc_time_of_day > 43200.0) day_offset = -86400.0;
    }
    if (previous_time_of_day && *time_of_day < *previous_time_of_day - 43200.0) day_offset += 86400.0;
    previous_time_of_day = time_of_day;

    const auto quality = ParseOptionalNumber(f[6]);
    if (!quality || *quality <= 0) {
      collector.Skip(line.where, fmt::format("GGA fix quality '{}' means no fix", f[6]));
      continue;
    }
    const auto lat = ParseNmeaAngle(f[2], f[3], 2, 'N', 'S');
    const auto lon = ParseNmeaAngle(f[4], f[5], 3, 'E', 'W');
    if (!lat || !lon) {
      collector.Skip(line.where,
                     fmt::format("GGA position '{},{},{},{}' is malformed", f[2], f[3], f[4], f[5]));
      continue;
    }
    const auto altitude = ParseOptionalNumber(f[9]);
    if (!altitude) {
      collector.Skip(line.where, fmt::format("GGA altitude '{}' is malformed", f[9]));
      continue;
    }
    const auto separation = f.size() > 11 ? ParseOptionalNumber(f[11]) : std::nullopt;
    const auto hdop = ParseOptionalNumber(f[8]);
    GpsFix fix;
    fix.timestamp = day_start.value_or(0.0) + day_offset + *time_of_day;
    fix.position = Wgs84{*lat, *lon, *altitude + separation.value_or(0.0)};
    fix.sigma_m = hdop && *hdop > 0 ? *hdop * options.nmea_uere_m : options.default_sigma_m;
    fix.source = line.where;
    collector.Add(std::move(fix));
  }
  return log;
}

void LogSkippedFixes(const GpsLog& log, size_t max_lines) {
  for (const std::string& note : log.notes) spdlog::info("GPS {}: {}", log.source.string(), note);
  for (size_t i = 0; i < log.skipped.size() && i < max_lines; ++i) {
    spdlog::warn("GPS fix skipped: {}: {}", log.skipped[i].where.ToString(), log.skipped[i].reason);
  }
  if (log.skipped.size() > max_lines) {
    spdlog::warn("GPS: {} more fixes skipped in {}", log.skipped.size() - max_lines, log.source.string());
  }
}

EnuFrame MakeEnuFrame(const GpsLog& log, const std::optional<Wgs84>& origin) {
  if (origin) return EnuFrame(*origin);
  if (log.fixes.empty()) throw InputError(log.source, "no valid GPS fix to place the ENU origin at");
  return EnuFrame(log.fixes.front().position);
}

Points3d FixesToEnu(const std::vector<GpsFix>& fixes, const EnuFrame& frame) {
  Points3d enu;
  enu.reserve(fixes.size());
  for (const GpsFix& fix : fixes) enu.push_back(frame.ToEnu(fix.position));
  return enu;
}

std::vector<std::optional<size_t>> MatchFixesToTimes(const std::vector<GpsFix>& fixes,
                                                     const std::vector<double>& times, double tolerance_s,
                                                     double time_offset_s) {
  Require(tolerance_s >= 0 && std::isfinite(tolerance_s),
          "GPS match tolerance must be a non-negative number");
  std::vector<std::optional<size_t>> matches(times.size());
  if (fixes.empty()) return matches;
  for (size_t i = 0; i < times.size(); ++i) {
    const double t = times[i] + time_offset_s;
    if (!std::isfinite(t)) continue;
    const auto it = std::lower_bound(fixes.begin(), fixes.end(), t,
                                     [](const GpsFix& fix, double value) { return fix.timestamp < value; });
    size_t best = fixes.size();
    double best_dt = std::numeric_limits<double>::infinity();
    if (it != fixes.end()) {
      best = static_cast<size_t>(it - fixes.begin());
      best_dt = it->timestamp - t;
    }
    if (it != fixes.begin()) {
      const auto prev = std::prev(it);
      if (t - prev->timestamp <= best_dt) {
        best = static_cast<size_t>(prev - fixes.begin());
        best_dt = t - prev->timestamp;
      }
    }
    if (best < fixes.size() && best_dt <= tolerance_s) matches[i] = best;
  }
  return matches;
}

double GuessTimeOffset(const std::vector<GpsFix>& fixes, const std::vector<double>& frame_times) {
  if (fixes.empty() || frame_times.empty()) return 0.0;
  const double gps_begin = fixes.front().timestamp, gps_end = fixes.back().timestamp;
  const auto [min_it, max_it] = std::minmax_element(frame_times.begin(), frame_times.end());
  if (*max_it >= gps_begin && *min_it <= gps_end) return 0.0;
  return gps_begin - *min_it;
}

}  // namespace semslam
