// Trajectories: TUM (8 columns) or KITTI poses (12), told apart by the reader.
#include "fuzz_input.h"
#include "semslam/io/trajectory_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, size_t size) {
  const auto path = semslam::fuzz::WriteInput(data, size, "poses.txt");
  semslam::fuzz::ExpectOnlyInputErrors([&] { (void)semslam::ReadTrajectory(path, std::nullopt); });
  return 0;
}
