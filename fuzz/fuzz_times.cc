// times.txt (one timestamp per line) and KITTI raw timestamps.txt ("2011-09-26 13:02:25.964389445").
#include "fuzz_input.h"
#include "semslam/io/kitti_raw.h"
#include "semslam/io/trajectory_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, size_t size) {
  const auto path = semslam::fuzz::WriteInput(data, size, "times.txt");
  semslam::fuzz::ExpectOnlyInputErrors([&] { (void)semslam::ReadTimes(path); });
  semslam::fuzz::ExpectOnlyInputErrors([&] { (void)semslam::ReadKittiRawTimestamps(path); });
  return 0;
}
