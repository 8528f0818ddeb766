// The map loader (map.semslam). Random bytes would almost never pass the file's checksum, so the input is the
// payload: the target wraps it in a valid header (magic, version, size, FNV-1a) and the loader then parses
// and checks the content itself (references, counts, finite numbers).
#include <string>

#include "fuzz_input.h"
#include "semslam/core/binary_io.h"
#include "semslam/map/map.h"
#include "semslam/map/map_file.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, size_t size) {
  const std::filesystem::path path = semslam::fuzz::WorkDir() / "map.semslam";
  semslam::WriteChecksummedFile(path, std::string_view("SEMSLMAP", 8), semslam::kMapFileVersion,
                                semslam::fuzz::AsText(data, size));
  semslam::fuzz::ExpectOnlyInputErrors([&] {
    semslam::Map map;
    (void)semslam::ReadMapFile(path, map);
  });
  return 0;
}
