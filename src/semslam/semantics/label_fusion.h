#pragma once
// Bayesian label fusion per map point (the paper's eqs. 1-6, in log space).
//
// A point's posterior over the 19 classes after observations F_1..F_k (uniform prior) is
//   p(l | F_1..k) = p(l | F_k) p(l | F_1..k-1) / Z,   Z = sum_l p(l | F_k) p(l | F_1..k-1)      (eqs. 4-5)
// kept as log-probabilities: an observation adds its log-probabilities (19 additions, nothing else);
// normalization is lazy: Z is never needed for the argmax and is computed only when a probability is asked
// for, and every few observations the values are shifted so that the maximum is 0 (nothing drifts out of
// float precision) and floored at kMinRelativeLogProbability. The label is the argmax (eq. 6) and its
// confidence the posterior of the argmax. A keyframe observation projects the point into the keyframe (eqs.
// 1-2) and reads the segmentation's distribution at that pixel (eq. 3): FuseKeyframeObservations does this
// for a batch of points.

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "semslam/core/binary_io.h"
#include "semslam/geometry/camera.h"
#include "semslam/geometry/rigid3.h"
#include "semslam/semantics/class_table.h"
#include "semslam/semantics/segmentation.h"

namespace semslam {

class LabelDistribution {
 public:
  // Posterior log-probabilities are kept relative to the most probable class, floored at
  // kMinRelativeLogProbability (e^-60: far beyond anything a few observations can overturn) at least every
  // kRenormalizeEvery observations.
  static constexpr float kMinRelativeLogProbability = -60.0f;
  static constexpr std::uint32_t kRenormalizeEvery = 8;
  static constexpr size_t kSerializedBytes = kNumClasses * sizeof(float) + sizeof(std::uint32_t);

  // Uniform, no observations.
  LabelDistribution() { log_p_.fill(0.0f); }
  // From stored relative log-probabilities (e.g. a map file); normalized the same way. Throws InvalidArgument
  // on NaN or infinite values.
  static LabelDistribution FromLogProbabilities(std::span<const float, kNumClasses> log_probabilities,
                                                std::uint32_t num_observations);

  // Multiplies in one observation (19 log-probabilities, e.g. from Segmentation::Sample; they need not be
  // normalized). Each entry is floored at kMinObservationLogProbability first, so no single observation can
  // rule a class out.
  void Fuse(const float* observation_log_probs) {
    for (int c = 0; c < kNumClasses; ++c) {
      const float v = observation_log_probs[c];
      log_p_[static_cast<size_t>(c)] += v > kMinObservationLogProbability ? v : kMinObservationLogProbability;
    }
    if (++observations_ % kRenormalizeEvery == 0) Renormalize();
  }
  void Fuse(const ClassLogProbs& observation) { Fuse(observation.data()); }
  // Fuses the label-only observation `label` with the confusion model (alpha for the label, the rest spread
  // evenly). kNoLabel is ignored.
  void FuseLabel(int label, float alpha);
  // Point fusion (two map points found to be one): both posteriors were formed from a uniform prior by
  // independent observations, so the joint posterior is their product. Observation counts add.
  void Merge(const LabelDistribution& other);

  // argmax (eq. 6); kNoLabel while the point has no observation.
  int Label() const;
  // Posterior probability of Label(); 1/19 with no observation.
  float Confidence() const;
  int NumObservations() const { return static_cast<int>(observations_); }
  bool HasObservations() const { return observations_ > 0; }
  // Posterior probability of the dynamic classes together (0 without observations).
  float DynamicProbability() const;
  // Normalized posterior probabilities and log-probabilities.
  std::array<float, kNumClasses> Probabilities() const;
  ClassLogProbs NormalizedLogProbabilities() const;
  // Log-probabilities relative to the most probable class (maximum 0), floored at kMinRelativeLogProbability.
  ClassLogProbs RelativeLogProbabilities() const;

