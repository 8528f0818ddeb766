#pragma once
// Reads the images of each frame for a run, skipping bad ones: a frame whose image is missing, empty,
// truncated, undecodable or of another size than the sequence's is skipped with one warning naming the file,
// and counted. More than max_bad_in_row bad frames in a row mean the sequence itself is broken (a disk that
// went away, a folder being overwritten): TooManyInRow() then tells the run to stop and save its work.

#include <cstddef>
#include <opencv2/core/mat.hpp>
#include <optional>
#include <string>
#include <vector>

namespace semslam {

class ImageSequence;

struct FrameImages {
  cv::Mat left;   // grey, for tracking
  cv::Mat right;  // empty unless stereo
  cv::Mat color;  // the left image in colour (8-bit BGR) when asked for and the camera has colour, else empty
};

struct BadFrame {
  size_t frame = 0;
  std::string reason;  // the reader's message, naming the file
};

class FrameReader {
 public:
  // max_bad_in_row: how many bad frames in a row are tolerated (0: none). color: keep the left image in
  // colour too (for the segmenter) when the sequence has colour; it is decoded once and converted to grey.
  FrameReader(const ImageSequence& sequence, bool stereo, size_t max_bad_in_row, bool color = false);

  // The frame's images, or nullopt when one of them cannot be used (warned and counted).
  std::optional<FrameImages> Read(size_t frame);

  bool TooManyInRow() const { return bad_in_row_ > max_bad_in_row_; }
  size_t bad_in_row() const { return bad_in_row_; }
  const std::vector<BadFrame>& bad_frames() const { return bad_frames_; }

 private:
  const ImageSequence& sequence_;
  bool stereo_;
  bool color_;
  size_t max_bad_in_row_;
  size_t bad_in_row_ = 0;
  std::vector<BadFrame> bad_frames_;
};

}  // namespace semslam
