#pragma once
// Shared by the GPS readers (not part of the API).

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>

#include "semslam/geo/gps.h"

namespace semslam::gps_internal {

// Validates a fix and appends it to the log or to its skipped list.
class FixCollector {
 public:
  FixCollector(GpsLog& log, const GpsReadOptions& options) : log_(log), options_(options) {}

  void Skip(const SourceLocation& where, std::string reason) {
    log_.skipped.push_back({where, std::move(reason)});
  }

  void Add(GpsFix fix) {
    const SourceLocation& where = fix.source;
    const Wgs84& p = fix.position;
    if (!std::isfinite(fix.timestamp)) return Skip(where, "time is not a finite number");
    // Time order is checked against the previous record with a finite time (accepted or not: a record that
    // goes back in time is out of order even when the one before it was rejected for its position) and
    // against the last accepted fix (the log stays strictly increasing).
    const std::optional<double> previous_record = previous_time_;
    previous_time_ = fix.timestamp;
    if (previous_record && fix.timestamp <= *previous_record) {
      return Skip(where, fmt::format("time {:.6f} is not after the previous record's {:.6f} (non-monotonic)",
                                     fix.timestamp, *previous_record));
    }
    if (!std::isfinite(p.latitude_deg) || !std::isfinite(p.longitude_deg) || !std::isfinite(p.altitude_m)) {
      return Skip(where, "position is not finite (NaN or infinite)");
    }
    if (std::abs(p.latitude_deg) > 90.0)
      return Skip(where, fmt::format("latitude {} out of range", p.latitude_deg));
    if (std::abs(p.longitude_deg) > 180.0) {
      return Skip(where, fmt::format("longitude {} out of range", p.longitude_deg));
    }
    if (p.altitude_m < options_.min_altitude_m || p.altitude_m > options_.max_altitude_m) {
      return Skip(where, fmt::format("altitude {} m out of range", p.altitude_m));
    }
    if (!std::isfinite(fix.sigma_m) || fix.sigma_m <= 0) {
      return Skip(where, fmt::format("sigma {} is not a positive number", fix.sigma_m));
    }
    if (!log_.fixes.empty() && fix.timestamp <= log_.fixes.back().timestamp) {
      return Skip(where, fmt::format("time {:.6f} is not after the previous fix's {:.6f} (non-monotonic)",
                                     fix.timestamp, log_.fixes.back().timestamp));
    }
    fix.sigma_m = std::max(fix.sigma_m, options_.min_sigma_m);
    log_.fixes.push_back(std::move(fix));
  }

 private:
  GpsLog& log_;
  const GpsReadOptions& options_;
  std::optional<double> previous_time_;
};

}  // namespace semslam::gps_internal
