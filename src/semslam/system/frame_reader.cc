#include "semslam/system/frame_reader.h"

#include <spdlog/spdlog.h>

#include "semslam/core/error.h"
#include "semslam/io/sequence.h"

namespace semslam {

FrameReader::FrameReader(const ImageSequence& sequence, bool stereo, size_t max_bad_in_row, bool color)
    : sequence_(sequence),
      stereo_(stereo),
      color_(color && sequence.IsColor()),
      max_bad_in_row_(max_bad_in_row) {}

std::optional<FrameImages> FrameReader::Read(size_t frame) {
  try {
    FrameImages images;
    if (color_) {
      images.color = sequence_.LoadColorImage(frame);
      images.left = GreyFromColor(images.color);
    } else {
      images.left = sequence_.LoadImage(frame, 0);
    }
    if (stereo_) images.right = sequence_.LoadImage(frame, 1);
    bad_in_row_ = 0;
    return images;
  } catch (const InputError& e) {
    spdlog::warn("frame {} skipped: {}", frame, e.what());
    bad_frames_.push_back({frame, e.what()});
    ++bad_in_row_;
    return std::nullopt;
  }
}

}  // namespace semslam
