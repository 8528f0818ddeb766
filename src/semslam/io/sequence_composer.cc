#include "semslam/io/sequence_composer.h"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <opencv2/core.hpp>

#include "semslam/core/atomic_file.h"
#include "semslam/core/error.h"
#include "semslam/core/interrupt.h"
#include "semslam/core/progress.h"
#include "semslam/io/image_folder.h"
#include "semslam/io/trajectory_io.h"

namespace semslam {
namespace fs = std::filesystem;
namespace {

size_t ParseFrame(std::string_view text, std::string_view part, size_t frame_count) {
  size_t value = 0;
  const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  Require(!text.empty() && ec == std::errc() && ptr == text.data() + text.size(),
          fmt::format("frame list: '{}' in '{}' is not a frame number or a range A-B", text, part));
  Require(
      value < frame_count,
      fmt::format("frame list: the sequence has no frame {} (in '{}'; {})", value, part,
                  frame_count == 0 ? "it has none" : fmt::format("its frames are 0 to {}", frame_count - 1)));
  return value;
}

// The source's frame interval: the median difference of its timestamps (0.1 s when it has one frame).
double FrameInterval(const ImageSequence& source) {
  std::vector<double> steps;
  for (size_t i = 1; i < source.size(); ++i) steps.push_back(source.Timestamp(i) - source.Timestamp(i - 1));
  if (steps.empty()) return 0.1;
  std::nth_element(steps.begin(), steps.begin() + static_cast<long>(steps.size() / 2), steps.end());
  const double step = steps[steps.size() / 2];
  return step > 0 ? step : 0.1;
}

// The ground-truth pose of each source frame (by timestamp), when the source has a ground truth for all of
// them.
std::optional<std::vector<Rigid3d>> TruthByFrame(const ImageSequence& source) {
  const std::optional<Trajectory> truth = source.GroundTruth();
  if (!truth || truth->empty()) return std::nullopt;
  std::vector<Rigid3d> poses;
  for (size_t i = 0; i < source.size(); ++i) {
    const double t = source.Timestamp(i);
    const auto it = std::lower_bound(truth->begin(), truth->end(), t - 1e-4,
                                     [](const StampedPose& p, double value) { return p.timestamp < value; });
    if (it == truth->end() || std::abs(it->timestamp - t) > 1e-4) return std::nullopt;
    poses.push_back(it->world_from_camera);
  }
  return poses;
}

// Cityscapes' "ignore" id: a black frame's labels say nothing was seen. Its depth is 0, "no depth".
constexpr double kNoLabel = 255.0;

// The source's label or depth image of `frame`, from a folder of per-frame images named by frame index (as
// the synthetic city writes them), unchanged (8-bit labels, 16-bit depth). Throws InputError naming the file.
cv::Mat LoadFrameImage(const fs::path& dir, size_t frame, std::string_view what) {
  const fs::path path = dir / fmt::format("{:06d}.png", frame);
  std::error_code ec;
  if (!fs::is_regular_file(path, ec))
    throw InputError(path, fmt::format("compose: the {} image of frame {} is missing", what, frame));
  return ReadImageUnchanged(path);
}

// WriteComposedSequence's writing, into a folder it has checked.
void WriteComposedFrames(const ImageSequence& source, const std::vector<ComposedFrame>& frames,
                         const fs::path& out, bool stereo, bool show_progress) {
  fs::create_directories(out / "left");
  if (stereo) fs::create_directories(out / "right");
  // The synthetic city's per-frame labels and depth go along, so that a composed drive can be segmented
  // (`--segmenter truth-noisy:RATE`) and its labels measured as the source's.
  const std::optional<fs::path> labels = source.LabelDirectory(), depth = source.DepthDirectory();
  if (labels) fs::create_directories(out / "labels");
  if (depth) fs::create_directories(out / "depth");

  const double dt = FrameInterval(source);
  const std::optional<std::vector<Rigid3d>> truth = TruthByFrame(source);
  std::string times, poses;
  double time = 0.0;
  std::vector<Rigid3d> truth_out;
  ProgressReporter progress("compose", frames.size(), show_progress);
  for (size_t i = 0; i < frames.size(); ++i) {
    if (InterruptRequested()) {
      throw Interrupted(InterruptSignal(),
                        fmt::format("compose: interrupted by {} after {} of {} frames; {} is left as it was",
                                    InterruptName(), i, frames.size(), out.string()));
    }
    const ComposedFrame& f = frames[i];
    const std::string name = fmt::format("{:06d}.png", i);
    for (int camera = 0; camera < (stereo ? 2 : 1); ++camera) {
      cv::Mat image = source.LoadImage(f.source_frame, camera);
      if (f.black) image = cv::Mat::zeros(image.size(), image.type());
      WritePng(out / (camera == 0 ? "left" : "right") / name, image);
    }
    if (labels) {
      cv::Mat label = LoadFrameImage(*labels, f.source_frame, "label");
      if (f.black) label.setTo(cv::Scalar::all(kNoLabel));
      WritePng(out / "labels" / name, label);
    }
    if (depth) {
      cv::Mat metres = LoadFrameImage(*depth, f.source_frame, "depth");
      if (f.black) metres.setTo(cv::Scalar::all(0));
      WritePng(out / "depth" / name, metres);
    }
    // A jump of k source frames takes k frame intervals, as frames dropped by a camera would.
    if (i > 0) {
      const size_t previous = frames[i - 1].source_frame;
      const size_t jump = f.source_frame > previous ? f.source_frame - previous : previous - f.source_frame;
      time += dt * static_cast<double>(std::max<size_t>(1, jump));
    }
    times += fmt::format("{:.6f}\n", time);
    // The source's own frame, not one re-based on the first composed frame: drives composed from one source
    // then share it, as a merged map measured with one alignment needs.
    if (truth) truth_out.push_back((*truth)[f.source_frame]);
    progress.Update(i + 1, "");
  }
  progress.Finish(fmt::format("{} frames", frames.size()));
  WriteFileAtomically(out / "times.txt", times);
  CameraYaml yaml;
  yaml.camera = source.camera();
  yaml.images = out / "left";
  yaml.times = out / "times.txt";
  yaml.name = source.name() + "-composed";
  if (stereo) {
    yaml.baseline = source.stereo()->baseline;
    yaml.right_images = out / "right";
  }
  if (labels) yaml.labels = out / "labels";
  if (depth) yaml.depth = out / "depth";
  if (truth) {
    WriteKittiPoses(out / "gt.txt", truth_out);
    yaml.ground_truth = out / "gt.txt";
  }
  WriteCameraYaml(out / "camera.yaml", yaml);
}

}  // namespace

std::vector<size_t> ParseFrameList(std::string_view text, size_t frame_count) {
  std::vector<size_t> frames;
  size_t start = 0;
  while (start <= text.size()) {
    const size_t comma = std::min(text.find(',', start), text.size());
    const std::string_view part = text.substr(start, comma - start);
    Require(!part.empty(), fmt::format("frame list '{}' has an empty part", text));
    const size_t dash = part.find('-');
    if (dash == std::string_view::npos) {
      frames.push_back(ParseFrame(part, text, frame_count));
    } else {
      const size_t a = ParseFrame(part.substr(0, dash), text, frame_count),
                   b = ParseFrame(part.substr(dash + 1), text, frame_count);
      if (a <= b) {
        for (size_t f = a; f <= b; ++f) frames.push_back(f);
      } else {
        for (size_t f = a + 1; f-- > b;) frames.push_back(f);
      }
    }
    start = comma + 1;
  }
  return frames;
}

std::vector<ComposedFrame> ComposeFrames(const std::vector<size_t>& frames, size_t black_first,
                                         size_t black_end) {
  std::vector<ComposedFrame> composed;
  for (size_t i = 0; i < frames.size(); ++i)
    composed.push_back({frames[i], i >= black_first && i < black_end});
  return composed;
}

void WriteComposedSequence(const ImageSequence& source, const std::vector<ComposedFrame>& frames,
                           const fs::path& out, bool stereo, bool show_progress) {
  Require(!frames.empty(), "compose: no frames");
  for (const ComposedFrame& f : frames) {
    if (f.source_frame >= source.size()) {
      const std::string range =
          source.size() == 0 ? "it has none" : fmt::format("its frames are 0 to {}", source.size() - 1);
      throw InputError(source.directory(),
                       fmt::format("compose: the sequence has no frame {} ({})", f.source_frame, range));
    }
  }
  std::error_code ec;
  if (fs::exists(out, ec) && !fs::is_directory(out, ec))
    throw InputError(out, "compose: the output folder is a file");
  if (fs::exists(out, ec) && !fs::is_empty(out, ec))
    throw InputError(out, "compose: the output folder is not empty");
  // The folder was new or empty: a compose that does not finish leaves it so.
  const bool created = !fs::exists(out, ec);
  try {
    WriteComposedFrames(source, frames, out, stereo && source.stereo().has_value(), show_progress);
  } catch (...) {
    if (created) {
      fs::remove_all(out, ec);
    } else {
      for (const auto& entry : fs::directory_iterator(out, ec)) fs::remove_all(entry.path(), ec);
    }
    throw;
  }
}

}  // namespace semslam
