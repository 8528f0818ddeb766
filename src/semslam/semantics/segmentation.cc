#include "semslam/semantics/segmentation.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "semslam/core/error.h"

namespace semslam {
namespace {

constexpr float kOthers = 1.0f / (kNumClasses - 1);

float FlooredLog(float p) { return std::max(std::log(std::max(p, 0.0f)), kMinObservationLogProbability); }

}  // namespace

ClassLogProbs ConfusionLogProbs(int label, float alpha) {
  Require(IsValidTrainId(label), "ConfusionLogProbs: label must be a trainId 0..18");
  Require(alpha >= 1.0f / kNumClasses - 1e-6f && alpha <= 1.0f, "ConfusionLogProbs: alpha must lie in [1/19, 1]");
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
  // Floor in place (NaN becomes the floor too: max(NaN, floor) with this argument order returns the floor).
  cv::Mat flat = s.data_.reshape(1, 1);
  for (int i = 0; i < flat.cols; ++i) {
    float& v = flat.at<float>(0, i);
    if (!(v >= kMinObservationLogProbability)) v = kMinObservationLogProbability;
    if (v > 0.0f) v = 0.0f;
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
    out[i] = static_cast<std::uint8_t>(std::max_element(p, p + kNumClasses) - p);
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
    columns[static_cast<size_t>(x)] = std::min(static_cast<int>((static_cast<float>(x) + 0.5f) * scale_x_),
                                               labels.cols - 1);
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
    Require(plane.type() == CV_32FC1 && plane.size() == size, "SegmentationFromScores: planes must be CV_32F of one size");
  }
  // Per-channel probabilities.
  std::vector<cv::Mat> probabilities(planes.size());
  cv::Mat sum = cv::Mat::zeros(size, CV_32FC1);
  if (kind == ScoreKind::kLogits) {
    cv::Mat max_score = planes[0].clone();
    for (size_t c = 1; c < planes.size(); ++c) cv::max(max_score, planes[c], max_score);
    for (size_t c = 0; c < planes.size(); ++c) {
      cv::exp(planes[c] - max_score, probabilities[c]);
      sum += probabilities[c];
    }
  } else {
    for (size_t c = 0; c < planes.size(); ++c) {
      if (kind == ScoreKind::kLogProbabilities) {
        cv::exp(planes[c], probabilities[c]);
      } else {
        probabilities[c] = cv::max(planes[c], 0.0);
      }
      sum += probabilities[c];
    }
  }
  // Pixels with no mass at all (or NaN) become uniform.
  cv::Mat inverse_sum(size, CV_32FC1);
  for (int y = 0; y < size.height; ++y) {
    const float* s = sum.ptr<float>(y);
    float* inv = inverse_sum.ptr<float>(y);
    for (int x = 0; x < size.width; ++x) inv[x] = (s[x] > 0.0f && std::isfinite(s[x])) ? 1.0f / s[x] : 0.0f;
  }
  // Class probabilities: mapped channels add; unmapped channels are spread evenly.
  std::vector<cv::Mat> classes(kNumClasses);
  for (cv::Mat& c : classes) c = cv::Mat::zeros(size, CV_32FC1);
  cv::Mat spread = cv::Mat::zeros(size, CV_32FC1);
  for (size_t c = 0; c < planes.size(); ++c) {
    const std::uint8_t id = channel_to_train_id[c];
    if (id < kNumClasses) {
      classes[id] += probabilities[c];
    } else {
      spread += probabilities[c];
    }
  }
  spread *= 1.0 / kNumClasses;
  cv::Mat no_mass = (inverse_sum == 0.0f);  // uniform where nothing was known
  for (cv::Mat& c : classes) {
    c += spread;
    cv::multiply(c, inverse_sum, c);
    c.setTo(1.0f / kNumClasses, no_mass);
    cv::max(c, kMinObservationProbability, c);
    cv::log(c, c);
  }
  cv::Mat merged;
  cv::merge(classes, merged);
  return Segmentation::FromLogProbabilities(std::move(merged), input_size);
}

}  // namespace semslam
