// SLAM configuration files (--config, config/default.yaml).
#include "fuzz_input.h"
#include "semslam/system/slam_config.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, size_t size) {
  const auto path = semslam::fuzz::WriteInput(data, size, "config.yaml");
  semslam::fuzz::ExpectOnlyInputErrors([&] {
    semslam::SlamOptions options;
    semslam::ApplySlamConfig(path, &options);
    (void)semslam::SlamConfigToYaml(options);
  });
  return 0;
}
