#include "semslam/semantics/label_fusion.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>

#include "semslam/core/error.h"

namespace semslam {

LabelDistribution LabelDistribution::FromLogProbabilities(
    std::span<const float, kNumClasses> log_probabilities, std::uint32_t num_observations) {
  LabelDistribution d;
  for (int c = 0; c < kNumClasses; ++c) {
    const float v = log_probabilities[static_cast<size_t>(c)];
    Require(std::isfinite(v), "LabelDistribution: log-probabilities must be finite");
    d.log_p_[static_cast<size_t>(c)] = v;
  }
  d.observations_ = num_observations;
  d.Renormalize();
  return d;
}

void LabelDistribution::Renormalize() {
  float best = log_p_[0];
  for (int c = 1; c < kNumClasses; ++c) best = std::max(best, log_p_[static_cast<size_t>(c)]);
  for (float& v : log_p_) v = std::max(v - best, kMinRelativeLogProbability);
}

void LabelDistribution::FuseLabel(int label, float alpha) {
  if (!IsValidTrainId(label)) return;
  Fuse(ConfusionLogProbs(label, alpha));
}

void LabelDistribution::Merge(const LabelDistribution& other) {
  for (int c = 0; c < kNumClasses; ++c)
    log_p_[static_cast<size_t>(c)] += other.log_p_[static_cast<size_t>(c)];
  observations_ += other.observations_;
  Renormalize();
}

int LabelDistribution::Label() const {
  if (observations_ == 0) return kNoLabel;
  return static_cast<int>(std::max_element(log_p_.begin(), log_p_.end()) - log_p_.begin());
}

ClassLogProbs LabelDistribution::RelativeLogProbabilities() const {
  LabelDistribution copy = *this;
  copy.Renormalize();
  return copy.log_p_;
}

float LabelDistribution::Confidence() const {
  // Relative to the maximum, the argmax's posterior is 1 / sum(exp(log_p - max)).
  const float best = *std::max_element(log_p_.begin(), log_p_.end());
  float sum = 0.0f;
  for (float v : log_p_) sum += std::exp(std::max(v - best, kMinRelativeLogProbability));
  return 1.0f / sum;
}

std::array<float, kNumClasses> LabelDistribution::Probabilities() const {
  const ClassLogProbs relative = RelativeLogProbabilities();
  std::array<float, kNumClasses> p;
  float sum = 0.0f;
  for (int c = 0; c < kNumClasses; ++c)
    sum += p[static_cast<size_t>(c)] = std::exp(relative[static_cast<size_t>(c)]);
  for (float& v : p) v /= sum;
  return p;
}

ClassLogProbs LabelDistribution::NormalizedLogProbabilities() const {
  ClassLogProbs out = RelativeLogProbabilities();
  float sum = 0.0f;
  for (float v : out) sum += std::exp(v);
  const float log_z = std::log(sum);
  for (float& v : out) v -= log_z;
  return out;
}

void LabelDistribution::AppendTo(BinaryWriter& writer) const {
  for (float v : RelativeLogProbabilities()) writer.Put<float>(v);
  writer.Put<std::uint32_t>(observations_);
}

LabelDistribution LabelDistribution::ReadFrom(BinaryReader& reader) {
  ClassLogProbs values;
  for (float& v : values) v = reader.Get<float>();
  const auto observations = reader.Get<std::uint32_t>();
  for (float v : values) {
    if (!std::isfinite(v) || v > 0.0f) reader.Fail("label distribution: invalid log-probability");
  }
  return FromLogProbabilities(values, observations);
}

std::string LabelDistribution::ToBytes() const {
  BinaryWriter writer;
  AppendTo(writer);
  return writer.bytes();
}

LabelDistribution LabelDistribution::FromBytes(std::string_view bytes) {
  Require(bytes.size() == kSerializedBytes, "LabelDistribution::FromBytes: expected " +
                                                std::to_string(kSerializedBytes) + " bytes, got " +
                                                std::to_string(bytes.size()));
  ClassLogProbs values;
  std::uint32_t observations = 0;
  std::memcpy(values.data(), bytes.data(), kNumClasses * sizeof(float));
  std::memcpy(&observations, bytes.data() + kNumClasses * sizeof(float), sizeof(observations));
  for (float v : values)
    Require(std::isfinite(v) && v <= 0.0f, "LabelDistribution::FromBytes: invalid value");
  return FromLogProbabilities(values, observations);
}

void FusionOptions::Check() const {
  Require(std::isfinite(min_depth) && min_depth > 0.0, "FusionOptions: min_depth must be > 0");
  Require(std::isfinite(margin) && margin >= 0.0, "FusionOptions: margin must be >= 0");
}

FusionStats FuseKeyframeObservations(const Segmentation& segmentation, const Rigid3d& camera_from_world,
                                     const PinholeCamera& camera, std::span<const PointObservation> points,
                                     const FusionOptions& options) {
  options.Check();
  Require(!segmentation.empty(), "FuseKeyframeObservations: empty segmentation");
  Require(
      camera.width == segmentation.input_size().width && camera.height == segmentation.input_size().height,
      "FuseKeyframeObservations: camera " + std::to_string(camera.width) + "x" +
          std::to_string(camera.height) + " but segmentation of a " +
          std::to_string(segmentation.input_size().width) + "x" +
          std::to_string(segmentation.input_size().height) + " image");
  FusionStats stats;
  const Eigen::Matrix3d rotation = camera_from_world.rotation.toRotationMatrix();
  const Eigen::Vector3d& translation = camera_from_world.translation;
  const bool pinhole = camera.distortion.IsZero();
  const double lo_x = options.margin - 0.5, hi_x = camera.width - 0.5 - options.margin;
  const double lo_y = options.margin - 0.5, hi_y = camera.height - 0.5 - options.margin;
  ClassLogProbs sample;
  for (const PointObservation& point : points) {
    if (point.distribution == nullptr) continue;
    const Eigen::Vector3d in_camera = rotation * point.world_position + translation;  // eq. 1
    if (!(in_camera.z() > options.min_depth)) {
      ++stats.behind;
      continue;
    }
    double u, v;  // eq. 2
    if (pinhole) {
      const double inv_z = 1.0 / in_camera.z();
      u = camera.fx * in_camera.x() * inv_z + camera.cx;
      v = camera.fy * in_camera.y() * inv_z + camera.cy;
    } else {
      const Eigen::Vector2d pixel = camera.Project(in_camera);
      u = pixel.x();
      v = pixel.y();
    }
    if (!(u >= lo_x && u < hi_x && v >= lo_y && v < hi_y)) {
      ++stats.outside;
      continue;
    }
    if (!segmentation.Sample(static_cast<float>(u), static_cast<float>(v), sample.data())) {  // eq. 3
      ++stats.unlabeled;
      continue;
    }
    point.distribution->Fuse(sample);  // eqs. 4-5
    ++stats.fused;
  }
  return stats;
}

int SampleAtPixels(const Segmentation& segmentation, std::span<const Eigen::Vector2f> pixels,
                   std::vector<float>* log_probs) {
  return SampleAtKeypoints(
      segmentation, pixels, [](const Eigen::Vector2f& p) { return p; }, log_probs);
}

float DynamicProbability(const float* log_probs) {
  if (!IsSampledObservation(log_probs)) return 0.0f;
  float all = 0.0f, dynamic = 0.0f;
  for (int c = 0; c < kNumClasses; ++c) {
    const float p = std::exp(log_probs[c]);
    all += p;
    if (IsDynamicClass(c)) dynamic += p;
  }
  return dynamic / all;
}

float LabelDistribution::DynamicProbability() const {
  if (observations_ == 0) return 0.0f;
  const auto p = Probabilities();
  float dynamic = 0.0f;
  for (int c = 0; c < kNumClasses; ++c) dynamic += IsDynamicClass(c) ? p[static_cast<size_t>(c)] : 0.0f;
  return dynamic;
}

bool IsSampledObservation(const float* row) {
  for (int c = 0; c < kNumClasses; ++c) {
    if (row[c] != 0.0f) return true;
  }
  return false;
}

bool FuseSampledObservation(LabelDistribution& distribution, const float* row) {
  if (!IsSampledObservation(row)) return false;
  distribution.Fuse(row);
  return true;
}

}  // namespace semslam
