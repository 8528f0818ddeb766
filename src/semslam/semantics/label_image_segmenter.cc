#include "semslam/semantics/label_image_segmenter.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <sstream>

#include "semslam/core/error.h"

namespace semslam {
namespace {

std::uint64_t SplitMix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

std::string FrameName(std::int64_t frame_index, int digits) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%0*lld", digits, static_cast<long long>(frame_index));
  return buffer;
}

// A smooth random field in [0, 1): uniform values on a grid of `cell` pixels, interpolated bicubically.
cv::Mat SmoothNoise(cv::Size size, double cell, std::mt19937_64& rng) {
  cell = std::max(cell, 1.0);
  const int grid_w = static_cast<int>(std::ceil(size.width / cell)) + 3;
  const int grid_h = static_cast<int>(std::ceil(size.height / cell)) + 3;
  cv::Mat grid(grid_h, grid_w, CV_32FC1);
  std::uniform_real_distribution<float> uniform(0.0f, 1.0f);
  for (int y = 0; y < grid_h; ++y) {
    for (int x = 0; x < grid_w; ++x) grid.at<float>(y, x) = uniform(rng);
  }
  cv::Mat big;
  cv::resize(
      grid, big,
      cv::Size(static_cast<int>(std::lround(grid_w * cell)), static_cast<int>(std::lround(grid_h * cell))), 0,
      0, cv::INTER_CUBIC);
  const int offset = static_cast<int>(std::lround(cell));  // skip the border cells
  return big(cv::Rect(offset, offset, size.width, size.height)).clone();
}

}  // namespace

std::filesystem::path FindFrameFile(const std::filesystem::path& dir, std::int64_t frame_index,
                                    const std::string& extension, const std::string& suffix) {
  for (int digits : {6, 10}) {
    const std::filesystem::path path = dir / (FrameName(frame_index, digits) + suffix + extension);
    if (std::filesystem::exists(path)) return path;
  }
  return {};
}

cv::Mat ReadLabelImage(const std::filesystem::path& path) {
  if (!std::filesystem::is_regular_file(path)) throw InputError(path, "label image not found");
  cv::Mat image = cv::imread(path.string(), cv::IMREAD_UNCHANGED);
  if (image.empty()) throw InputError(path, "cannot decode the label image");
  if (image.type() == CV_8UC1) return image;
  if (image.type() == CV_8UC3 || image.type() == CV_8UC4) {
    // A colourized (or palette) label image: map Cityscapes palette colours back to trainIds.
    std::map<std::uint32_t, std::uint8_t> by_color;
    for (int c = 0; c < kNumClasses; ++c) {
      const Rgb rgb = ClassColor(c);
      by_color[(std::uint32_t{rgb.r} << 16) | (std::uint32_t{rgb.g} << 8) | rgb.b] =
          static_cast<std::uint8_t>(c);
    }
    cv::Mat labels(image.size(), CV_8UC1);
    size_t unknown = 0;
    const int step = image.channels();
    for (int y = 0; y < image.rows; ++y) {
      const std::uint8_t* in = image.ptr<std::uint8_t>(y);
      std::uint8_t* out = labels.ptr<std::uint8_t>(y);
      for (int x = 0; x < image.cols; ++x, in += step) {
        const std::uint32_t key = (std::uint32_t{in[2]} << 16) | (std::uint32_t{in[1]} << 8) | in[0];
        const auto it = by_color.find(key);
        if (it != by_color.end()) {
          out[x] = it->second;
        } else {
          out[x] = kNoLabel;
          if (key != 0) ++unknown;
        }
      }
    }
    if (unknown > labels.total() / 100) {
      throw InputError(path,
                       "a colour image that is not a Cityscapes-palette label image; expected 8-bit grey "
                       "trainIds or labelIds");
    }
    return labels;
  }
  throw InputError(path, "expected an 8-bit single-channel label image");
}

cv::Mat LabelIdsToTrainIds(const cv::Mat& label_ids) {
  Require(label_ids.type() == CV_8UC1, "LabelIdsToTrainIds: expected CV_8U");
  const auto& table = LabelIdToTrainIdTable();
  cv::Mat lut(1, 256, CV_8UC1, const_cast<std::uint8_t*>(table.data()));
  cv::Mat out;
  cv::LUT(label_ids, lut, out);
  return out;
}