  // 80 bytes: 19 little-endian float32 relative log-probabilities, then the uint32 observation count.
  void AppendTo(BinaryWriter& writer) const;
  static LabelDistribution ReadFrom(BinaryReader& reader);
  std::string ToBytes() const;
  // Throws InvalidArgument on a wrong size or invalid values.
  static LabelDistribution FromBytes(std::string_view bytes);

  // Same observation count and same relative log-probabilities.
  friend bool operator==(const LabelDistribution& a, const LabelDistribution& b) {
    return a.observations_ == b.observations_ && a.RelativeLogProbabilities() == b.RelativeLogProbabilities();
  }

 private:
  void Renormalize();

  ClassLogProbs log_p_;  // up to a constant: the posterior's log-probabilities
  std::uint32_t observations_ = 0;
};

// One map point seen by a keyframe: its world position and the distribution to update.
struct PointObservation {
  Eigen::Vector3d world_position;
  LabelDistribution* distribution = nullptr;
};

struct FusionStats {
  int fused = 0;      // points whose distribution was updated
  int behind = 0;     // depth <= min_depth
  int outside = 0;    // projected outside the image (or margin)
  int unlabeled = 0;  // inside, but the segmentation has no label there
};

struct FusionOptions {
  double min_depth = 1e-3;  // metres in front of the camera
  double margin = 0.0;      // pixels kept free at the image border

  void Check() const;
};

// Fuses one keyframe's segmentation into the given points: each is moved into the camera frame (eq. 1),
// projected (eq. 2, with the camera's distortion), its class distribution read at the pixel (eq. 3) and
// multiplied in (eqs. 4-5). `camera` is the camera of the segmented image: its width and height must equal
// the segmentation's input size (throws InvalidArgument otherwise). Null distributions are skipped. Not
// synchronized: the caller holds whatever lock guards the distributions.
FusionStats FuseKeyframeObservations(const Segmentation& segmentation, const Rigid3d& camera_from_world,
                                     const PinholeCamera& camera, std::span<const PointObservation> points,
                                     const FusionOptions& options = {});

// Per-keypoint sampling: 19 log-probabilities per pixel (row-major, appended to nothing: the vector is
// resized to 19 * pixels.size()), so a point created after the keyframe was segmented can still get this
// keyframe's observation (FuseSampledObservation). Pixels outside or without a label get an all-zero row,
// which means "no observation" (a real observation's log-probabilities are negative). Returns the number of
// labeled pixels.
int SampleAtPixels(const Segmentation& segmentation, std::span<const Eigen::Vector2f> pixels,
                   std::vector<float>* log_probs);
// The same for any keypoint type: `pixel_of(keypoint)` returns its pixel (anything with x() and y()).
template <typename Keypoints, typename PixelOf>
int SampleAtKeypoints(const Segmentation& segmentation, const Keypoints& keypoints, PixelOf pixel_of,
                      std::vector<float>* log_probs) {
  log_probs->assign(std::size(keypoints) * kNumClasses, 0.0f);
  int labeled = 0;
  float* row = log_probs->data();
  for (const auto& keypoint : keypoints) {
    const auto pixel = pixel_of(keypoint);
    labeled += segmentation.Sample(static_cast<float>(pixel.x()), static_cast<float>(pixel.y()), row) ? 1 : 0;
    row += kNumClasses;
  }
  return labeled;
}
// Probability that an observation (19 log-probabilities, e.g. a sampled row) is of a dynamic class (person,
// rider, vehicles): for keeping features on moving things out of tracking and relocalization. 0 for a "none"
// row.
float DynamicProbability(const float* log_probs);

// Whether a sampled row holds an observation (is not the all-zero "none" row).
bool IsSampledObservation(const float* row);
// Fuses a sampled row (from SampleAtPixels) into `distribution`; false (nothing done) for a "none" row.
bool FuseSampledObservation(LabelDistribution& distribution, const float* row);

}  // namespace semslam
