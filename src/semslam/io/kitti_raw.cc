#include "semslam/io/kitti_raw.h"

#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <regex>
#include <system_error>

#include "semslam/core/atomic_file.h"
#include "semslam/core/text_reader.h"

namespace semslam {

namespace fs = std::filesystem;

namespace {

constexpr const char* kOxtsFieldNames[OxtsRecord::kNumFields] = {
    "lat",          "lon",     "alt",     "roll",    "pitch",   "yaw",    "vn", "ve",
    "vf",           "vl",      "vu",      "ax",      "ay",      "az",     "af", "al",
    "au",           "wx",      "wy",      "wz",      "wf",      "wl",     "wu", "pos_accuracy",
    "vel_accuracy", "navstat", "numsats", "posmode", "velmode", "orimode"};

// The 25 floating-point fields, in file order (the last five fields are integers).
std::array<double*, 25> DoubleFields(OxtsRecord& r) {
  return {&r.lat, &r.lon, &r.alt, &r.roll, &r.pitch, &r.yaw,          &r.vn,          &r.ve, &r.vf,
          &r.vl,  &r.vu,  &r.ax,  &r.ay,   &r.az,    &r.af,           &r.al,          &r.au, &r.wx,
          &r.wy,  &r.wz,  &r.wf,  &r.wl,   &r.wu,    &r.pos_accuracy, &r.vel_accuracy};
}
std::array<int*, 5> IntFields(OxtsRecord& r) {
  return {&r.navstat, &r.numsats, &r.posmode, &r.velmode, &r.orimode};
}

fs::path OxtsDataFile(const fs::path& oxts_dir, size_t index) {
  return oxts_dir / "data" / fmt::format("{:010d}.txt", index);
}

// Reads the non-blank lines of a file; blank lines are accepted only at its end.
std::vector<std::pair<std::string, SourceLocation>> DataLines(const fs::path& path) {
  TextReader reader(path);
  std::vector<std::pair<std::string, SourceLocation>> lines;
  std::optional<SourceLocation> blank;
  while (const auto line = reader.NextLine()) {
    if (Trim(*line).empty()) {
      if (!blank) blank = reader.Where();
      continue;
    }
    if (blank) throw InputError(*blank, "blank line inside the file (one entry per line expected)");
    lines.emplace_back(*line, reader.Where());
  }
  return lines;
}

double ParseKittiRawTimestamp(std::string_view text, const SourceLocation& where) {
  // "YYYY-MM-DD hh:mm:ss.fffffffff" (UTC; the fraction may have any number of digits, or none).
  static const std::regex pattern(R"((\d{4})-(\d{2})-(\d{2})[ T](\d{2}):(\d{2}):(\d{2})(?:\.(\d+))?)");
  std::cmatch m;
  const std::string_view trimmed = Trim(text);
  if (!std::regex_match(trimmed.data(), trimmed.data() + trimmed.size(), m, pattern)) {
    throw InputError(where, "timestamp",
                     fmt::format("'{}' is not a date and time 'YYYY-MM-DD hh:mm:ss.fffffffff'", trimmed));
  }
  const auto number = [&](int group) { return std::stoi(m.str(group)); };
  using namespace std::chrono;
  const year_month_day date{year{number(1)}, month{static_cast<unsigned>(number(2))},
                            day{static_cast<unsigned>(number(3))}};
  if (!date.ok()) throw InputError(where, "timestamp", fmt::format("'{}' is not a valid date", m.str(0)));
  const int hour = number(4), minute = number(5), second = number(6);
  if (hour > 23 || minute > 59 || second > 60) {
    throw InputError(where, "timestamp", fmt::format("'{}' is not a valid time of day", m.str(0)));
  }
  const long long whole =
      sys_days(date).time_since_epoch().count() * 86400LL + hour * 3600LL + minute * 60LL + second;
  // Nanoseconds from the first nine fraction digits (KITTI writes exactly nine).
  long long nanos = 0;
  if (m[7].matched) {
    std::string digits = m.str(7).substr(0, 9);
    digits.resize(9, '0');
    nanos = std::stoll(digits);
  }
  return static_cast<double>(whole) + static_cast<double>(nanos) * 1e-9;
}

std::string FormatKittiRawTimestamp(double unix_seconds) {
  Require(std::isfinite(unix_seconds), "WriteKittiRawTimestamps: timestamps must be finite");
  long long whole = static_cast<long long>(std::floor(unix_seconds));
  long long nanos = std::llround((unix_seconds - static_cast<double>(whole)) * 1e9);
  if (nanos >= 1000000000LL) {
    whole += 1;
    nanos -= 1000000000LL;
  }
  using namespace std::chrono;
  const long long days = (whole >= 0 ? whole : whole - 86399) / 86400;
  const long long in_day = whole - days * 86400;
  const year_month_day date{sys_days{std::chrono::days{days}}};
  return fmt::format("{:04d}-{:02d}-{:02d} {:02d}:{:02d}:{:02d}.{:09d}", static_cast<int>(date.year()),
                     static_cast<unsigned>(date.month()), static_cast<unsigned>(date.day()), in_day / 3600,
                     (in_day / 60) % 60, in_day % 60, nanos);
}

}  // namespace

OxtsRecord ParseOxtsLine(const std::string& line, const SourceLocation& where) {
  const auto tokens = SplitTokens(line);
  if (tokens.size() != OxtsRecord::kNumFields) {
    throw InputError(where, "fields",
                     fmt::format("expected {} values (lat lon alt roll pitch yaw ... orimode), found {}",
                                 OxtsRecord::kNumFields, tokens.size()));
  }
  OxtsRecord record;
  const auto doubles = DoubleFields(record);
  for (size_t i = 0; i < doubles.size(); ++i) *doubles[i] = ParseDouble(tokens[i], where, kOxtsFieldNames[i]);
  const auto ints = IntFields(record);
  for (size_t i = 0; i < ints.size(); ++i) {
    const size_t k = doubles.size() + i;
    // Some tools write the status fields as floats ("4.0"); accept integral values.
    const double value = ParseDouble(tokens[k], where, kOxtsFieldNames[k]);
    if (value != std::floor(value) || std::abs(value) > 1e9) {
      throw InputError(where, kOxtsFieldNames[k], fmt::format("'{}' is not an integer", tokens[k]));
    }
    *ints[i] = static_cast<int>(value);
  }
  if (std::abs(record.lat) > 90)
    throw InputError(where, "lat", fmt::format("{} is outside -90..90", record.lat));
  if (std::abs(record.lon) > 180)
    throw InputError(where, "lon", fmt::format("{} is outside -180..180", record.lon));
  return record;
}

std::string FormatOxtsLine(const OxtsRecord& record) {
  OxtsRecord copy = record;
  std::string line;
  for (const double* value : DoubleFields(copy)) {
    if (!line.empty()) line += ' ';
    // Shortest representation that reads back to the same double.
    line += fmt::format("{}", *value);
  }
  for (const int* value : IntFields(copy)) line += fmt::format(" {}", *value);
  return line;
}

std::vector<double> ReadKittiRawTimestamps(const fs::path& path) {
  std::vector<double> stamps;
  for (const auto& [line, where] : DataLines(path)) {
    const double t = ParseKittiRawTimestamp(line, where);
    if (!stamps.empty() && t < stamps.back()) {
      throw InputError(where, "timestamp", "goes back in time from the previous line");
    }
    stamps.push_back(t);
  }
  return stamps;
}

void WriteKittiRawTimestamps(const fs::path& path, const std::vector<double>& unix_seconds) {
  std::string text;
  text.reserve(unix_seconds.size() * 30);
  for (const double t : unix_seconds) text += FormatKittiRawTimestamp(t) + "\n";
  WriteFileAtomically(path, text);
}

std::vector<StampedOxts> ReadOxtsFolder(const fs::path& oxts_dir) {
  const std::vector<double> stamps = ReadKittiRawTimestamps(oxts_dir / "timestamps.txt");
  std::vector<StampedOxts> readings;
  readings.reserve(stamps.size());
  for (size_t i = 0; i < stamps.size(); ++i) {
    const fs::path file = OxtsDataFile(oxts_dir, i);
    const auto lines = DataLines(file);
    if (lines.size() != 1) {
      throw InputError(file, fmt::format("expected one line of {} values, found {} lines",
                                         OxtsRecord::kNumFields, lines.size()));
    }
    readings.push_back({stamps[i], ParseOxtsLine(lines[0].first, lines[0].second)});
  }
  std::error_code ec;
  if (fs::exists(OxtsDataFile(oxts_dir, stamps.size()), ec)) {
    throw InputError(oxts_dir / "timestamps.txt",
                     fmt::format("lists {} timestamps but data/ holds more records ({} exists)",
                                 stamps.size(), OxtsDataFile(oxts_dir, stamps.size()).filename().string()));
  }
  return readings;
}

void WriteOxtsFolder(const fs::path& oxts_dir, const std::vector<StampedOxts>& readings) {
  std::vector<double> stamps;
  stamps.reserve(readings.size());
  for (size_t i = 0; i < readings.size(); ++i) {
    WriteFileAtomically(OxtsDataFile(oxts_dir, i), FormatOxtsLine(readings[i].record) + "\n");
    stamps.push_back(readings[i].timestamp);
  }
  // Records left over from an earlier, longer write would no longer match timestamps.txt.
  std::error_code ec;
  for (size_t i = readings.size(); fs::exists(OxtsDataFile(oxts_dir, i), ec); ++i) {
    fs::remove(OxtsDataFile(oxts_dir, i), ec);
  }
  WriteKittiRawTimestamps(oxts_dir / "timestamps.txt", stamps);
}

std::vector<double> KittiRawCalibFile::Get(const std::string& key, size_t count) const {
  const auto it = values.find(key);
  if (it == values.end()) throw InputError(SourceLocation{file, 0}, key, "missing");
  if (it->second.size() != count) {
    const auto line = lines.find(key);
    throw InputError(SourceLocation{file, line == lines.end() ? 0 : line->second}, key,
                     fmt::format("expected {} numbers, found {}", count, it->second.size()));
  }
  return it->second;
}

Eigen::Matrix3d KittiRawCalibFile::GetRotation(const std::string& key) const {
  const std::vector<double> r = Get(key, 9);
  Eigen::Matrix3d rotation;
  for (int i = 0; i < 9; ++i) rotation(i / 3, i % 3) = r[static_cast<size_t>(i)];
  const std::optional<std::string> defect = RotationDefect(rotation);
  if (!defect) return rotation;
  const auto line = lines.find(key);
  throw InputError(SourceLocation{file, line == lines.end() ? 0 : line->second}, key,
                   "is not a rotation: " + *defect);
}

KittiRawCalibFile ReadKittiRawCalibFile(const fs::path& path) {
  TextReader reader(path);
  KittiRawCalibFile calib;
  calib.file = path;
  while (const auto line = reader.NextLine()) {
    const std::string_view text = Trim(*line);
    if (text.empty() || text.front() == '#') continue;
    const SourceLocation where = reader.Where();
    const size_t colon = text.find(':');
    if (colon == std::string_view::npos) throw InputError(where, "expected 'key: values'");
    const std::string key(Trim(text.substr(0, colon)));
    if (key == "calib_time") continue;  // a date, not numbers
    if (calib.values.count(key)) throw InputError(where, key, "given twice");
    std::vector<double> numbers;
    const auto tokens = SplitTokens(text.substr(colon + 1));
    for (size_t i = 0; i < tokens.size(); ++i) {
      numbers.push_back(ParseDouble(tokens[i], where, fmt::format("{}[{}]", key, i)));
    }
    calib.values.emplace(key, std::move(numbers));
    calib.lines.emplace(key, where.line);
  }
  return calib;
}

Rigid3d ReadKittiRawRigid(const fs::path& path) {
  const KittiRawCalibFile calib = ReadKittiRawCalibFile(path);
  const Eigen::Matrix3d rotation = calib.GetRotation("R");
  const std::vector<double> t = calib.Get("T", 3);
  Eigen::Matrix3x4d m;
  m.leftCols<3>() = rotation;
  for (int i = 0; i < 3; ++i) m(i, 3) = t[static_cast<size_t>(i)];
  return Rigid3d::FromMatrix(m);
}

std::vector<VelodynePoint> ReadVelodyneScan(const fs::path& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw InputError(path, "Velodyne scan not found");
  std::ifstream in(path, std::ios::binary);
  const std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (!in.eof() && in.fail()) throw InputError(path, "cannot read the Velodyne scan");
  constexpr size_t kPointBytes = 4 * sizeof(float);
  if (bytes.empty() || bytes.size() % kPointBytes != 0) {
    throw InputError(path, fmt::format("{} bytes: not a whole number of points (x y z reflectance, 16 bytes "
                                       "each)",
                                       bytes.size()));
  }
  std::vector<VelodynePoint> points(bytes.size() / kPointBytes);
  for (size_t i = 0; i < points.size(); ++i) {
    float v[4];
    std::memcpy(v, bytes.data() + i * kPointBytes, kPointBytes);
    for (const float x : v) {
      if (!std::isfinite(x)) {
        throw InputError(path,
                         fmt::format("point {} (byte {}) holds a non-finite value", i, i * kPointBytes));
      }
    }
    points[i].position = Eigen::Vector3d(v[0], v[1], v[2]);
    points[i].reflectance = v[3];
  }
  return points;
}

}  // namespace semslam
