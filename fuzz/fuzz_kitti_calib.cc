// KITTI odometry calib.txt (P0..P3, Tr).
#include "fuzz_input.h"
#include "semslam/io/kitti_odometry.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, size_t size) {
  const auto path = semslam::fuzz::WriteInput(data, size, "calib.txt");
  semslam::fuzz::ExpectOnlyInputErrors([&] {
    const semslam::KittiCalibration calibration = semslam::ReadKittiCalibration(path);
    (void)calibration.Stereo01(1241, 376);
  });
  return 0;
}
