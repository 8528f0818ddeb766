#include "semslam/map/keyframe.h"

#include <algorithm>
#include <cmath>

#include "semslam/core/error.h"
#include "semslam/map/map_point.h"

namespace semslam {
namespace {
constexpr int kCovisibilityThreshold = 15;
}  // namespace

KeyFrame::KeyFrame(std::uint64_t id, const Frame& frame)
    : id_(id),
      frame_id_(frame.id()),
      timestamp_(frame.timestamp()),
      data_(frame.shared_data()),
      map_points_(frame.map_points) {
  SetPose(frame.camera_from_world());
  for (size_t i = 0; i < map_points_.size(); ++i) {
    if (i < frame.outliers.size() && frame.outliers[i]) map_points_[i] = nullptr;
  }
  if (frame.has_bow) {
    has_bow = true;
    bow = frame.bow;
    feature_vector = frame.feature_vector;
  }
}

void KeyFrame::ReplaceData(std::shared_ptr<const FrameData> data) {
  Require(data != nullptr && data->features.size() == data_->features.size(),
          "keyframe: replaced data must hold the same keypoints");
  data_ = std::move(data);
}

void KeyFrame::SetPose(const Rigid3d& camera_from_world) {
  camera_from_world_ = camera_from_world;
  world_from_camera_ = camera_from_world.Inverse();
}

double KeyFrame::scale_correction() const {
  if (!bad_ || parent_ == nullptr) return scale_correction_;
  return scale_correction_ * parent_->scale_correction() / parent_scale_when_erased_;
}

void KeyFrame::CorrectScale(double scale) {
  Require(std::isfinite(scale) && scale > 0.0, "keyframe: a scale correction must be positive");
  if (!bad_) scale_correction_ *= scale;
}

Rigid3d KeyFrame::camera_from_parent() const {
  if (parent_ == nullptr) return camera_from_parent_;
  return Stretched(camera_from_parent_, parent_->scale_correction() / parent_scale_when_erased_);
}

void KeyFrame::EraseMapPoint(const MapPoint* point) {
  const int index = point->IndexIn(this);
  if (index >= 0 && map_points_[static_cast<size_t>(index)] == point) {
    map_points_[static_cast<size_t>(index)] = nullptr;
    return;
  }
  for (auto& p : map_points_) {
    if (p == point) p = nullptr;
  }
}

int KeyFrame::CountTrackedPoints(int min_observations) const {
  int count = 0;
  for (const MapPoint* p : map_points_) {
    if (p != nullptr && !p->is_bad() && p->num_observations() >= min_observations) ++count;
  }
  return count;
}

std::set<MapPoint*> KeyFrame::GoodMapPoints() const {
  std::set<MapPoint*> points;
  for (MapPoint* p : map_points_) {
    if (p != nullptr && !p->is_bad()) points.insert(p);
  }
  return points;
}

void KeyFrame::UpdateConnections() {
  std::map<KeyFrame*, int, ById> counter;
  for (const MapPoint* p : map_points_) {
    if (p == nullptr || p->is_bad()) continue;
    for (const auto& [other, index] : p->observations()) {
      if (other != this && !other->is_bad()) ++counter[other];
    }
  }
  if (counter.empty()) return;

  KeyFrame* best = nullptr;
  int best_weight = 0;
  std::vector<std::pair<int, KeyFrame*>> strong;
  for (const auto& [other, weight] : counter) {
    if (weight > best_weight || (weight == best_weight && best != nullptr && other->id() < best->id())) {
      best_weight = weight;
      best = other;
    }
    if (weight >= kCovisibilityThreshold) {
      strong.emplace_back(weight, other);
      other->AddConnection(this, weight);
    }
  }
  if (strong.empty()) {
    strong.emplace_back(best_weight, best);
    best->AddConnection(this, best_weight);
  }
  std::sort(strong.begin(), strong.end(), [](const auto& a, const auto& b) {
    return a.first != b.first ? a.first > b.first : a.second->id() < b.second->id();
  });
  connection_weights_ = counter;
  ordered_connections_.clear();
  ordered_weights_.clear();
  for (const auto& [weight, other] : strong) {
    ordered_connections_.push_back(other);
    ordered_weights_.push_back(weight);
  }
  if (first_connection_ && !map_origin_) {
    // The spanning-tree parent: the best covisible keyframe, preferring older ones so the tree stays causal.
    // Never one of its own descendants: a merged map's first keyframe sees only its own map's younger keyframes
    // until the maps' points are fused there, and taking one of them made a cycle (a map file that could not
    // be loaded). It stays a root until then.
    const auto best_covisible = [this](bool older_only) -> KeyFrame* {
      for (KeyFrame* candidate : ordered_connections_) {
        if ((!older_only || candidate->id() < id_) && !IsAncestorOf(candidate)) return candidate;
      }
      return nullptr;
    };
    KeyFrame* parent = best_covisible(/*older_only=*/true);
    if (parent == nullptr) parent = best_covisible(/*older_only=*/false);
    if (parent != nullptr) {
      ChangeParent(parent);
      first_connection_ = false;
    }
  }
}

void KeyFrame::AddConnection(KeyFrame* other, int weight) {
  const auto it = connection_weights_.find(other);
  if (it != connection_weights_.end() && it->second == weight) return;
  connection_weights_[other] = weight;
  UpdateBestCovisibles();
}

void KeyFrame::EraseConnection(KeyFrame* other) {
  if (connection_weights_.erase(other) > 0) UpdateBestCovisibles();
}

void KeyFrame::UpdateBestCovisibles() {
  std::vector<std::pair<int, KeyFrame*>> pairs;
  pairs.reserve(connection_weights_.size());
  for (const auto& [other, weight] : connection_weights_) pairs.emplace_back(weight, other);
  std::sort(pairs.begin(), pairs.end(), [](const auto& a, const auto& b) {
    return a.first != b.first ? a.first > b.first : a.second->id() < b.second->id();
  });
  ordered_connections_.clear();
  ordered_weights_.clear();
  for (const auto& [weight, other] : pairs) {
    ordered_connections_.push_back(other);
    ordered_weights_.push_back(weight);
  }
}

std::vector<KeyFrame*> KeyFrame::BestCovisibles(size_t n) const {
  const size_t count = std::min(n, ordered_connections_.size());
  return {ordered_connections_.begin(), ordered_connections_.begin() + static_cast<long>(count)};
}

std::vector<KeyFrame*> KeyFrame::CovisiblesWithWeightAtLeast(int weight) const {
  std::vector<KeyFrame*> out;
  for (size_t i = 0; i < ordered_connections_.size() && ordered_weights_[i] >= weight; ++i) {
    out.push_back(ordered_connections_[i]);
  }
  return out;
}

int KeyFrame::ConnectionWeight(KeyFrame* other) const {
  const auto it = connection_weights_.find(other);
  return it == connection_weights_.end() ? 0 : it->second;
}

bool KeyFrame::HasAncestor(const KeyFrame* keyframe) const {
  for (const KeyFrame* k = this; k != nullptr; k = k->parent_) {
    if (k == keyframe) return true;
  }
  return false;
}

bool KeyFrame::IsAncestorOf(const KeyFrame* keyframe) const {
  // A keyframe without children (a new one, the usual case) is no one's ancestor but its own: no walk.
  return keyframe == this || (!children_.empty() && keyframe->HasAncestor(this));
}

void KeyFrame::ChangeParent(KeyFrame* parent) {
  if (parent != nullptr && IsAncestorOf(parent)) return;  // the tree stays a tree
  if (parent_ != nullptr) parent_->children_.erase(this);
  parent_ = parent;
  if (parent_ != nullptr) parent_->children_.insert(this);
}

void KeyFrame::AddLoopEdge(KeyFrame* other) {
  not_erase_ = true;
  loop_edges_.insert(other);
}

void KeyFrame::SetErase() {
  if (loop_edges_.empty()) not_erase_ = false;
  if (to_be_erased_) SetBad();
}

void KeyFrame::SetBad() {
  if (map_origin_ || bad_) return;
  if (not_erase_) {
    to_be_erased_ = true;
    return;
  }
  for (const auto& [other, weight] : connection_weights_) other->EraseConnection(this);
  for (MapPoint* p : map_points_) {
    if (p != nullptr) p->EraseObservation(this);
  }
  connection_weights_.clear();
  ordered_connections_.clear();
  ordered_weights_.clear();

  // Re-attach each child to the candidate parent (this one's parent or an already re-attached sibling)
  // it shares the most points with.
  std::set<KeyFrame*, ById> parent_candidates;
  if (parent_ != nullptr) parent_candidates.insert(parent_);
  while (!children_.empty()) {
    KeyFrame* best_child = nullptr;
    KeyFrame* best_parent = nullptr;
    int best_weight = -1;
    for (KeyFrame* child : children_) {
      if (child->is_bad()) continue;
      for (KeyFrame* candidate : child->Covisibles()) {
        if (!parent_candidates.count(candidate)) continue;
        const int w = child->ConnectionWeight(candidate);
        if (w > best_weight) {
          best_weight = w;
          best_child = child;
          best_parent = candidate;
        }
      }
    }
    if (best_child == nullptr) break;
    best_child->ChangeParent(best_parent);
    parent_candidates.insert(best_child);
    children_.erase(best_child);
  }
  // Children without covisibility to any candidate go to this keyframe's parent.
  for (KeyFrame* child : std::set<KeyFrame*, ById>(children_)) child->ChangeParent(parent_);
  children_.clear();
  if (parent_ != nullptr) {
    parent_->children_.erase(this);
    camera_from_parent_ = camera_from_world_ * parent_->world_from_camera();
    parent_scale_when_erased_ = parent_->scale_correction();
  }
  bad_ = true;
}

double KeyFrame::SceneDepthQuantile(int q) const {
  std::vector<double> depths;
  depths.reserve(map_points_.size());
  for (const MapPoint* p : map_points_) {
    if (p != nullptr && !p->is_bad()) depths.push_back((camera_from_world_ * p->position()).z());
  }
  if (depths.empty()) return 0.0;
  const size_t k = (depths.size() - 1) / static_cast<size_t>(std::max(q, 1));
  std::nth_element(depths.begin(), depths.begin() + static_cast<long>(k), depths.end());
  return depths[k];
}

bool KeyFrame::IsInImage(const Eigen::Vector3d& world_point) const {
  const Eigen::Vector3d p = camera_from_world_ * world_point;
  if (p.z() <= 0) return false;
  const Eigen::Vector2d uv = data_->camera.Project(p);
  return data_->InBounds(static_cast<float>(uv.x()), static_cast<float>(uv.y()));
}

std::optional<Eigen::Vector3d> KeyFrame::UnprojectStereo(int index) const {
  if (!data_->HasDepth(index)) return std::nullopt;
  const auto& kp = data_->features.keypoints[static_cast<size_t>(index)];
  const Eigen::Vector3d p_cam =
      data_->camera.UnprojectDepth(kp.pixel.cast<double>(), data_->depth[static_cast<size_t>(index)]);
  return world_from_camera_ * p_cam;
}

std::pair<KeyFrame*, Rigid3d> GoodAncestor(KeyFrame* kf, Rigid3d x_from_kf, double units) {
  if (kf == nullptr) return {nullptr, {}};
  while (kf->is_bad() && kf->parent() != nullptr) {
    x_from_kf = Stretched(x_from_kf, kf->scale_correction() / units) * kf->camera_from_parent();
    kf = kf->parent();
    units = kf->scale_correction();  // camera_from_parent() is in the parent's units as they are now
  }
  if (kf->is_bad()) return {nullptr, {}};
  return {kf, Stretched(x_from_kf, kf->scale_correction() / units)};
}

}  // namespace semslam
