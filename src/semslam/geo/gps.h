#pragma once
// GPS fixes: readers for KITTI oxts folders, CSV logs and NMEA GGA sentences, validation, matching to frame
// timestamps, and the ENU frame they are expressed in.
//
// Policy: a file that cannot be read as its format at all (missing, wrong column count, text where a CSV
// number belongs) throws InputError naming file, line and field. A single bad fix inside a readable file
// (NaN, latitude/longitude/altitude out of range, time not after the previous fix, bad NMEA checksum, no fix
// quality) is skipped and reported in GpsLog::skipped with its file:line; it is never fused.

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "semslam/core/error.h"
#include "semslam/geo/wgs84.h"
#include "semslam/geometry/eigen_types.h"

namespace semslam {

struct GpsFix {
  double timestamp =
      0.0;  // seconds, in the source's time base (oxts: Unix; NMEA: Unix UTC, see options; CSV: as given)
  Wgs84 position;         // altitude: height above the WGS84 ellipsoid when the source gives it
  double sigma_m = 1.0;   // 1-sigma position uncertainty, metres
  SourceLocation source;  // where the fix was read
};

// A fix that was read but not accepted.
struct SkippedFix {
  SourceLocation where;
  std::string reason;
};

struct GpsLog {
  std::vector<GpsFix> fixes;  // accepted fixes, strictly increasing in time
  std::vector<SkippedFix> skipped;
  std::filesystem::path source;
  std::string format;  // "oxts", "csv", "nmea" or "kml"
  // The log gives no times, one position per frame instead: each fix's timestamp is its frame number in the
  // sequence until TimeFixesByFrame gives it that frame's time.
  bool times_are_frames = false;
  std::vector<std::string> notes;  // what a reader or TimeFixesByFrame left out as a whole, for the log
};

struct GpsReadOptions {
  // Sigma of fixes whose source gives none (CSV without a sigma column).
  double default_sigma_m = 1.0;
  // Lower bound on any sigma (oxts pos_accuracy can be a few centimetres, far better than the fix really is).
  double min_sigma_m = 0.05;
  // oxts: use the record's pos_accuracy as sigma (else default_sigma_m).
  bool oxts_use_pos_accuracy = true;
  // NMEA: sigma = HDOP * nmea_uere_m (user equivalent range error).
  double nmea_uere_m = 2.5;
  // NMEA: sentences without "*hh" are skipped when true.
  bool nmea_require_checksum = true;
  // NMEA GGA carries only the UTC time of day. Timestamps are day_start + time of day, where day_start is
  // this value (Unix seconds of a UTC midnight) when given, else the date of the first valid RMC sentence,
  // else 0 (timestamps are then seconds since midnight). A time of day that jumps back by more than 12 h
  // rolls over to the next day.
  std::optional<double> nmea_day_start_unix;
  // Altitudes outside [min, max] metres are out of range.
  double min_altitude_m = -1000.0;
  double max_altitude_m = 20000.0;

  void Check() const;
};

// A KITTI raw oxts folder (timestamps.txt + data/%010d.txt), or a folder holding one as `oxts/`.
GpsLog ReadGpsOxts(const std::filesystem::path& path, const GpsReadOptions& options = {});
// CSV `t,lat,lon[,alt,sigma]`. An optional header line names the columns (t|time|timestamp, lat|latitude,
// lon|lng|longitude, alt|altitude|height, sigma|accuracy|std) in any order; without one the order is as
// above. Lines starting with '#' and blank lines are ignored. Empty alt/sigma fields take the defaults.
GpsLog ReadGpsCsv(const std::filesystem::path& file, const GpsReadOptions& options = {});
// NMEA 0183: GGA sentences (any talker) are fixes; RMC sentences only give the date. Other sentences are
// ignored. Altitude = MSL altitude + geoid separation (ellipsoidal height) when the separation is given.
GpsLog ReadGpsNmea(const std::filesystem::path& file, const GpsReadOptions& options = {});
// KML: the positions of a gx:Track (<when> with <gx:coord>) or of Placemarks with a <TimeStamp>, in Unix
// time; a document without times (a LineString's <coordinates>) gives one position per frame of the sequence,
// the k-th for frame k (times_are_frames). Sigma: default_sigma_m.
GpsLog ReadGpsKml(const std::filesystem::path& file, const GpsReadOptions& options = {});
// Gives the fixes of a log read with times_are_frames the times of their frames (`frame_times[k]`: frame k of
// the sequence); positions beyond the sequence are dropped (and noted). Nothing for a timed log.
void TimeFixesByFrame(GpsLog& log, const std::vector<double>& frame_times);
// "YYYY-MM-DDThh:mm:ss[.s][Z|+hh:mm|-hh:mm]" -> Unix seconds (UTC without a zone); nullopt when malformed.
std::optional<double> ParseIso8601Utc(std::string_view text);
// Any of the above: a directory is an oxts folder; a .kml file is KML; a file whose first non-blank character
// is '$' is NMEA; anything else is CSV.
GpsLog ReadGps(const std::filesystem::path& path, const GpsReadOptions& options = {});

// Logs the skipped fixes (the first `max_lines` of them, then a count) as warnings.
void LogSkippedFixes(const GpsLog& log, size_t max_lines = 10);

// The ENU frame of a log: around `origin` when given, else around the first fix. Throws InputError when
// there is neither.
EnuFrame MakeEnuFrame(const GpsLog& log, const std::optional<Wgs84>& origin = std::nullopt);
Points3d FixesToEnu(const std::vector<GpsFix>& fixes, const EnuFrame& frame);

// For each time in `times` (seconds, frame time base), the index of the fix nearest in time to
// time + time_offset_s, if it is within `tolerance_s`; nullopt otherwise. `fixes` must be time-ordered.
std::vector<std::optional<size_t>> MatchFixesToTimes(const std::vector<GpsFix>& fixes,
                                                     const std::vector<double>& times, double tolerance_s,
                                                     double time_offset_s = 0.0);

// The offset to add to frame times to reach the GPS time base: 0 when the two ranges overlap, else the
// difference of their starts (KITTI odometry times.txt starts at 0 while oxts times are Unix seconds; a
// recording whose frames and fixes start together).
double GuessTimeOffset(const std::vector<GpsFix>& fixes, const std::vector<double>& frame_times);

}  // namespace semslam
