#pragma once
// SLAM options from a YAML file (`semslam run --config FILE`), and back to YAML (written beside a run's
// outputs so that every run records the options it used). See config/default.yaml for every key.

#include <filesystem>
#include <string>

#include "semslam/system/slam_system.h"

namespace semslam {

// Overrides the options named in `file`; keys it does not name keep their value. Throws InputError naming the
// file, line and key for an unknown key, a value of the wrong type, or a value its option rejects.
void ApplySlamConfig(const std::filesystem::path& file, SlamOptions* options);

// The options as YAML, in the format ApplySlamConfig reads.
std::string SlamConfigToYaml(const SlamOptions& options);

}  // namespace semslam
