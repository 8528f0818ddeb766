// KITTI raw: one oxts record per line (30 fields) and the calib_*.txt key: numbers files.
#include <string>

#include "fuzz_input.h"
#include "semslam/io/kitti_raw.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, size_t size) {
  const std::string_view text = semslam::fuzz::AsText(data, size);
  int line_number = 0;
  for (size_t begin = 0; begin <= text.size();) {
    size_t end = text.find('\n', begin);
    if (end == std::string_view::npos) end = text.size();
    const std::string line(text.substr(begin, end - begin));
    ++line_number;
    semslam::fuzz::ExpectOnlyInputErrors(
        [&] { (void)semslam::ParseOxtsLine(line, semslam::SourceLocation{"oxts.txt", line_number}); });
    begin = end + 1;
  }
  const auto path = semslam::fuzz::WriteInput(data, size, "calib_cam_to_cam.txt");
  semslam::fuzz::ExpectOnlyInputErrors([&] {
    const semslam::KittiRawCalibFile calib = semslam::ReadKittiRawCalibFile(path);
    (void)calib.Get("P_rect_00", 12);
  });
  semslam::fuzz::ExpectOnlyInputErrors([&] { (void)semslam::ReadKittiRawRigid(path); });
  return 0;
}
