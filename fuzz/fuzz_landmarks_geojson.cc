// Landmark catalogues as GeoJSON (FeatureCollection or Feature of Points).
#include "fuzz_input.h"
#include "semslam/landmarks/catalogue.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, size_t size) {
  const auto path = semslam::fuzz::WriteInput(data, size, "landmarks.geojson");
  semslam::fuzz::ExpectOnlyInputErrors([&] { (void)semslam::ReadLandmarks(path); });
  return 0;
}
