// Landmark catalogues as CSV (name,lat,lon[,alt,category], quoted fields, optional header).
#include "fuzz_input.h"
#include "semslam/landmarks/catalogue.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, size_t size) {
  const auto path = semslam::fuzz::WriteInput(data, size, "landmarks.csv");
  semslam::fuzz::ExpectOnlyInputErrors([&] {
    std::vector<semslam::Landmark> landmarks = semslam::ReadLandmarks(path);
    semslam::MakeLandmarkNamesUnique(landmarks);
  });
  return 0;
}
