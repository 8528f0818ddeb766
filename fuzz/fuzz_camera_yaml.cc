// Image folders' camera.yaml.
#include "fuzz_input.h"
#include "semslam/io/image_folder.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, size_t size) {
  const auto path = semslam::fuzz::WriteInput(data, size, "camera.yaml");
  semslam::fuzz::ExpectOnlyInputErrors([&] { (void)semslam::ReadCameraYaml(path); });
  return 0;
}
