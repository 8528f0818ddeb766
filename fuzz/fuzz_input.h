#pragma once
// Shared by the fuzz targets: semslam's readers take file paths, so each input is written to a file of its own
// (in a per-process temporary folder, on tmpfs when /dev/shm is there) and read back through the real reader.
//
// A reader may refuse any input, but only the way semslam refuses bad input: InputError (naming the file) or
// InvalidArgument. Anything else escaping a reader (a raw nlohmann or yaml-cpp exception, std::out_of_range,
// ...) is a defect: it is left uncaught, and libFuzzer reports it with the input that caused it.

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>

#include "semslam/core/error.h"

namespace semslam::fuzz {

inline const std::filesystem::path& WorkDir() {
  static const std::filesystem::path dir = [] {
    const std::filesystem::path base =
        std::filesystem::is_directory("/dev/shm") ? "/dev/shm" : std::filesystem::temp_directory_path();
    const std::filesystem::path d = base / ("semslam-fuzz-" + std::to_string(::getpid()));
    std::filesystem::create_directories(d);
    std::atexit([] {
      std::error_code ec;
      std::filesystem::remove_all(WorkDir(), ec);
    });
    return d;
  }();
  return dir;
}

// Writes the bytes to WorkDir()/name and returns the path.
inline std::filesystem::path WriteInput(const std::uint8_t* data, size_t size, const std::string& name) {
  const std::filesystem::path path = WorkDir() / name;
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  return path;
}

inline std::string_view AsText(const std::uint8_t* data, size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

// Runs `read` and lets only semslam's own input errors through.
template <typename Read>
void ExpectOnlyInputErrors(Read&& read) {
  try {
    read();
  } catch (const InputError&) {
  } catch (const InvalidArgument&) {
  }
}

}  // namespace semslam::fuzz