std::vector<cv::Mat> ReadNpyProbabilities(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "cannot open the .npy file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  const std::string bytes = buffer.str();
  if (bytes.size() < 10 || bytes.compare(0, 6, "\x93NUMPY") != 0)
    throw InputError(path, "not a NumPy .npy file");
  const int major = static_cast<unsigned char>(bytes[6]);
  size_t header_len = 0, header_start = 0;
  if (major == 1) {
    header_len = static_cast<unsigned char>(bytes[8]) |
                 (static_cast<size_t>(static_cast<unsigned char>(bytes[9])) << 8);
    header_start = 10;
  } else if (major == 2 || major == 3) {
    if (bytes.size() < 12) throw InputError(path, "truncated .npy header");
    header_len = 0;
    for (int i = 0; i < 4; ++i)
      header_len |= static_cast<size_t>(static_cast<unsigned char>(bytes[8 + i])) << (8 * i);
    header_start = 12;
  } else {
    throw InputError(path, "unsupported .npy version " + std::to_string(major));
  }
  if (header_start + header_len > bytes.size()) throw InputError(path, "truncated .npy header");
  const std::string header = bytes.substr(header_start, header_len);
  const auto field = [&](const std::string& key) {
    const size_t at = header.find("'" + key + "'");
    if (at == std::string::npos) throw InputError(path, "npy header has no '" + key + "'");
    return header.substr(header.find(':', at) + 1);
  };
  const std::string descr_part = field("descr");
  const size_t q1 = descr_part.find('\'');
  const size_t q2 = descr_part.find('\'', q1 + 1);
  const std::string descr = descr_part.substr(q1 + 1, q2 - q1 - 1);
  if (descr != "<f4" && descr != "|u1" && descr != "<u1") {
    throw InputError(path, "npy dtype '" + descr + "' not supported (float32 '<f4' or uint8 '|u1')");
  }
  if (field("fortran_order").find("True") < field("fortran_order").find(',')) {
    throw InputError(path, "Fortran-ordered .npy arrays are not supported");
  }
  const std::string shape_part = field("shape");
  const std::string shape_text =
      shape_part.substr(shape_part.find('(') + 1, shape_part.find(')') - shape_part.find('(') - 1);
  std::vector<long long> shape;
  std::stringstream shape_stream(shape_text);
  std::string item;
  while (std::getline(shape_stream, item, ',')) {
    if (item.find_first_not_of(" ") == std::string::npos) continue;
    shape.push_back(std::stoll(item));
  }
  if (shape.size() != 3) throw InputError(path, "expected a 3-dimensional array (H x W x C or C x H x W)");
  // The class axis is the one of 19 or 20 entries; H x W x C when both ends could be.
  const auto is_classes = [](long long n) { return n == kNumClasses || n == kNumClasses + 1; };
  const bool channels_last = is_classes(shape[2]);
  const bool channels_first = !channels_last && is_classes(shape[0]);
  if (!channels_last && !channels_first) {
    throw InputError(path,
                     "expected 19 class channels (or 20 with 'unlabeled' first) on the first or last axis");
  }
  if (shape[0] <= 0 || shape[1] <= 0 || shape[2] <= 0 || shape[0] * shape[1] * shape[2] > (1LL << 31)) {
    throw InputError(path, "bad array shape");
  }
  const int channels = static_cast<int>(channels_last ? shape[2] : shape[0]);
  const int rows = static_cast<int>(channels_last ? shape[0] : shape[1]);
  const int cols = static_cast<int>(channels_last ? shape[1] : shape[2]);
  const size_t element = descr == "<f4" ? 4 : 1;
  const size_t data_start = header_start + header_len;
  const size_t count = static_cast<size_t>(channels) * static_cast<size_t>(rows) * static_cast<size_t>(cols);
  if (bytes.size() - data_start < count * element) throw InputError(path, "truncated .npy data");
  const int type = element == 4 ? CV_32FC1 : CV_8UC1;
  const double scale = element == 4 ? 1.0 : 1.0 / 255.0;
  std::vector<cv::Mat> planes(static_cast<size_t>(channels));
  char* data = const_cast<char*>(bytes.data() + data_start);
  if (channels_first) {
    for (int c = 0; c < channels; ++c) {
      cv::Mat(rows, cols, type, data + static_cast<size_t>(c) * rows * cols * element)
          .convertTo(planes[static_cast<size_t>(c)], CV_32FC1, scale);
    }
  } else {
    cv::Mat interleaved(rows, cols, CV_MAKETYPE(CV_MAT_DEPTH(type), channels), data);
    std::vector<cv::Mat> raw;
    cv::split(interleaved, raw);
    for (int c = 0; c < channels; ++c)
      raw[static_cast<size_t>(c)].convertTo(planes[static_cast<size_t>(c)], CV_32FC1, scale);
  }
  for (const cv::Mat& p : planes) {
    if (!cv::checkRange(p)) throw InputError(path, "NaN or infinite probabilities");
  }
  return planes;
}

