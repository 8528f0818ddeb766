// GPS logs as NMEA 0183 (GGA fixes, RMC dates).
#include "fuzz_input.h"
#include "semslam/geo/gps.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, size_t size) {
  const auto path = semslam::fuzz::WriteInput(data, size, "gps.nmea");
  semslam::GpsReadOptions options;
  options.nmea_require_checksum = size % 2 == 0;  // both ways, or checksums would hide everything else
  semslam::fuzz::ExpectOnlyInputErrors([&] { (void)semslam::ReadGpsNmea(path, options); });
  return 0;
}
