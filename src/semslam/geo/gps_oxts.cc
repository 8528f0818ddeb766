// KITTI oxts GPS input (through io's reader) and the format dispatch. Kept apart from gps.cc so that the CSV
// and NMEA readers do not pull the io module in.

#include <fmt/format.h>

#include <cctype>
#include <fstream>

#include "semslam/geo/gps.h"
#include "semslam/geo/gps_internal.h"
#include "semslam/io/kitti_raw.h"

namespace semslam {

namespace fs = std::filesystem;
using gps_internal::FixCollector;

namespace {

fs::path FindOxtsFolder(const fs::path& path) {
  for (const fs::path& candidate : {path, path / "oxts"}) {
    if (fs::is_regular_file(candidate / "timestamps.txt") && fs::is_directory(candidate / "data"))
      return candidate;
  }
  throw InputError(path, "not a KITTI oxts folder (expected timestamps.txt and data/, here or under oxts/)");
}

}  // namespace

GpsLog ReadGpsOxts(const fs::path& path, const GpsReadOptions& options) {
  options.Check();
  const fs::path dir = FindOxtsFolder(path);
  GpsLog log;
  log.source = dir;
  log.format = "oxts";
  FixCollector collector(log, options);
  const std::vector<StampedOxts> readings = ReadOxtsFolder(dir);
  for (size_t i = 0; i < readings.size(); ++i) {
    const OxtsRecord& r = readings[i].record;
    GpsFix fix;
    fix.timestamp = readings[i].timestamp;
    fix.position = Wgs84{r.lat, r.lon, r.alt};
    fix.sigma_m =
        options.oxts_use_pos_accuracy && r.pos_accuracy > 0 ? r.pos_accuracy : options.default_sigma_m;
    fix.source = SourceLocation{dir / "data" / fmt::format("{:010d}.txt", i), 1};
    collector.Add(std::move(fix));
  }
  return log;
}

GpsLog ReadGps(const fs::path& path, const GpsReadOptions& options) {
  if (fs::is_directory(path)) return ReadGpsOxts(path, options);
  std::string extension = path.extension().string();
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (extension == ".kml") return ReadGpsKml(path, options);
  std::ifstream stream(path);
  if (!stream) throw InputError(path, "cannot open the GPS file");
  char c = 0;
  while (stream.get(c)) {
    if (c == ' ' || c == '\t' || c == '\r' || c == '\n') continue;
    break;
  }
  if (stream && c == '$') return ReadGpsNmea(path, options);
  return ReadGpsCsv(path, options);
}

}  // namespace semslam
