#include "semslam/map/map_point.h"

#include <algorithm>
#include <limits>

#include "semslam/map/keyframe.h"

namespace semslam {

MapPoint::MapPoint(std::uint64_t id, const Eigen::Vector3d& position, KeyFrame* reference_keyframe)
    : id_(id),
      first_keyframe_id_(reference_keyframe ? reference_keyframe->id() : 0),
      position_(position),
      reference_keyframe_(reference_keyframe) {}

std::uint32_t MapPoint::map_id() const {
  return reference_keyframe_ != nullptr ? reference_keyframe_->map_id() : 0;
}

void MapPoint::AddObservation(KeyFrame* keyframe, int keypoint_index, bool fuse_labels) {
  if (observations_.count(keyframe)) return;
  observations_[keyframe] = keypoint_index;
  num_observations_ += keyframe->data().HasDepth(keypoint_index) ? 2 : 1;
  ClassLogProbs observation;
  if (fuse_labels && keyframe->keypoint_labels.Get(static_cast<size_t>(keypoint_index), &observation)) {
    labels_.Fuse(observation);
  }
}

void MapPoint::EraseObservation(KeyFrame* keyframe) {
  const auto it = observations_.find(keyframe);
  if (it == observations_.end()) return;
  num_observations_ -= keyframe->data().HasDepth(it->second) ? 2 : 1;
  observations_.erase(it);
  if (reference_keyframe_ == keyframe && !observations_.empty())
    reference_keyframe_ = observations_.begin()->first;
  // Two cameras are the minimum for a point to stay constrained.
  if (num_observations_ <= 2) SetBad();
}

int MapPoint::IndexIn(const KeyFrame* keyframe) const {
  if (keyframe == nullptr) return -1;
  const auto it = observations_.find(const_cast<KeyFrame*>(keyframe));
  return it == observations_.end() ? -1 : it->second;
}

void MapPoint::SetBad() {
  if (bad_) return;
  bad_ = true;
  const auto observations = std::move(observations_);
  observations_.clear();
  num_observations_ = 0;
  for (const auto& [keyframe, index] : observations) keyframe->SetMapPoint(index, nullptr);
}

void MapPoint::ReplaceWith(MapPoint* other) {
  if (other == this || other == nullptr) return;
  const auto observations = std::move(observations_);
  observations_.clear();
  num_observations_ = 0;
  bad_ = true;
  replaced_by_ = other;
  for (const auto& [keyframe, index] : observations) {
    if (!other->IsObservedBy(keyframe)) {
      keyframe->SetMapPoint(index, other);
      other->AddObservation(keyframe, index);
    } else {
      keyframe->SetMapPoint(index, nullptr);
    }
  }
  other->IncreaseFound(found());
  other->IncreaseVisible(visible());
  // Two independent label posteriors over a uniform prior multiply.
  other->labels_.Merge(labels_);
  other->UpdateDescriptor();
}

MapPoint* MapPoint::Resolve() {
  MapPoint* p = this;
  while (p->replaced_by_ != nullptr) p = p->replaced_by_;
  return p;
}

void MapPoint::UpdateDescriptor() {
  if (bad_ || observations_.empty()) return;
  std::vector<const Descriptor*> descriptors;
  descriptors.reserve(observations_.size());
  for (const auto& [keyframe, index] : observations_) {
    if (!keyframe->is_bad())
      descriptors.push_back(&keyframe->features().descriptors[static_cast<size_t>(index)]);
  }
  if (descriptors.empty()) return;
  const size_t n = descriptors.size();
  std::vector<int> distances(n * n, 0);
  for (size_t i = 0; i < n; ++i) {
    for (size_t j = i + 1; j < n; ++j) {
      distances[i * n + j] = distances[j * n + i] = HammingDistance(*descriptors[i], *descriptors[j]);
    }
  }
  int best_median = std::numeric_limits<int>::max();
  size_t best = 0;
  std::vector<int> row(n);
  for (size_t i = 0; i < n; ++i) {
    std::copy(distances.begin() + static_cast<long>(i * n),
              distances.begin() + static_cast<long>((i + 1) * n), row.begin());
    std::nth_element(row.begin(), row.begin() + static_cast<long>((n - 1) / 2), row.end());
    const int median = row[(n - 1) / 2];
    if (median < best_median) {
      best_median = median;
      best = i;
    }
  }
  descriptor_ = *descriptors[best];
}

void MapPoint::UpdateNormalAndDepth() {
  if (bad_ || observations_.empty() || reference_keyframe_ == nullptr) return;
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  int n = 0;
  for (const auto& [keyframe, index] : observations_) {
    const Eigen::Vector3d ray = position_ - keyframe->center();
    const double norm = ray.norm();
    if (norm > 0) {
      normal += ray / norm;
      ++n;
    }
  }
  if (n == 0) return;
  const int ref_index = IndexIn(reference_keyframe_);
  if (ref_index < 0) return;
  const auto& pyramid = reference_keyframe_->features().pyramid;
  const int level = reference_keyframe_->features().keypoints[static_cast<size_t>(ref_index)].level;
  const float distance = static_cast<float>((position_ - reference_keyframe_->center()).norm());
  max_distance_ = distance * pyramid.scale[static_cast<size_t>(level)];
  min_distance_ = max_distance_ / pyramid.scale[static_cast<size_t>(pyramid.num_levels - 1)];
  normal_ = normal.normalized();
}

int MapPoint::PredictLevel(float distance, const PyramidGeometry& pyramid) const {
  return pyramid.PredictLevel(distance, max_distance_);
}

float MapPoint::FoundRatio() const {
  const int v = visible();
  return v > 0 ? static_cast<float>(found()) / static_cast<float>(v) : 0.0f;
}

}  // namespace semslam
