#include "semslam/semantics/segmentation.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <opencv2/core.hpp>
#include <opencv2/core/hal/hal.hpp>
#include <opencv2/imgproc.hpp>
#include <string>

#include "semslam/core/error.h"

namespace semslam {
namespace {

constexpr float kOthers = 1.0f / (kNumClasses - 1);

float FlooredLog(float p) { return std::max(std::log(std::max(p, 0.0f)), kMinObservationLogProbability); }

// A stored row of all zeros marks a pixel without a label (a real row sums to 1 in probability: at most one
// 0).
inline bool IsNoLabelRow(const float* row) { return row[0] == 0.0f && row[1] == 0.0f; }

}  // namespace

ClassLogProbs ConfusionLogProbs(int label, float alpha) {
  Require(IsValidTrainId(label), "ConfusionLogProbs: label must be a trainId 0..18");
  Require(alpha >= 1.0f / kNumClasses - 1e-6f && alpha <= 1.0f,
          "ConfusionLogProbs: alpha must lie in [1/19, 1]");
  ClassLogProbs row;
  row.fill(FlooredLog((1.0f - alpha) * kOthers));
  row[static_cast<size_t>(label)] = FlooredLog(alpha);
  return row;
}

void Segmentation::SetGeometry(cv::Size input_size) {
  Require(input_size.width > 0 && input_size.height > 0, "Segmentation: empty input size");
  Require(!data_.empty(), "Segmentation: empty data");
  input_size_ = input_size;
  scale_x_ = static_cast<float>(data_.cols) / static_cast<float>(input_size.width);
  scale_y_ = static_cast<float>(data_.rows) / static_cast<float>(input_size.height);
  max_x_ = static_cast<float>(input_size.width) - 0.5f;
  max_y_ = static_cast<float>(input_size.height) - 0.5f;
}

Segmentation Segmentation::FromLogProbabilities(cv::Mat log_probabilities, cv::Size input_size) {
  Require(log_probabilities.type() == CV_32FC(kNumClasses),
          "Segmentation::FromLogProbabilities: expected CV_32FC(19) log-probabilities");
  Segmentation s;
  s.storage_ = Storage::kLogProbabilities;
  s.data_ = log_probabilities.isContinuous() ? log_probabilities : log_probabilities.clone();
  // Floor in place (NaN too).
  float* v = s.data_.ptr<float>();
  const size_t n = s.data_.total() * kNumClasses;
  for (size_t i = 0; i < n; ++i) {
    if (!(v[i] >= kMinObservationLogProbability)) v[i] = kMinObservationLogProbability;
    if (v[i] > 0.0f) v[i] = 0.0f;
  }
  s.SetGeometry(input_size);
  return s;
}

Segmentation Segmentation::FromLabels(cv::Mat labels, cv::Size input_size, float alpha, cv::Mat confidence) {
  Require(labels.type() == CV_8UC1, "Segmentation::FromLabels: expected CV_8U trainIds");
  Require(confidence.empty() || (confidence.type() == CV_8UC1 && confidence.size() == labels.size()),
          "Segmentation::FromLabels: confidence must be CV_8U of the labels' size");
  Segmentation s;
  s.storage_ = Storage::kLabels;
  s.data_ = labels.isContinuous() ? labels : labels.clone();
  s.alpha_ = alpha;
  s.label_rows_.reserve(kNumClasses);
  for (int c = 0; c < kNumClasses; ++c) s.label_rows_.push_back(ConfusionLogProbs(c, alpha));
  if (!confidence.empty()) {
    s.confidence_ = confidence.isContinuous() ? confidence : confidence.clone();
    s.confidence_logs_.resize(256);
    for (int v = 0; v < 256; ++v) {
      const float p = std::clamp(static_cast<float>(v) / 255.0f, 1.0f / kNumClasses, 1.0f);
      s.confidence_logs_[static_cast<size_t>(v)] = {FlooredLog(p), FlooredLog((1.0f - p) * kOthers)};
    }
  }
  s.SetGeometry(input_size);
  return s;
}

bool Segmentation::SampleIndex(int index, float* log_probs) const {
  if (storage_ == Storage::kLogProbabilities) {
    if (IsNoLabelRow(data_.ptr<float>() + static_cast<size_t>(index) * kNumClasses)) return false;
    std::memcpy(log_probs, data_.ptr<float>() + static_cast<size_t>(index) * kNumClasses,
                kNumClasses * sizeof(float));
    return true;
  }
  const std::uint8_t label = data_.ptr<std::uint8_t>()[index];
  if (label >= kNumClasses) return false;
  if (confidence_.empty()) {
    std::memcpy(log_probs, label_rows_[label].data(), kNumClasses * sizeof(float));
  } else {
    const auto& logs = confidence_logs_[confidence_.ptr<std::uint8_t>()[index]];
    std::fill(log_probs, log_probs + kNumClasses, logs[1]);
    log_probs[label] = logs[0];
  }
  return true;
}

std::uint8_t Segmentation::LabelAt(float x, float y) const {
  const int index = StorageIndex(x, y);
  if (index < 0) return kNoLabel;
  if (storage_ == Storage::kLabels) {
    const std::uint8_t label = data_.ptr<std::uint8_t>()[index];
    return label < kNumClasses ? label : kNoLabel;
  }
  const float* p = data_.ptr<float>() + static_cast<size_t>(index) * kNumClasses;
  if (IsNoLabelRow(p)) return kNoLabel;
  return static_cast<std::uint8_t>(std::max_element(p, p + kNumClasses) - p);
}

cv::Mat Segmentation::Labels() const {
  if (storage_ == Storage::kEmpty) return {};
  cv::Mat labels(data_.size(), CV_8UC1);
  if (storage_ == Storage::kLabels) {
    const std::uint8_t* in = data_.ptr<std::uint8_t>();
    std::uint8_t* out = labels.ptr<std::uint8_t>();
    for (size_t i = 0; i < data_.total(); ++i) out[i] = in[i] < kNumClasses ? in[i] : kNoLabel;
    return labels;
  }
  const float* p = data_.ptr<float>();
  std::uint8_t* out = labels.ptr<std::uint8_t>();
  for (size_t i = 0; i < data_.total(); ++i, p += kNumClasses) {
    out[i] = IsNoLabelRow(p) ? kNoLabel : static_cast<std::uint8_t>(std::max_element(p, p + kNumClasses) - p);
  }
  return labels;
}

cv::Mat Segmentation::LabelsAtInputSize() const {
  cv::Mat labels = Labels();
  if (labels.empty() || labels.size() == input_size_) return labels;
  // Nearest neighbour with the same cell mapping as Sample().
  cv::Mat out(input_size_, CV_8UC1);
  std::vector<int> columns(static_cast<size_t>(input_size_.width));
  for (int x = 0; x < input_size_.width; ++x) {
    columns[static_cast<size_t>(x)] =
        std::min(static_cast<int>((static_cast<float>(x) + 0.5f) * scale_x_), labels.cols - 1);
  }
  for (int y = 0; y < input_size_.height; ++y) {
    const int sy = std::min(static_cast<int>((static_cast<float>(y) + 0.5f) * scale_y_), labels.rows - 1);
    const std::uint8_t* in = labels.ptr<std::uint8_t>(sy);
    std::uint8_t* row = out.ptr<std::uint8_t>(y);
    for (int x = 0; x < input_size_.width; ++x) row[x] = in[columns[static_cast<size_t>(x)]];
  }
  return out;
}

cv::Mat Segmentation::Confidence() const {
  if (storage_ == Storage::kEmpty) return {};
  cv::Mat confidence(data_.size(), CV_32FC1);
  float* out = confidence.ptr<float>();
  if (storage_ == Storage::kLabels) {
    const std::uint8_t* in = data_.ptr<std::uint8_t>();
    for (size_t i = 0; i < data_.total(); ++i) {
      if (in[i] >= kNumClasses) {
        out[i] = 0.0f;
      } else if (confidence_.empty()) {
        out[i] = std::exp(label_rows_[in[i]][in[i]]);
      } else {
        out[i] = std::exp(confidence_logs_[confidence_.ptr<std::uint8_t>()[i]][0]);
      }
    }
    return confidence;
  }
  const float* p = data_.ptr<float>();
  for (size_t i = 0; i < data_.total(); ++i, p += kNumClasses) {
    if (IsNoLabelRow(p)) {
      out[i] = 0.0f;
      continue;
    }
    const float best = *std::max_element(p, p + kNumClasses);
    float sum = 0.0f;
    for (int c = 0; c < kNumClasses; ++c) sum += std::exp(p[c] - best);
    out[i] = 1.0f / sum;
  }
  return confidence;
}

Segmentation Segmentation::Compacted() const {
  if (storage_ != Storage::kLogProbabilities) return *this;
  cv::Mat confidence;
  Confidence().convertTo(confidence, CV_8UC1, 255.0);
  return FromLabels(Labels(), input_size_, 1.0f, confidence);
}

size_t Segmentation::MemoryBytes() const {
  return data_.total() * data_.elemSize() + confidence_.total() * confidence_.elemSize();
}

Segmentation SegmentationFromScores(std::span<const cv::Mat> planes, ScoreKind kind,
                                    std::span<const std::uint8_t> channel_to_train_id, cv::Size input_size) {
  Require(!planes.empty(), "SegmentationFromScores: no score planes");
  Require(planes.size() == channel_to_train_id.size(),
          "SegmentationFromScores: " + std::to_string(planes.size()) + " score planes but " +
              std::to_string(channel_to_train_id.size()) + " entries in the class mapping");
  const cv::Size size = planes[0].size();
  for (const cv::Mat& plane : planes) {
    Require(plane.type() == CV_32FC1 && plane.size() == size,
            "SegmentationFromScores: planes must be CV_32F of one size");
  }
  // Row by row, so that everything stays in cache and exp/log run vectorized over whole rows.
  const size_t channels = planes.size();
  const size_t w = static_cast<size_t>(size.width);
  std::vector<float> p(channels * w), classes(kNumClasses * w), max_score(w), inverse_sum(w), spread(w);
  std::vector<std::uint8_t> no_label(w);
  cv::Mat out(size, CV_32FC(kNumClasses));
  for (int y = 0; y < size.height; ++y) {
    for (size_t c = 0; c < channels; ++c) std::memcpy(&p[c * w], planes[c].ptr<float>(y), w * sizeof(float));
    // Per-channel probabilities (unnormalized).
    if (kind == ScoreKind::kLogits) {
      std::copy(p.begin(), p.begin() + static_cast<std::ptrdiff_t>(w), max_score.begin());
      for (size_t c = 1; c < channels; ++c) {
        const float* row = &p[c * w];
        for (size_t x = 0; x < w; ++x) max_score[x] = std::max(max_score[x], row[x]);
      }
      for (size_t c = 0; c < channels; ++c) {
        float* row = &p[c * w];
        for (size_t x = 0; x < w; ++x) row[x] -= max_score[x];
      }
    }
    if (kind == ScoreKind::kProbabilities) {
      for (float& v : p) v = v > 0.0f ? v : 0.0f;  // NaN too
    } else {
      cv::hal::exp32f(p.data(), p.data(), static_cast<int>(p.size()));
    }
    std::fill(inverse_sum.begin(), inverse_sum.end(), 0.0f);
    for (size_t c = 0; c < channels; ++c) {
      const float* row = &p[c * w];
      for (size_t x = 0; x < w; ++x) inverse_sum[x] += row[x];
    }
    for (float& v : inverse_sum) v = (v > 0.0f && std::isfinite(v)) ? 1.0f / v : 0.0f;
    // Class probabilities: mapped channels add; unmapped ones ("no class") are spread evenly, and where they
    // outweigh every class the pixel has no label.
    std::fill(classes.begin(), classes.end(), 0.0f);
    std::fill(spread.begin(), spread.end(), 0.0f);
    for (size_t c = 0; c < channels; ++c) {
      const std::uint8_t id = channel_to_train_id[c];
      float* target = id < kNumClasses ? &classes[id * w] : spread.data();
      const float* row = &p[c * w];
      for (size_t x = 0; x < w; ++x) target[x] += row[x];
    }
    std::copy(classes.begin(), classes.begin() + static_cast<std::ptrdiff_t>(w), max_score.begin());
    for (size_t k = 1; k < static_cast<size_t>(kNumClasses); ++k) {
      const float* row = &classes[k * w];
      for (size_t x = 0; x < w; ++x) max_score[x] = std::max(max_score[x], row[x]);
    }
    for (size_t x = 0; x < w; ++x) {
      no_label[x] = spread[x] > max_score[x] ? 1 : 0;
      spread[x] *= 1.0f / kNumClasses;
    }
    for (size_t k = 0; k < static_cast<size_t>(kNumClasses); ++k) {
      float* row = &classes[k * w];
      for (size_t x = 0; x < w; ++x) {
        // Uniform where nothing was known (no mass, or NaN).
        const float v = inverse_sum[x] > 0.0f ? (row[x] + spread[x]) * inverse_sum[x] : 1.0f / kNumClasses;
        row[x] = v > kMinObservationProbability ? v : kMinObservationProbability;
      }
    }
    cv::hal::log32f(classes.data(), classes.data(), static_cast<int>(classes.size()));
    float* dst = out.ptr<float>(y);
    for (size_t x = 0; x < w; ++x, dst += kNumClasses) {
      if (no_label[x]) {
        std::fill(dst, dst + kNumClasses, 0.0f);
        continue;
      }
      for (size_t k = 0; k < static_cast<size_t>(kNumClasses); ++k)
        dst[k] = std::min(classes[k * w + x], 0.0f);
    }
  }
  return Segmentation::FromLogProbabilities(std::move(out), input_size);
}

}  // namespace semslam