void LabelImageSegmenter::Options::Check() const {
  Require(alpha >= 1.0f / kNumClasses && alpha <= 1.0f, "labels: alpha must lie in [1/19, 1]");
}

LabelImageSegmenter::LabelImageSegmenter(std::filesystem::path dir, Options options)
    : dir_(std::move(dir)), options_(options) {
  options_.Check();
  if (!std::filesystem::is_directory(dir_)) throw InputError(dir_, "label folder not found");
}

std::string LabelImageSegmenter::Describe() const {
  return "labels " + dir_.string() + " (" + (options_.label_ids ? "labelIds" : "trainIds") + ", alpha " +
         std::to_string(options_.alpha) + ")";
}

Segmentation LabelImageSegmenter::Segment(const cv::Mat& image, std::int64_t frame_index) {
  Require(frame_index >= 0, "labels: a frame index is needed to find the label file");
  if (const auto npy = FindFrameFile(dir_, frame_index, ".npy"); !npy.empty()) {
    const std::vector<cv::Mat> planes = ReadNpyProbabilities(npy);
    std::vector<std::uint8_t> mapping;
    if (planes.size() == static_cast<size_t>(kNumClasses)) {
      for (int c = 0; c < kNumClasses; ++c) mapping.push_back(static_cast<std::uint8_t>(c));
    } else if (planes.size() == static_cast<size_t>(kNumClasses + 1)) {
      mapping.push_back(kNoLabel);
      for (int c = 0; c < kNumClasses; ++c) mapping.push_back(static_cast<std::uint8_t>(c));
    } else {
      throw InputError(npy, "expected 19 class channels (or 20 with 'unlabeled' first), got " +
                                std::to_string(planes.size()));
    }
    return SegmentationFromScores(planes, ScoreKind::kProbabilities, mapping,
                                  image.empty() ? planes[0].size() : image.size());
  }
  const auto png = FindFrameFile(dir_, frame_index, ".png");
  if (png.empty()) {
    throw InputError(dir_ / (FrameName(frame_index, 6) + ".png"),
                     "label image of frame " + std::to_string(frame_index) + " not found");
  }
  cv::Mat labels = ReadLabelImage(png);
  if (options_.label_ids) labels = LabelIdsToTrainIds(labels);
  cv::Mat confidence;
  if (const auto conf = FindFrameFile(dir_, frame_index, ".png", "_conf"); !conf.empty()) {
    confidence = ReadLabelImage(conf);
    if (confidence.size() != labels.size())
      throw InputError(conf, "confidence image size differs from the labels'");
  }
  return Segmentation::FromLabels(labels, image.empty() ? labels.size() : image.size(), options_.alpha,
                                  confidence);
}

void LabelNoiseOptions::Check() const {
  Require(std::isfinite(rate) && rate >= 0.0 && rate <= 0.9, "label noise: rate must lie in [0, 0.9]");
  Require(std::isfinite(blob_fraction) && blob_fraction >= 0.0 && blob_fraction <= 1.0,
          "label noise: blob_fraction must lie in [0, 1]");
  Require(std::isfinite(blob_size) && blob_size >= 0.0, "label noise: blob_size must be >= 0");
}

