#pragma once
// Sequences made of another one's frames in another order: a drive played forwards and backwards as one
// (it revisits every place, and the camera turns around), cut hard (frames left out: the camera jumps), or
// blacked out for a while (the camera sees nothing). They test what no recorded drive holds: losing
// tracking, starting new maps and merging them. The result is an image folder with camera.yaml (see
// image_folder.h): the images, times at the source's frame rate, and the ground truth when the source has
// one.

#include <cstddef>
#include <filesystem>
#include <string_view>
#include <vector>

#include "semslam/io/sequence.h"

namespace semslam {

// One frame of a composed sequence: a frame of the source, or a black image.
struct ComposedFrame {
  size_t source_frame = 0;
  bool black = false;
};

// Parses a frame list: comma-separated ranges "A-B" (inclusive; A > B runs backwards) or single frames,
// e.g. "0-159,158-0,1-159", of a source with `frame_count` frames. Throws InvalidArgument naming the bad
// part, or a frame the source does not have (before a range is expanded).
std::vector<size_t> ParseFrameList(std::string_view text, size_t frame_count);

// The composed frames: `frames` in order, with those at composed positions [black_first, black_end)
// black.
std::vector<ComposedFrame> ComposeFrames(const std::vector<size_t>& frames, size_t black_first = 0,
                                         size_t black_end = 0);

// Writes the composed sequence into `out` (created; it must be empty or missing): images (left, and right
// when `stereo` and the source has a second camera), times.txt (at the source's frame rate; a jump over k
// source frames takes k intervals), gt.txt (KITTI poses in the source's frame, when the source has a
// ground truth), labels and depth (when the source has them; a black frame's labels are 255, "ignore", and
// its depth 0) and camera.yaml. Throws InputError for frames the source does not have, or whose label or
// depth image is missing, and Interrupted at Ctrl-C (core/interrupt.h); a compose that does not finish leaves
// `out` as it found it.
void WriteComposedSequence(const ImageSequence& source, const std::vector<ComposedFrame>& frames,
                           const std::filesystem::path& out, bool stereo, bool show_progress = false);

}  // namespace semslam
