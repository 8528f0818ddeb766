// GPS tracks as KML (gx:Track, timed Placemarks, or an untimed LineString: one position per frame).
#include "fuzz_input.h"
#include "semslam/geo/gps.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, size_t size) {
  const auto path = semslam::fuzz::WriteInput(data, size, "gps.kml");
  semslam::fuzz::ExpectOnlyInputErrors([&] {
    semslam::GpsLog log = semslam::ReadGpsKml(path);
    semslam::TimeFixesByFrame(log, {0.0, 0.1, 0.2});
    if (!log.fixes.empty()) (void)semslam::MakeEnuFrame(log);
  });
  return 0;
}
