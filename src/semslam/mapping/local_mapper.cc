#include "semslam/mapping/local_mapper.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <set>
#include <unordered_map>

#include "semslam/core/error.h"
#include "semslam/geometry/triangulation.h"
#include "semslam/map/map_matcher.h"
#include "semslam/mapping/map_optimization.h"
#include "semslam/optim/bundle_adjustment.h"
#include "semslam/place/keyframe_database.h"
#include "semslam/place/vocabulary.h"

namespace semslam {

void LocalMapperOptions::Check() const {
  Require(close_depth_baselines > 0, "local mapper: close_depth_baselines must be positive");
  Require(triangulation_neighbours_mono > 0 && triangulation_neighbours_stereo > 0,
          "local mapper: triangulation neighbour counts must be positive");
  Require(redundant_keyframe_ratio > 0 && redundant_keyframe_ratio <= 1,
          "local mapper: redundant_keyframe_ratio must be in (0, 1]");
  Require(local_ba_iterations > 0, "local mapper: local_ba_iterations must be positive");
  Require(min_parallax_deg >= 0 && min_parallax_deg < 90,
          "local mapper: min_parallax_deg must be in [0, 90)");
}

LocalMapper::LocalMapper(const LocalMapperOptions& options, Map& map, const Vocabulary& vocabulary,
                         KeyFrameDatabase& database, TimingRegistry& timing)
    : options_(options), map_(map), vocabulary_(vocabulary), database_(database), timing_(timing) {
  options_.Check();
}

LocalMapper::~LocalMapper() {
  RequestFinish();
  Join();
}

void LocalMapper::AddKeyFrameListener(std::function<void(KeyFrame*)> listener) {
  listeners_.push_back(std::move(listener));
}

void LocalMapper::Start() {
  if (thread_.joinable()) return;
  finish_requested_ = false;
  finished_ = false;
  thread_ = std::thread([this] { Run(); });
}

void LocalMapper::RequestFinish() {
  finish_requested_ = true;
  Release();
  queue_cv_.notify_all();
}

void LocalMapper::Join() {
  if (thread_.joinable()) thread_.join();
}

void LocalMapper::InsertKeyFrame(KeyFrame* keyframe) {
  {
    std::lock_guard lock(queue_mutex_);
    queue_.push_back(keyframe);
  }
  if (options_.yield_to_new_keyframes) abort_ba_ = true;
  queue_cv_.notify_all();
}

size_t LocalMapper::KeyframesInQueue() const {
  std::lock_guard lock(queue_mutex_);
  return queue_.size();
}

bool LocalMapper::HasNewKeyFrames() const { return KeyframesInQueue() > 0; }

void LocalMapper::WaitUntilIdle() {
  std::unique_lock lock(queue_mutex_);
  queue_cv_.wait(lock, [this] { return IdleLocked() || !thread_.joinable(); });
}

bool LocalMapper::WaitUntilIdleFor(double seconds) {
  std::unique_lock lock(queue_mutex_);
  return queue_cv_.wait_for(lock, std::chrono::duration<double>(std::max(0.0, seconds)),
                            [this] { return IdleLocked() || !thread_.joinable(); });
}

bool LocalMapper::IsIdle() const {
  std::lock_guard lock(queue_mutex_);
  return IdleLocked();
}

void LocalMapper::WaitForQueueAtMost(size_t n) {
  std::unique_lock lock(queue_mutex_);
  queue_cv_.wait(lock, [this, n] { return queue_.size() <= n || !thread_.joinable() || finished_.load(); });
}

void LocalMapper::RequestStop() {
  std::lock_guard lock(stop_mutex_);
  ++stop_requests_;
  abort_ba_ = true;
  queue_cv_.notify_all();
}

bool LocalMapper::IsStopped() const {
  std::lock_guard lock(stop_mutex_);
  return stopped_;
}

bool LocalMapper::StopRequested() const {
  std::lock_guard lock(stop_mutex_);
  return stop_requests_ > 0;
}

void LocalMapper::Release() {
  {
    std::lock_guard lock(stop_mutex_);
    if (stop_requests_ > 0) --stop_requests_;
    if (stop_requests_ > 0) return;  // another holder still needs the mapper stopped
    stopped_ = false;
  }
  // Taking the queue mutex orders this with the stopped thread's check of IsStopped() before it waits.
  { std::lock_guard lock(queue_mutex_); }
  queue_cv_.notify_all();
}

void LocalMapper::WaitWhilePaused() {
  // Release() notifies under the queue mutex, so no wake-up is lost between the check and the wait.
  std::unique_lock lock(queue_mutex_);
  queue_cv_.wait(lock, [this] { return !StopRequested() || !thread_.joinable() || finished_.load(); });
}

bool LocalMapper::SetNotStop(bool value) {
  std::lock_guard lock(stop_mutex_);
  if (value && stopped_) return false;
  not_stop_ = value;
  return true;
}

bool LocalMapper::StopIfRequested() {
  std::lock_guard lock(stop_mutex_);
  if (stop_requests_ > 0 && !not_stop_) {
    stopped_ = true;
    return true;
  }
  return false;
}

void LocalMapper::Reset() {
  std::lock_guard lock(queue_mutex_);
  queue_.clear();
  current_ = nullptr;
}

void LocalMapper::Run() {
  while (true) {
    accept_keyframes_ = false;
    if (HasNewKeyFrames()) {
      {
        std::lock_guard lock(queue_mutex_);
        busy_ = true;
      }
      Stopwatch watch;
      ProcessNewKeyFrame();
      CullRecentPoints();
      CreateNewMapPoints();
      if (!NewerKeyFramesWaiting()) SearchInNeighbours();
      abort_ba_ = false;
      if (!NewerKeyFramesWaiting() && !StopRequested()) {
        LocalBundleAdjustment();
        CullKeyFrames();
      }
      timing_.Add("local_mapping", watch.ElapsedMs());
      ++num_processed_;
      for (const auto& listener : listeners_) listener(current_);
      {
        std::lock_guard lock(queue_mutex_);
        busy_ = false;
      }
      queue_cv_.notify_all();
    } else if (StopIfRequested()) {
      std::unique_lock lock(queue_mutex_);
      queue_cv_.notify_all();
      queue_cv_.wait(lock, [this] { return !IsStopped() || finish_requested_.load(); });
    }
    accept_keyframes_ = true;
    if (finish_requested_ && !HasNewKeyFrames()) break;
    std::unique_lock lock(queue_mutex_);
    queue_cv_.wait_for(lock, std::chrono::milliseconds(3),
                       [this] { return !queue_.empty() || finish_requested_.load() || StopRequested(); });
  }
  std::lock_guard lock(queue_mutex_);
  busy_ = false;
  finished_ = true;
  queue_cv_.notify_all();
}

void LocalMapper::ProcessNewKeyFrame() {
  ScopedTimer timer(timing_, "mapping_process_keyframe");
  {
    std::lock_guard lock(queue_mutex_);
    current_ = queue_.front();
    queue_.pop_front();
  }
  queue_cv_.notify_all();
  // The bag of words needs only the keyframe's own (immutable) descriptors: no lock.
  if (!current_->has_bow) {
    vocabulary_.Transform(current_->features().descriptors, &current_->bow, &current_->feature_vector);
    current_->has_bow = true;
  }
  auto lock = map_.WriteLock();
  for (size_t i = 0; i < current_->num_features(); ++i) {
    MapPoint* p = current_->map_point(static_cast<int>(i));
    if (p == nullptr) continue;
    if (p->is_bad()) {
      current_->SetMapPoint(static_cast<int>(i), nullptr);
      continue;
    }
    if (!p->IsObservedBy(current_)) {
      p->AddObservation(current_, static_cast<int>(i));
      p->UpdateNormalAndDepth();
      p->UpdateDescriptor();
    } else if (p->IndexIn(current_) != static_cast<int>(i)) {
      current_->SetMapPoint(static_cast<int>(i), nullptr);  // the point is already matched elsewhere here
    } else {
      // Created by tracking for this keyframe (stereo): cull it like the mapper's own new points.
      map_.recent_points.push_back(p);
    }
  }
  current_->UpdateConnections();
  database_.Add(current_->id(), current_->bow);
}

void LocalMapper::CullRecentPoints() {
  ScopedTimer timer(timing_, "mapping_point_culling");
  auto lock = map_.WriteLock();
  const int min_observations = options_.monocular ? 2 : 3;
  const std::uint64_t current_id = current_->id();
  auto& recent = map_.recent_points;
  size_t kept = 0;
  for (MapPoint* p : recent) {
    bool keep = true;
    if (p->is_bad()) {
      keep = false;
    } else if (p->FoundRatio() < 0.25f) {
      p->SetBad();
      keep = false;
    } else if (current_id >= p->first_keyframe_id() + 2 && p->num_observations() <= min_observations) {
      p->SetBad();
      keep = false;
    } else if (current_id >= p->first_keyframe_id() + 3) {
      keep = false;  // old enough: no longer on probation
    }
    if (p->is_bad()) map_.EraseMapPoint(p);
    if (keep) recent[kept++] = p;
  }
  recent.resize(kept);
}

namespace {

Eigen::Matrix3d FundamentalFromPoses(const KeyFrame& kf1, const KeyFrame& kf2) {
  // F21 maps pixels of kf1 to epipolar lines in kf2: F21 = K^-T [t21]x R21 K^-1.
  const Rigid3d kf2_from_kf1 = kf2.camera_from_world() * kf1.world_from_camera();
  const Eigen::Matrix3d k_inv = kf1.camera().K().inverse();
  const Eigen::Matrix3d k2_inv = kf2.camera().K().inverse();
  return k2_inv.transpose() * SkewSymmetric(kf2_from_kf1.translation) *
         kf2_from_kf1.rotation.toRotationMatrix() * k_inv;
}

// Whether the keyframe's segmentation saw a moving class at the keypoint.
bool IsDynamicKeypoint(const KeyFrame& keyframe, int index) {
  ClassLogProbs observation;
  return keyframe.keypoint_labels.Get(static_cast<size_t>(index), &observation) &&
         DynamicProbability(observation.data()) > 0.5f;
}

struct NewPoint {
  Eigen::Vector3d position;
  KeyFrame* other;
  int index1;
  int index2;
};

}  // namespace

void LocalMapper::CreateNewMapPoints() {
  ScopedTimer timer(timing_, "mapping_triangulation");
  std::vector<NewPoint> created;
  {
    auto lock = map_.ReadLock();
    const size_t nn = static_cast<size_t>(options_.monocular ? options_.triangulation_neighbours_mono
                                                             : options_.triangulation_neighbours_stereo);
    const std::vector<KeyFrame*> neighbours = current_->BestCovisibles(nn);
    const KeyFrame& kf1 = *current_;
    const FrameData& d1 = kf1.data();
    const auto& pyramid = d1.features.pyramid;
    const float ratio_factor = 1.5f * pyramid.scale_factor;
    const Eigen::Vector3d c1 = kf1.center();
    const Rigid3d& t1w = kf1.camera_from_world();
    const Eigen::Matrix3d r_w1 = kf1.world_from_camera().rotation.toRotationMatrix();
    const double max_cos_parallax = std::cos(options_.min_parallax_deg * M_PI / 180.0);

    for (size_t n = 0; n < neighbours.size(); ++n) {
      if (n > 0 && NewerKeyFramesWaiting()) break;
      const KeyFrame& kf2 = *neighbours[n];
      const FrameData& d2 = kf2.data();
      const Eigen::Vector3d c2 = kf2.center();
      const double baseline = (c2 - c1).norm();
      if (!options_.monocular) {
        if (baseline < d2.stereo->baseline) continue;
      } else {
        const double median_depth = kf2.SceneDepthQuantile(2);
        if (median_depth <= 0 || baseline / median_depth < 0.01) continue;
      }
      const auto pairs = SearchForTriangulation(kf1, kf2, FundamentalFromPoses(kf1, kf2), false);
      const Rigid3d& t2w = kf2.camera_from_world();
      const Eigen::Matrix3d r_w2 = kf2.world_from_camera().rotation.toRotationMatrix();
      for (const auto& [i1, i2] : pairs) {
        if (options_.exclude_dynamic && (IsDynamicKeypoint(kf1, i1) || IsDynamicKeypoint(kf2, i2))) continue;
        const Keypoint& kp1 = d1.features.keypoints[static_cast<size_t>(i1)];
        const Keypoint& kp2 = d2.features.keypoints[static_cast<size_t>(i2)];
        const bool stereo1 = d1.HasDepth(i1), stereo2 = d2.HasDepth(i2);
        const Eigen::Vector3d b1 = d1.camera.PixelToNormalized(kp1.pixel.cast<double>()).homogeneous();
        const Eigen::Vector3d b2 = d2.camera.PixelToNormalized(kp2.pixel.cast<double>()).homogeneous();
        const Eigen::Vector3d ray1 = r_w1 * b1, ray2 = r_w2 * b2;
        const double cos_rays = ray1.dot(ray2) / (ray1.norm() * ray2.norm());
        const double cos_stereo1 =
            stereo1 ? std::cos(2.0 * std::atan2(d1.stereo->baseline / 2, d1.depth[static_cast<size_t>(i1)]))
                    : 2.0;
        const double cos_stereo2 =
            stereo2 ? std::cos(2.0 * std::atan2(d2.stereo->baseline / 2, d2.depth[static_cast<size_t>(i2)]))
                    : 2.0;
        const double cos_stereo = std::min(cos_stereo1, cos_stereo2);

        std::optional<Eigen::Vector3d> x;
        if (cos_rays < cos_stereo && cos_rays > 0 && (stereo1 || stereo2 || cos_rays < max_cos_parallax)) {
          x = TriangulatePoint(t1w, t2w, b1, b2);
        } else if (stereo1 && cos_stereo1 < cos_stereo2) {
          x = kf1.UnprojectStereo(i1);
        } else if (stereo2 && cos_stereo2 < cos_stereo1) {
          x = kf2.UnprojectStereo(i2);
        }
        if (!x) continue;
        // In front of both cameras, reprojecting within the keypoints' uncertainty.
        auto reprojects = [&](const Rigid3d& tcw, const FrameData& d, int index, const Keypoint& kp,
                              bool stereo) {
          const Eigen::Vector3d pc = tcw * *x;
          if (pc.z() <= 0) return false;
          const Eigen::Vector2d uv = d.camera.Project(pc);
          const double ex = uv.x() - kp.pixel.x(), ey = uv.y() - kp.pixel.y();
          const double inv_sigma2 = d.features.pyramid.inv_sigma2[kp.level];
          if (!stereo) return (ex * ex + ey * ey) * inv_sigma2 <= 5.991;
          const double er = d.stereo->ProjectRightU(pc) - d.right_u[static_cast<size_t>(index)];
          return (ex * ex + ey * ey + er * er) * inv_sigma2 <= 7.8;
        };
        if (!reprojects(t1w, d1, i1, kp1, stereo1) || !reprojects(t2w, d2, i2, kp2, stereo2)) continue;
        // Scale consistency between the distances and the detection levels.
        const double dist1 = (*x - c1).norm(), dist2 = (*x - c2).norm();
        if (dist1 == 0 || dist2 == 0) continue;
        const double ratio_dist = dist2 / dist1;
        const double ratio_octave = pyramid.scale[kp1.level] / d2.features.pyramid.scale[kp2.level];
        if (ratio_dist * ratio_factor < ratio_octave || ratio_dist > ratio_octave * ratio_factor) continue;
        created.push_back({*x, neighbours[n], i1, i2});
      }
    }
  }
  if (created.empty()) return;
  auto lock = map_.WriteLock();
  int added = 0;
  for (const NewPoint& np : created) {
    if (np.other->is_bad() || current_->is_bad()) continue;
    if (current_->map_point(np.index1) != nullptr || np.other->map_point(np.index2) != nullptr) continue;
    MapPoint* p = map_.AddMapPoint(np.position, current_);
    p->AddObservation(current_, np.index1);
    p->AddObservation(np.other, np.index2);
    current_->SetMapPoint(np.index1, p);
    np.other->SetMapPoint(np.index2, p);
    p->UpdateDescriptor();
    p->UpdateNormalAndDepth();
    map_.recent_points.push_back(p);
    ++added;
  }
  spdlog::debug("keyframe {}: {} new points", current_->id(), added);
}

void LocalMapper::SearchInNeighbours() {
  ScopedTimer timer(timing_, "mapping_fusion");
  auto lock = map_.WriteLock();
  const size_t nn = static_cast<size_t>(options_.monocular ? 20 : 10);
  std::vector<KeyFrame*> targets;
  for (KeyFrame* kf : current_->BestCovisibles(nn)) {
    if (kf->is_bad() || kf->fuse_target_keyframe == current_->id()) continue;
    targets.push_back(kf);
    kf->fuse_target_keyframe = current_->id();
    for (KeyFrame* second : kf->BestCovisibles(5)) {
      if (second->is_bad() || second->fuse_target_keyframe == current_->id() || second == current_) continue;
      targets.push_back(second);
      second->fuse_target_keyframe = current_->id();
    }
  }
  // The current keyframe's points into its neighbours...
  std::vector<MapPoint*> own;
  for (MapPoint* p : current_->map_points()) {
    if (p != nullptr && !p->is_bad()) own.push_back(p);
  }
  for (KeyFrame* kf : targets) Fuse(kf, own);
  // ...and the neighbours' points into the current keyframe.
  std::vector<MapPoint*> candidates;
  for (KeyFrame* kf : targets) {
    for (MapPoint* p : kf->map_points()) {
      if (p == nullptr || p->is_bad() || p->fuse_candidate_keyframe == current_->id()) continue;
      p->fuse_candidate_keyframe = current_->id();
      candidates.push_back(p);
    }
  }
  Fuse(current_, candidates);
  for (MapPoint* p : current_->map_points()) {
    if (p != nullptr && !p->is_bad()) {
      p->UpdateDescriptor();
      p->UpdateNormalAndDepth();
    }
  }
  current_->UpdateConnections();
}

void LocalMapper::LocalBundleAdjustment() {
  ScopedTimer timer(timing_, "local_ba");
  BundleAdjustmentProblem problem;
  std::vector<KeyFrame*> local, fixed, all;
  std::vector<MapPoint*> points;
  std::vector<ObservationRef> refs;
  {
    auto lock = map_.ReadLock();
    if (map_.NumKeyFrames() <= 2) return;
    // The current keyframe and its covisible keyframes move; keyframes that only see their points hold still.
    const std::uint64_t tag = current_->id();
    local.push_back(current_);
    current_->local_ba_keyframe = tag;
    for (KeyFrame* kf : current_->Covisibles()) {
      if (kf->is_bad() || kf->local_ba_keyframe == tag) continue;
      kf->local_ba_keyframe = tag;
      local.push_back(kf);
    }
    for (KeyFrame* kf : local) {
      for (MapPoint* p : kf->map_points()) {
        if (p == nullptr || p->is_bad() || p->local_ba_keyframe == tag) continue;
        p->local_ba_keyframe = tag;
        points.push_back(p);
      }
    }
    for (MapPoint* p : points) {
      for (const auto& [kf, index] : p->observations()) {
        if (kf->is_bad() || kf->local_ba_keyframe == tag || kf->fixed_ba_keyframe == tag) continue;
        kf->fixed_ba_keyframe = tag;
        fixed.push_back(kf);
      }
    }
    BuildBundleAdjustmentProblem(local, fixed, points, &problem, &refs);
  }
  if (abort_ba_) return;
  all = local;
  all.insert(all.end(), fixed.begin(), fixed.end());
  BundleAdjustmentOptions options;
  options.iterations = options_.local_ba_iterations;
  options.abort = &abort_ba_;
  options.refine_without_outliers = true;
  const BundleAdjustmentResult result = BundleAdjust(problem, options);
  auto lock = map_.WriteLock();
  if (options_.monocular) {
    // The frames kept relative to these keyframes stretch with the map around them: a young map's local BAs
    // settle its scale over its first seconds (LocalScaleChanges).
    FollowLocalScaleChanges(LocalScaleChanges(problem, all, points));
  }
  ApplyBundleAdjustment(map_, problem, result, all, points, refs, /*drop_outliers=*/true);
}

void LocalMapper::CullKeyFrames() {
  ScopedTimer timer(timing_, "mapping_keyframe_culling");
  auto lock = map_.WriteLock();
  const double close =
      current_->data().stereo ? options_.close_depth_baselines * current_->data().stereo->baseline : 0.0;
  // A copy: erasing a keyframe changes the current keyframe's covisibility list.
  const std::vector<KeyFrame*> covisibles = current_->Covisibles();
  for (KeyFrame* kf : covisibles) {
    if (kf->is_map_origin() || kf->is_bad()) continue;
    const FrameData& d = kf->data();
    int total = 0, redundant = 0;
    for (size_t i = 0; i < kf->num_features(); ++i) {
      MapPoint* p = kf->map_point(static_cast<int>(i));
      if (p == nullptr || p->is_bad()) continue;
      if (!options_.monocular && (d.depth[i] > close || d.depth[i] < 0)) continue;
      ++total;
      if (p->num_observations() <= 3) continue;
      const int level = d.features.keypoints[i].level;
      int seen = 0;
      for (const auto& [other, index] : p->observations()) {
        if (other == kf) continue;
        if (other->features().keypoints[static_cast<size_t>(index)].level <= level + 1 && ++seen >= 3) break;
      }
      if (seen >= 3) ++redundant;
    }
    if (total > 0 && redundant > options_.redundant_keyframe_ratio * total) {
      kf->SetBad();
      if (kf->is_bad()) {
        map_.EraseKeyFrame(kf);
        database_.Erase(kf->id());
      }
    }
  }
}

}  // namespace semslam