cv::Mat AddLabelNoise(const cv::Mat& truth, const LabelNoiseOptions& options, std::uint64_t seed) {
  options.Check();
  Require(truth.type() == CV_8UC1, "AddLabelNoise: expected CV_8U trainIds");
  cv::Mat noisy = truth.clone();
  if (options.rate <= 0.0 || truth.empty()) return noisy;
  std::mt19937_64 rng(SplitMix64(seed));
  const cv::Mat labeled = truth < kNumClasses;
  const int num_labeled = cv::countNonZero(labeled);
  if (num_labeled == 0) return noisy;

  // Blobs: the pixels where a smooth random field is highest, as many as the blob share of the errors.
  cv::Mat blobs = cv::Mat::zeros(truth.size(), CV_8UC1);
  const long long target_blob = std::llround(options.rate * options.blob_fraction * num_labeled);
  if (target_blob > 0) {
    const double cell = options.blob_size > 0.0 ? options.blob_size : std::max(4.0, truth.rows / 8.0);
    cv::Mat field = SmoothNoise(truth.size(), cell, rng) + 0.5 * SmoothNoise(truth.size(), cell / 2.0, rng);
    std::vector<float> values;
    values.reserve(static_cast<size_t>(num_labeled));
    for (int y = 0; y < truth.rows; ++y) {
      const float* f = field.ptr<float>(y);
      const std::uint8_t* l = labeled.ptr<std::uint8_t>(y);
      for (int x = 0; x < truth.cols; ++x) {
        if (l[x]) values.push_back(f[x]);
      }
    }
    const size_t k = values.size() - static_cast<size_t>(target_blob);
    std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
    const float threshold = values[k];
    blobs = (field >= threshold) & labeled;
  }
  const int num_blob = cv::countNonZero(blobs);
  cv::Mat components;
  const int num_components = num_blob > 0 ? cv::connectedComponents(blobs, components, 8, CV_32S) : 1;
  // One wrong class per blob (and, where that happens to be the true class, one fixed substitute).
  std::vector<std::array<std::uint8_t, 2>> blob_class(static_cast<size_t>(num_components));
  std::uniform_int_distribution<int> any_class(0, kNumClasses - 1), other(1, kNumClasses - 1);
  for (auto& b : blob_class)
    b = {static_cast<std::uint8_t>(any_class(rng)), static_cast<std::uint8_t>(other(rng))};

  // Salt: independent errors among the other pixels, so that the total error rate is `rate`.
  const double remaining = options.rate * num_labeled - num_blob;
  const double salt =
      num_labeled > num_blob ? std::clamp(remaining / (num_labeled - num_blob), 0.0, 1.0) : 0.0;
  const auto salt_threshold = static_cast<std::uint64_t>(salt * 4294967296.0);
  const std::uint64_t pixel_seed = rng();
  for (int y = 0; y < truth.rows; ++y) {
    const std::uint8_t* t = truth.ptr<std::uint8_t>(y);
    const std::uint8_t* in_blob = blobs.ptr<std::uint8_t>(y);
    std::uint8_t* out = noisy.ptr<std::uint8_t>(y);
    for (int x = 0; x < truth.cols; ++x) {
      if (t[x] >= kNumClasses) continue;
      if (in_blob[x]) {
        const auto& b = blob_class[static_cast<size_t>(components.at<int>(y, x))];
        out[x] = b[0] != t[x] ? b[0] : static_cast<std::uint8_t>((t[x] + b[1]) % kNumClasses);
        continue;
      }
      const std::uint64_t r = SplitMix64(pixel_seed ^ (static_cast<std::uint64_t>(y) * truth.cols + x));
      if ((r >> 32) < salt_threshold) {
        const auto shift = 1 + static_cast<int>((r & 0xffffffffULL) % (kNumClasses - 1));
        out[x] = static_cast<std::uint8_t>((t[x] + shift) % kNumClasses);
      }
    }
  }
  return noisy;
}

void TruthNoisySegmenter::Options::Check() const {
  noise.Check();
  Require(alpha < 0.0f || (alpha >= 1.0f / kNumClasses && alpha <= 1.0f),
          "truth-noisy: alpha must lie in [1/19, 1]");
}

float TruthNoisySegmenter::Options::ResolvedAlpha() const {
  if (alpha >= 0.0f) return alpha;
  return std::max(1.0f - static_cast<float>(noise.rate), 1.0f / kNumClasses);
}

TruthNoisySegmenter::TruthNoisySegmenter(std::filesystem::path truth_dir, Options options)
    : truth_dir_(std::move(truth_dir)), options_(options) {
  options_.Check();
  if (!std::filesystem::is_directory(truth_dir_))
    throw InputError(truth_dir_, "ground-truth label folder not found");
}

std::string TruthNoisySegmenter::Describe() const {
  return "truth-noisy " + truth_dir_.string() + " (rate " + std::to_string(options_.noise.rate) + ", blobs " +
         std::to_string(options_.noise.blob_fraction) + ", alpha " +
         std::to_string(options_.ResolvedAlpha()) + ", seed " + std::to_string(options_.seed) + ")";
}

cv::Mat TruthNoisySegmenter::NoisyLabels(std::int64_t frame_index) const {
  Require(frame_index >= 0, "truth-noisy: a frame index is needed to find the label file");
  const auto path = FindFrameFile(truth_dir_, frame_index, ".png");
  if (path.empty()) {
    throw InputError(truth_dir_ / (FrameName(frame_index, 6) + ".png"),
                     "ground-truth label image of frame " + std::to_string(frame_index) + " not found");
  }
  const cv::Mat truth = ReadLabelImage(path);
  return AddLabelNoise(truth, options_.noise,
                       SplitMix64(options_.seed) ^ SplitMix64(static_cast<std::uint64_t>(frame_index) + 1));
}

Segmentation TruthNoisySegmenter::Segment(const cv::Mat& image, std::int64_t frame_index) {
  cv::Mat labels = NoisyLabels(frame_index);
  return Segmentation::FromLabels(labels, image.empty() ? labels.size() : image.size(),
                                  options_.ResolvedAlpha());
}

}  // namespace semslam
