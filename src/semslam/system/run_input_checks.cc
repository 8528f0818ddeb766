#include "semslam/system/run_input_checks.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "semslam/core/error.h"
#include "semslam/core/utf8.h"

namespace semslam {

namespace fs = std::filesystem;

void RequireUtf8Argument(const fs::path& path, std::string_view what) {
  if (path.empty()) return;
  RequireUtf8Path(path, what);
  std::error_code ec;
  const fs::path absolute = fs::absolute(path, ec);
  if (!ec) RequireUtf8Path(absolute, what);
}

void CheckGpsLog(const GpsLog& log, const std::vector<double>& frame_times) {
  if (log.fixes.empty()) {
    if (log.skipped.empty()) throw InputError(log.source, "the GPS log holds no fix");
    const SkippedFix& first = log.skipped.front();
    throw InputError(log.source, fmt::format("no usable GPS fix: all {} were skipped (the first at {}: {})",
                                             log.skipped.size(), first.where.ToString(), first.reason));
  }
  if (frame_times.empty()) return;
  const double offset = GuessTimeOffset(log.fixes, frame_times);
  const double begin = log.fixes.front().timestamp, end = log.fixes.back().timestamp;
  const double slack = 1.0;
  const bool overlap = std::any_of(frame_times.begin(), frame_times.end(), [&](double t) {
    return t + offset >= begin - slack && t + offset <= end + slack;
  });
  // Clock times on both sides (after 1973) that do not overlap: the guess that they start together is
  // likely wrong (a log of another recording, or of another day).
  constexpr double kClockTime = 1e8;
  if (offset != 0.0 && begin > kClockTime && frame_times.front() > kClockTime) {
    spdlog::warn(
        "{}: the GPS fixes ({:.3f}..{:.3f} s) and the frames ({:.3f}..{:.3f} s) are both clock times but do "
        "not overlap; assumed to start together (offset {:.3f} s). Is the log of this recording?",
        log.source.string(), begin, end, frame_times.front(), frame_times.back(), offset);
  }
  if (!overlap) {
    spdlog::warn(
        "{}: the GPS fixes ({:.3f}..{:.3f} s) do not overlap the frames ({:.3f}..{:.3f} s, offset "
        "{:.3f} s): no fix can be matched to a frame, and the map will not be georeferenced",
        log.source.string(), begin, end, frame_times.front() + offset, frame_times.back() + offset, offset);
  }
}

double HorizontalDistanceM(const Wgs84& a, const Wgs84& b) {
  constexpr double kRadiusM = 6371008.8;
  constexpr double kDeg = std::numbers::pi / 180.0;
  const double dlat = (b.latitude_deg - a.latitude_deg) * kDeg;
  const double dlon = (b.longitude_deg - a.longitude_deg) * kDeg;
  const double h = std::sin(dlat / 2) * std::sin(dlat / 2) + std::cos(a.latitude_deg * kDeg) *
                                                                 std::cos(b.latitude_deg * kDeg) *
                                                                 std::sin(dlon / 2) * std::sin(dlon / 2);
  return 2 * kRadiusM * std::asin(std::min(1.0, std::sqrt(h)));
}

size_t WarnAboutFarLandmarks(const std::vector<Landmark>& landmarks, const fs::path& file,
                             const std::optional<GpsLog>& gps, double far_m) {
  if (landmarks.empty()) return 0;
  if (!gps || gps->fixes.empty()) {
    spdlog::warn("{}: landmarks are placed in the map through GPS; without --gps the catalogue is not used",
                 file.string());
    return 0;
  }
  // A few hundred fixes along the drive are enough to tell "near" from "thousands of km away".
  const size_t step = std::max<size_t>(1, gps->fixes.size() / 500);
  struct Far {
    const Landmark* landmark;
    double distance_m;
  };
  std::vector<Far> far;
  for (const Landmark& landmark : landmarks) {
    double nearest = std::numeric_limits<double>::infinity();
    for (size_t i = 0; i < gps->fixes.size(); i += step) {
      nearest = std::min(nearest, HorizontalDistanceM(landmark.position, gps->fixes[i].position));
    }
    nearest = std::min(nearest, HorizontalDistanceM(landmark.position, gps->fixes.back().position));
    if (nearest > far_m) far.push_back({&landmark, nearest});
  }
  if (far.empty()) return 0;
  std::sort(far.begin(), far.end(), [](const Far& a, const Far& b) { return a.distance_m < b.distance_m; });
  std::string examples;
  for (size_t i = 0; i < std::min<size_t>(far.size(), 3); ++i) {
    examples += fmt::format("{}'{}' ({}) {:.0f} km", i > 0 ? ", " : "", far[i].landmark->name,
                            far[i].landmark->source.ToString(), far[i].distance_m / 1e3);
  }
  if (far.size() == landmarks.size()) {
    spdlog::warn(
        "{}: none of the {} landmarks lies within {:.0f} km of the GPS track (nearest: {}); a catalogue "
        "of another place, or latitude and longitude swapped?",
        file.string(), landmarks.size(), far_m / 1e3, examples);
  } else {
    spdlog::warn(
        "{}: {} of the {} landmarks lie more than {:.0f} km from the GPS track and will match nothing: {}",
        file.string(), far.size(), landmarks.size(), far_m / 1e3, examples);
  }
  return far.size();
}

}  // namespace semslam
