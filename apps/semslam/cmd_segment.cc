// semslam segment: run a segmenter on images, write colourized labels, print JSON (class histogram; pixel
// accuracy and mIoU against ground truth when given).

#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "commands.h"
#include "semslam/core/atomic_file.h"
#include "semslam/core/error.h"
#include "semslam/core/interrupt.h"
#include "semslam/core/progress.h"
#include "semslam/core/timing.h"
#include "semslam/semantics/class_table.h"
#include "semslam/semantics/label_image_segmenter.h"
#include "semslam/semantics/segmenter.h"
#include "semslam/semantics/semantic_outputs.h"

namespace semslam::cli {
namespace {

namespace fs = std::filesystem;

struct SegmentArgs {
  std::string segmenter;
  std::vector<std::string> images;
  std::vector<std::string> truth;
  std::string truth_ids = "train";
  std::string out;
  std::uint64_t seed = 0;
  bool overlay = false;
};

bool IsImageFile(const fs::path& p) {
  std::string ext = p.extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".bmp" || ext == ".ppm" || ext == ".pgm";
}

std::vector<fs::path> ExpandImages(const std::vector<std::string>& args) {
  std::vector<fs::path> files;
  for (const std::string& arg : args) {
    const fs::path p(arg);
    if (fs::is_directory(p)) {
      std::vector<fs::path> in_dir;
      for (const auto& entry : fs::directory_iterator(p)) {
        if (entry.is_regular_file() && IsImageFile(entry.path())) in_dir.push_back(entry.path());
      }
      std::sort(in_dir.begin(), in_dir.end());
      if (in_dir.empty()) throw InputError(p, "no images in the folder");
      files.insert(files.end(), in_dir.begin(), in_dir.end());
    } else if (fs::is_regular_file(p)) {
      files.push_back(p);
    } else {
      throw InputError(p, "no such image file or folder");
    }
  }
  return files;
}

// The frame number in a file name such as 000123.png; `fallback` when the stem is not a number.
std::int64_t FrameIndexOf(const fs::path& image, std::int64_t fallback) {
  const std::string stem = image.stem().string();
  const auto digit = [](char c) { return c >= '0' && c <= '9'; };
  if (stem.empty() || stem.size() > 12 || !std::all_of(stem.begin(), stem.end(), digit)) return fallback;
  return std::stoll(stem);
}

// Ground truth for an image: in a folder, the file with the same stem, or the Cityscapes gtFine name of a
// leftImg8bit image.
fs::path FindTruth(const fs::path& truth_dir, const fs::path& image, bool label_ids) {
  const std::string stem = image.stem().string();
  std::vector<std::string> names;
  const std::string left = "_leftImg8bit";
  if (const size_t at = stem.rfind(left); at != std::string::npos) {
    names.push_back(stem.substr(0, at) + (label_ids ? "_gtFine_labelIds" : "_gtFine_labelTrainIds") + ".png");
  }
  names.push_back(stem + ".png");
  for (const std::string& name : names) {
    const fs::path candidate = truth_dir / name;
    if (fs::is_regular_file(candidate) && !fs::equivalent(candidate, image)) return candidate;
  }
  throw InputError(truth_dir / names.back(), "no ground truth for image " + image.string());
}

std::string EncodePng(const cv::Mat& image, const fs::path& for_path) {
  std::vector<std::uint8_t> bytes;
  if (!cv::imencode(".png", image, bytes, {cv::IMWRITE_PNG_COMPRESSION, 3})) {
    throw std::runtime_error("cannot encode " + for_path.string());
  }
  return std::string(bytes.begin(), bytes.end());
}

nlohmann::json Histogram(const ClassCounts& counts) {
  std::uint64_t total = 0;
  for (auto c : counts) total += c;
  nlohmann::json h = nlohmann::json::object();
  for (int c = 0; c <= kNumClasses; ++c) {
    const auto n = counts[static_cast<size_t>(c)];
    if (n == 0) continue;
    h[std::string(c < kNumClasses ? ClassKey(c) : "none")] =
        total ? static_cast<double>(n) / static_cast<double>(total) : 0.0;
  }
  return h;
}

void RunSegment(const SegmentArgs& args) {
  const std::vector<fs::path> images = ExpandImages(args.images);
  Require(args.truth_ids == "train" || args.truth_ids == "label", "--truth-ids must be 'train' or 'label'");
  const bool truth_label_ids = args.truth_ids == "label";

  // Ground truth: one folder (matched by name) or one file per image.
  std::vector<fs::path> truth_files;
  std::optional<fs::path> truth_dir;
  if (args.truth.size() == 1 && fs::is_directory(args.truth[0])) {
    truth_dir = fs::path(args.truth[0]);
  } else if (!args.truth.empty()) {
    for (const auto& t : args.truth) truth_files.emplace_back(t);
    Require(truth_files.size() == images.size(), "--truth lists " + std::to_string(truth_files.size()) +
                                                     " files for " + std::to_string(images.size()) +
                                                     " images");
  }

  SegmenterContext context;
  context.seed = args.seed;
  if (!images.empty()) {
    // auto picks its network by whether the images are colour (the first one tells).
    const cv::Mat first = cv::imread(images[0].string(), cv::IMREAD_UNCHANGED);
    context.colour_images = first.channels() >= 3;
  }
  if (truth_dir) {
    context.truth_label_dir = truth_dir;
  } else if (!images.empty() && images[0].parent_path().filename() == "image_0") {
    const fs::path labels = images[0].parent_path().parent_path() / "label_0";
    if (fs::is_directory(labels)) context.truth_label_dir = labels;
  }
  std::unique_ptr<Segmenter> segmenter = MakeSegmenter(args.segmenter, context);
  Require(segmenter != nullptr, "--segmenter none: nothing to do");

  const fs::path out_dir(args.out);
  ClassCounts histogram{};
  SegmentationScore total_score;
  std::vector<double> ms;
  nlohmann::json per_image = nlohmann::json::array();
  ProgressReporter progress("segment", images.size());
  // What this command wrote, removed again when it fails half-way: no label images without segment.json.
  std::vector<fs::path> written;
  try {
    for (size_t i = 0; i < images.size(); ++i) {
      const fs::path& path = images[i];
      const cv::Mat image = cv::imread(path.string(), cv::IMREAD_COLOR);
      if (image.empty()) throw InputError(path, "cannot decode the image");
      const Stopwatch watch;
      const Segmentation segmentation =
          segmenter->Segment(image, FrameIndexOf(path, static_cast<std::int64_t>(i)));
      const double elapsed = watch.ElapsedMs();
      ms.push_back(elapsed);
      const cv::Mat labels = segmentation.LabelsAtInputSize();
      const ClassCounts counts = CountLabels(labels);
      for (size_t c = 0; c < counts.size(); ++c) histogram[c] += counts[c];
      nlohmann::json entry = {{"image", path.string()}, {"ms", elapsed}};

      if (truth_dir || !truth_files.empty()) {
        const fs::path truth_path = truth_dir ? FindTruth(*truth_dir, path, truth_label_ids) : truth_files[i];
        cv::Mat truth = ReadLabelImage(truth_path);
        if (truth_label_ids) truth = LabelIdsToTrainIds(truth);
        cv::Mat predicted = labels;
        // A label image of another shape is another image's: scaling it would score the wrong pixels.
        const double aspect = static_cast<double>(labels.cols) / labels.rows,
                     truth_aspect = static_cast<double>(truth.cols) / truth.rows;
        if (std::abs(aspect / truth_aspect - 1.0) > 0.02) {
          throw InputError(truth_path,
                           fmt::format("the ground truth is {}x{} but {} is {}x{}: another shape", truth.cols,
                                       truth.rows, path.string(), labels.cols, labels.rows));
        }
        if (predicted.size() != truth.size()) {
          cv::resize(labels, predicted, truth.size(), 0, 0, cv::INTER_NEAREST);
        }
        SegmentationScore score;
        score.Add(predicted, truth);
        total_score.Add(predicted, truth);
        entry["truth"] = truth_path.string();
        entry["pixel_accuracy"] = score.PixelAccuracy();
        entry["mean_iou"] = score.MeanIou();
        entry["mean_iou_truth_classes"] = score.MeanIouOverTruthClasses();
      }
      if (!args.out.empty()) {
        const std::string stem = path.stem().string();
        const fs::path color_path = out_dir / (stem + "_labels.png");
        WriteFileAtomically(color_path,
                            EncodePng(ColorizeLabels(labels, args.overlay ? image : cv::Mat()), color_path));
        written.push_back(color_path);
        const fs::path ids_path = out_dir / (stem + "_trainids.png");
        WriteFileAtomically(ids_path, EncodePng(labels, ids_path));
        written.push_back(ids_path);
        entry["labels_png"] = color_path.string();
      }
      per_image.push_back(std::move(entry));
      if (i + 1 < images.size()) progress.Update(i + 1);
      if (InterruptRequested() && i + 1 < images.size()) {
        throw Interrupted(InterruptSignal(),
                          fmt::format("segment: interrupted by {} after {} of {} images; nothing kept",
                                      InterruptName(), i + 1, images.size()));
      }
    }
  } catch (...) {
    std::error_code ec;
    for (const fs::path& file : written) fs::remove(file, ec);
    throw;
  }
  progress.Finish();

  const TimingSummary timing = Summarize(ms);
  nlohmann::json result = {
      {"segmenter", segmenter->Describe()},
      {"images", images.size()},
      {"ms_per_image",
       {{"median", timing.median_ms},
        {"mean", timing.mean_ms},
        {"max", timing.max_ms},
        {"first", ms.empty() ? 0.0 : ms.front()}}},
      {"class_histogram", Histogram(histogram)},
  };
  if (total_score.pixels() > 0) {
    result["truth_pixels"] = total_score.pixels();
    result["pixel_accuracy"] = total_score.PixelAccuracy();
    result["mean_iou"] = total_score.MeanIou();
    result["mean_iou_truth_classes"] = total_score.MeanIouOverTruthClasses();
    nlohmann::json iou = nlohmann::json::object();
    for (int c = 0; c < kNumClasses; ++c) {
      if (const auto v = total_score.ClassIou(c)) iou[std::string(ClassKey(c))] = *v;
    }
    result["class_iou"] = iou;
  }
  result["per_image"] = per_image;
  const std::string text = result.dump(2) + "\n";
  if (!args.out.empty()) WriteFileAtomically(out_dir / "segment.json", text);
  std::fwrite(text.data(), 1, text.size(), stdout);
}

}  // namespace

void AddSegmentCommand(CLI::App& app) {
  auto args = std::make_shared<SegmentArgs>();
  auto* cmd = app.add_subcommand("segment", "Run a segmenter on images (and score it against ground truth)");
  cmd->add_option(
         "--segmenter", args->segmenter,
         "espnetv2:FILE.pth | sinet:FILE.pth | enet:FILE | onnx:CARD.yaml | labels:DIR | truth-noisy:RATE, with "
         "optional ,key=value settings (espnetv2/sinet: width=N, threads=N)")
      ->required();
  cmd->add_option("--images", args->images,
                  "Image files or folders (sorted); frame numbers come from the names")
      ->required();
  cmd->add_option(
      "--truth", args->truth,
      "Ground-truth trainId images: one folder (same names, or Cityscapes gtFine names) or one file per "
      "image");
  cmd->add_option("--truth-ids", args->truth_ids,
                  "What the ground truth holds: train (trainIds) or label (labelIds)")
      ->check(CLI::IsMember({"train", "label"}));
  cmd->add_option("--out", args->out,
                  "Folder for <name>_labels.png (colourized), <name>_trainids.png, segment.json");
  cmd->add_flag("--overlay", args->overlay, "Blend the colourized labels over the image");
  cmd->add_option("--seed", args->seed, "Seed for truth-noisy");
  cmd->callback([args] { RunSegment(*args); });
}

}  // namespace semslam::cli
