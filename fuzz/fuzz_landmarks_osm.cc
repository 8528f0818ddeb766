// OpenStreetMap extracts (.osm XML): the landmark catalogue with its street corners, and the streets.
#include "fuzz_input.h"
#include "semslam/landmarks/catalogue.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, size_t size) {
  const auto path = semslam::fuzz::WriteInput(data, size, "landmarks.osm");
  semslam::fuzz::ExpectOnlyInputErrors([&] { (void)semslam::ReadLandmarks(path); });
  semslam::fuzz::ExpectOnlyInputErrors([&] { (void)semslam::ReadStreetsOsm(path); });
  return 0;
}
