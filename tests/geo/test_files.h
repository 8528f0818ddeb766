#pragma once
// Writing small input files for reader tests.

#include <filesystem>
#include <fstream>
#include <string>

namespace semslam::testing {

inline std::filesystem::path WriteText(const std::filesystem::path& path, const std::string& text) {
  std::filesystem::create_directories(path.parent_path());
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

}  // namespace semslam::testing
