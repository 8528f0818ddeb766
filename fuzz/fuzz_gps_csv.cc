// GPS logs as CSV (t,lat,lon[,alt,sigma], optional header).
#include "fuzz_input.h"
#include "semslam/geo/gps.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, size_t size) {
  const auto path = semslam::fuzz::WriteInput(data, size, "gps.csv");
  semslam::fuzz::ExpectOnlyInputErrors([&] {
    const semslam::GpsLog log = semslam::ReadGpsCsv(path);
    if (!log.fixes.empty()) (void)semslam::MakeEnuFrame(log);
  });
  return 0;
}
