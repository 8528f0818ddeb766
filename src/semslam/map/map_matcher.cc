#include "semslam/map/map_matcher.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "semslam/features/matching.h"
#include "semslam/place/bow_matching.h"

namespace semslam {
namespace {

constexpr int kHigh = MatcherThresholds::kHigh;
constexpr int kLow = MatcherThresholds::kLow;

// Search radius by how frontal the view is: oblique views get a wider window.
float RadiusByViewingCos(float view_cos) { return view_cos > 0.998f ? 2.5f : 4.0f; }

struct Projection {
  Eigen::Vector3d point_in_camera;
  float u = 0, v = 0;
};

// Projects a world point with a (similarity) camera_from_world; false if behind or outside the image.
bool ProjectInto(const FrameData& data, const Sim3d& camera_from_world, const Eigen::Vector3d& world,
                 Projection* out) {
  out->point_in_camera = camera_from_world * world;
  if (out->point_in_camera.z() <= 0) return false;
  const Eigen::Vector2d uv = data.camera.Project(out->point_in_camera);
  out->u = static_cast<float>(uv.x());
  out->v = static_cast<float>(uv.y());
  return data.InBounds(out->u, out->v);
}

}  // namespace

int SearchLocalPoints(Frame& frame, const std::vector<MapPoint*>& points, float radius_factor,
                      float nn_ratio) {
  const FrameData& data = frame.data();
  const auto& pyramid = data.features.pyramid;
  int matches = 0;
  for (MapPoint* p : points) {
    if (!p->track_in_view || p->is_bad()) continue;
    const int level = p->track_level;
    const float radius = RadiusByViewingCos(p->track_view_cos) * radius_factor * pyramid.scale[level];
    const auto candidates = data.grid.FeaturesInArea(p->track_u, p->track_v, radius, level - 1, level);
    if (candidates.empty()) continue;
    const Descriptor& d = p->descriptor();
    int best = 256, second = 256, best_level = -1, second_level = -1, best_index = -1;
    for (const auto index : candidates) {
      const size_t i = static_cast<size_t>(index);
      if (frame.map_points[i] != nullptr && frame.map_points[i]->num_observations() > 0) continue;
      if (p->track_right_u >= 0 && !data.right_u.empty() && data.right_u[i] >= 0 &&
          std::abs(p->track_right_u - data.right_u[i]) > radius) {
        continue;
      }
      const int dist = HammingDistance(d, data.features.descriptors[i]);
      if (dist < best) {
        second = best;
        second_level = best_level;
        best = dist;
        best_level = data.features.keypoints[i].level;
        best_index = static_cast<int>(index);
      } else if (dist < second) {
        second = dist;
        second_level = data.features.keypoints[i].level;
      }
    }
    if (best > kHigh) continue;
    if (best_level == second_level && static_cast<float>(best) > nn_ratio * static_cast<float>(second))
      continue;
    frame.map_points[static_cast<size_t>(best_index)] = p;
    ++matches;
  }
  return matches;
}

int SearchFromLastFrame(Frame& current, const Frame& last, float radius, bool monocular) {
  const FrameData& data = current.data();
  const auto& pyramid = data.features.pyramid;
  RotationHistogram histogram;
  const Sim3d camera_from_world(current.camera_from_world());
  // Current camera centre in the last camera's frame: tells forward from backward motion (stereo).
  const Eigen::Vector3d center_in_last = last.camera_from_world() * current.center();
  const double baseline = data.stereo ? data.stereo->baseline : 0.0;
  const bool forward = !monocular && center_in_last.z() > baseline;
  const bool backward = !monocular && -center_in_last.z() > baseline;
  int matches = 0;
  for (size_t i = 0; i < last.map_points.size(); ++i) {
    MapPoint* p = last.map_points[i];
    if (p == nullptr || last.outliers[i] || p->is_bad()) continue;
    Projection proj;
    if (!ProjectInto(data, camera_from_world, p->position(), &proj)) continue;
    const int last_level = last.features().keypoints[i].level;
    const float r = radius * pyramid.scale[last_level];
    int min_level = last_level - 1, max_level = last_level + 1;
    if (forward) {
      min_level = last_level;
      max_level = pyramid.num_levels - 1;
    } else if (backward) {
      min_level = 0;
      max_level = last_level;
    }
    const auto candidates = data.grid.FeaturesInArea(proj.u, proj.v, r, min_level, max_level);
    if (candidates.empty()) continue;
    const float right_u_pred =
        data.stereo ? static_cast<float>(data.stereo->ProjectRightU(proj.point_in_camera)) : -1.0f;
    int best = 256, best_index = -1;
    for (const auto index : candidates) {
      const size_t c = static_cast<size_t>(index);
      if (current.map_points[c] != nullptr && current.map_points[c]->num_observations() > 0) continue;
      if (right_u_pred >= 0 && !data.right_u.empty() && data.right_u[c] >= 0 &&
          std::abs(right_u_pred - data.right_u[c]) > r) {
        continue;
      }
      const int dist = HammingDistance(p->descriptor(), data.features.descriptors[c]);
      if (dist < best) {
        best = dist;
        best_index = static_cast<int>(index);
      }
    }
    if (best > kHigh) continue;
    current.map_points[static_cast<size_t>(best_index)] = p;
    current.outliers[static_cast<size_t>(best_index)] = false;
    ++matches;
    histogram.Add(last.features().keypoints[i].angle_deg - data.features.keypoints[best_index].angle_deg,
                  best_index);
  }
  for (const int index : histogram.Inconsistent()) {
    current.map_points[static_cast<size_t>(index)] = nullptr;
    --matches;
  }
  return matches;
}

int SearchFromKeyFrame(Frame& frame, const KeyFrame& keyframe, const std::set<MapPoint*>& already_found,
                       float radius, int max_distance) {
  const FrameData& data = frame.data();
  const auto& pyramid = data.features.pyramid;
  const Sim3d camera_from_world(frame.camera_from_world());
  const Eigen::Vector3d center = frame.center();
  RotationHistogram histogram;
  int matches = 0;
  const auto& kf_points = keyframe.map_points();
  for (size_t i = 0; i < kf_points.size(); ++i) {
    MapPoint* p = kf_points[i];
    if (p == nullptr || p->is_bad() || already_found.count(p)) continue;
    Projection proj;
    if (!ProjectInto(data, camera_from_world, p->position(), &proj)) continue;
    const float distance = static_cast<float>((p->position() - center).norm());
    if (distance < p->min_distance() || distance > p->max_distance()) continue;
    const int level = p->PredictLevel(distance, pyramid);
    const auto candidates =
        data.grid.FeaturesInArea(proj.u, proj.v, radius * pyramid.scale[level], level - 1, level + 1);
    int best = 256, best_index = -1;
    for (const auto index : candidates) {
      if (frame.map_points[static_cast<size_t>(index)] != nullptr) continue;
      const int dist =
          HammingDistance(p->descriptor(), data.features.descriptors[static_cast<size_t>(index)]);
      if (dist < best) {
        best = dist;
        best_index = static_cast<int>(index);
      }
    }
    if (best > max_distance) continue;
    frame.map_points[static_cast<size_t>(best_index)] = p;
    ++matches;
    histogram.Add(keyframe.features().keypoints[i].angle_deg - data.features.keypoints[best_index].angle_deg,
                  best_index);
  }
  for (const int index : histogram.Inconsistent()) {
    frame.map_points[static_cast<size_t>(index)] = nullptr;
    --matches;
  }
  return matches;
}

int SearchByBow(const KeyFrame& keyframe, const Frame& frame, std::vector<MapPoint*>& matches, float nn_ratio,
                bool check_orientation) {
  matches.assign(frame.num_features(), nullptr);
  const auto& kf_features = keyframe.features();
  const auto& f_features = frame.features();
  RotationHistogram histogram;
  int count = 0;
  ForEachSharedNode(
      keyframe.feature_vector, frame.feature_vector, [&](const auto& kf_indices, const auto& f_indices) {
        for (const auto kf_index : kf_indices) {
          MapPoint* p = keyframe.map_point(static_cast<int>(kf_index));
          if (p == nullptr || p->is_bad()) continue;
          const Descriptor& d = kf_features.descriptors[static_cast<size_t>(kf_index)];
          int best = 256, second = 256, best_index = -1;
          for (const auto f_index : f_indices) {
            if (matches[static_cast<size_t>(f_index)] != nullptr) continue;
            const int dist = HammingDistance(d, f_features.descriptors[static_cast<size_t>(f_index)]);
            if (dist < best) {
              second = best;
              best = dist;
              best_index = static_cast<int>(f_index);
            } else if (dist < second) {
              second = dist;
            }
          }
          if (best > kLow || static_cast<float>(best) >= nn_ratio * static_cast<float>(second)) continue;
          matches[static_cast<size_t>(best_index)] = p;
          ++count;
          histogram.Add(kf_features.keypoints[static_cast<size_t>(kf_index)].angle_deg -
                            f_features.keypoints[static_cast<size_t>(best_index)].angle_deg,
                        best_index);
        }
      });
  if (check_orientation) {
    for (const int index : histogram.Inconsistent()) {
      matches[static_cast<size_t>(index)] = nullptr;
      --count;
    }
  }
  return count;
}

int SearchByBow(const KeyFrame& kf1, const KeyFrame& kf2, std::vector<MapPoint*>& matches12, float nn_ratio) {
  matches12.assign(kf1.num_features(), nullptr);
  std::vector<bool> matched2(kf2.num_features(), false);
  const auto& f1 = kf1.features();
  const auto& f2 = kf2.features();
  RotationHistogram histogram;
  int count = 0;
  ForEachSharedNode(kf1.feature_vector, kf2.feature_vector, [&](const auto& indices1, const auto& indices2) {
    for (const auto i1 : indices1) {
      MapPoint* p1 = kf1.map_point(static_cast<int>(i1));
      if (p1 == nullptr || p1->is_bad()) continue;
      int best = 256, second = 256, best_index = -1;
      for (const auto i2 : indices2) {
        MapPoint* p2 = kf2.map_point(static_cast<int>(i2));
        if (matched2[static_cast<size_t>(i2)] || p2 == nullptr || p2->is_bad()) continue;
        const int dist =
            HammingDistance(f1.descriptors[static_cast<size_t>(i1)], f2.descriptors[static_cast<size_t>(i2)]);
        if (dist < best) {
          second = best;
          best = dist;
          best_index = static_cast<int>(i2);
        } else if (dist < second) {
          second = dist;
        }
      }
      if (best > kLow || static_cast<float>(best) >= nn_ratio * static_cast<float>(second)) continue;
      matches12[static_cast<size_t>(i1)] = kf2.map_point(best_index);
      matched2[static_cast<size_t>(best_index)] = true;
      ++count;
      histogram.Add(f1.keypoints[static_cast<size_t>(i1)].angle_deg -
                        f2.keypoints[static_cast<size_t>(best_index)].angle_deg,
                    static_cast<int>(i1));
    }
  });
  for (const int index : histogram.Inconsistent()) {
    matches12[static_cast<size_t>(index)] = nullptr;
    --count;
  }
  return count;
}

std::vector<std::pair<int, int>> SearchForTriangulation(const KeyFrame& kf1, const KeyFrame& kf2,
                                                        const Eigen::Matrix3d& f21, bool only_stereo) {
  const auto& d1 = kf1.data();
  const auto& d2 = kf2.data();
  const auto& pyramid = d2.features.pyramid;
  // Epipole: the centre of camera 1 seen from camera 2.
  const Eigen::Vector3d c1_in_2 = kf2.camera_from_world() * kf1.center();
  const Eigen::Vector2d epipole = d2.camera.Project(c1_in_2);
  std::vector<int> match12(d1.features.size(), -1);
  std::vector<bool> taken2(d2.features.size(), false);
  RotationHistogram histogram;
  ForEachSharedNode(kf1.feature_vector, kf2.feature_vector, [&](const auto& indices1, const auto& indices2) {
    for (const auto i1 : indices1) {
      const size_t a = static_cast<size_t>(i1);
      if (kf1.map_point(static_cast<int>(a)) != nullptr) continue;
      const bool stereo1 = d1.HasDepth(static_cast<int>(a));
      if (only_stereo && !stereo1) continue;
      const Keypoint& kp1 = d1.features.keypoints[a];
      const Eigen::Vector3d x1(kp1.pixel.x(), kp1.pixel.y(), 1.0);
      const Eigen::Vector3d line = f21 * x1;  // epipolar line in image 2
      const double line_norm2 = line.x() * line.x() + line.y() * line.y();
      if (line_norm2 <= 0) continue;
      int best = kLow + 1, best_index = -1;
      for (const auto i2 : indices2) {
        const size_t b = static_cast<size_t>(i2);
        if (taken2[b] || kf2.map_point(static_cast<int>(b)) != nullptr) continue;
        const bool stereo2 = d2.HasDepth(static_cast<int>(b));
        if (only_stereo && !stereo2) continue;
        const int dist = HammingDistance(d1.features.descriptors[a], d2.features.descriptors[b]);
        if (dist >= best) continue;
        const Keypoint& kp2 = d2.features.keypoints[b];
        if (!stereo1 && !stereo2) {
          // Points near the epipole have no depth resolution.
          const double ex = epipole.x() - kp2.pixel.x(), ey = epipole.y() - kp2.pixel.y();
          if (ex * ex + ey * ey < 100.0 * pyramid.scale[kp2.level]) continue;
        }
        const double num = line.x() * kp2.pixel.x() + line.y() * kp2.pixel.y() + line.z();
        if (num * num / line_norm2 >= 3.84 * pyramid.sigma2[kp2.level]) continue;
        best = dist;
        best_index = static_cast<int>(b);
      }
      if (best_index < 0) continue;
      match12[a] = best_index;
      taken2[static_cast<size_t>(best_index)] = true;
      histogram.Add(kp1.angle_deg - d2.features.keypoints[static_cast<size_t>(best_index)].angle_deg,
                    static_cast<int>(a));
    }
  });
  for (const int index : histogram.Inconsistent()) match12[static_cast<size_t>(index)] = -1;
  std::vector<std::pair<int, int>> pairs;
  for (size_t i = 0; i < match12.size(); ++i) {
    if (match12[i] >= 0) pairs.emplace_back(static_cast<int>(i), match12[i]);
  }
  return pairs;
}

namespace {

// Finds the keypoint of `keyframe` that best matches `p` projected with `camera_from_world`, checking
// distance range, viewing angle and reprojection error. Returns -1 when none qualifies.
int FindFuseCandidate(const KeyFrame& keyframe, const Sim3d& camera_from_world, const Eigen::Vector3d& center,
                      const MapPoint* p, float radius, bool check_reprojection) {
  const FrameData& data = keyframe.data();
  const auto& pyramid = data.features.pyramid;
  Projection proj;
  if (!ProjectInto(data, camera_from_world, p->position(), &proj)) return -1;
  const Eigen::Vector3d ray = p->position() - center;
  const float distance = static_cast<float>(ray.norm());
  if (distance < p->min_distance() || distance > p->max_distance()) return -1;
  if (ray.dot(p->normal()) < 0.5 * distance) return -1;  // viewing angle over 60 degrees
  const int level = p->PredictLevel(distance, pyramid);
  const float r = radius * pyramid.scale[level];
  const auto candidates = data.grid.FeaturesInArea(proj.u, proj.v, r, -1, -1);
  const float right_u_pred =
      data.stereo ? static_cast<float>(data.stereo->ProjectRightU(proj.point_in_camera)) : -1.0f;
  int best = 256, best_index = -1;
  for (const auto index : candidates) {
    const size_t i = static_cast<size_t>(index);
    const Keypoint& kp = data.features.keypoints[i];
    if (kp.level < level - 1 || kp.level > level) continue;
    if (check_reprojection) {
      const float ex = proj.u - kp.pixel.x(), ey = proj.v - kp.pixel.y();
      if (data.HasDepth(static_cast<int>(i)) && right_u_pred >= 0) {
        const float er = right_u_pred - data.right_u[i];
        if ((ex * ex + ey * ey + er * er) * pyramid.inv_sigma2[kp.level] > 7.8f) continue;
      } else if ((ex * ex + ey * ey) * pyramid.inv_sigma2[kp.level] > 5.99f) {
        continue;
      }
    }
    const int dist = HammingDistance(p->descriptor(), data.features.descriptors[i]);
    if (dist < best) {
      best = dist;
      best_index = static_cast<int>(index);
    }
  }
  return best <= kLow ? best_index : -1;
}

}  // namespace

int Fuse(KeyFrame* keyframe, const std::vector<MapPoint*>& points, float radius) {
  const Sim3d camera_from_world(keyframe->camera_from_world());
  const Eigen::Vector3d center = keyframe->center();
  int fused = 0;
  for (MapPoint* p : points) {
    if (p == nullptr || p->is_bad() || p->IsObservedBy(keyframe)) continue;
    const int index = FindFuseCandidate(*keyframe, camera_from_world, center, p, radius, true);
    if (index < 0) continue;
    MapPoint* existing = keyframe->map_point(index);
    if (existing != nullptr && !existing->is_bad()) {
      if (existing->num_observations() > p->num_observations()) {
        p->ReplaceWith(existing);
      } else {
        existing->ReplaceWith(p);
      }
    } else {
      p->AddObservation(keyframe, index);
      keyframe->SetMapPoint(index, p);
    }
    ++fused;
  }
  return fused;
}

int FuseWithSim3(const KeyFrame& keyframe, const Sim3d& camera_from_world,
                 const std::vector<MapPoint*>& points, float radius, std::vector<MapPoint*>& replace) {
  replace.assign(points.size(), nullptr);
  const Eigen::Vector3d center = camera_from_world.Inverse().translation;
  int fused = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    const MapPoint* p = points[i];
    if (p == nullptr || p->is_bad() || p->IsObservedBy(&keyframe)) continue;
    const int index = FindFuseCandidate(keyframe, camera_from_world, center, p, radius, false);
    if (index < 0) continue;
    MapPoint* existing = keyframe.map_point(index);
    if (existing != nullptr && !existing->is_bad()) replace[i] = existing;
    ++fused;
  }
  return fused;
}

int SearchBySim3Projection(const KeyFrame& keyframe, const Sim3d& camera_from_world,
                           const std::vector<MapPoint*>& points, std::vector<MapPoint*>& matched,
                           int radius) {
  const FrameData& data = keyframe.data();
  const auto& pyramid = data.features.pyramid;
  const Eigen::Vector3d center = camera_from_world.Inverse().translation;
  std::set<MapPoint*> already(matched.begin(), matched.end());
  already.erase(nullptr);
  int count = 0;
  for (MapPoint* p : points) {
    if (p == nullptr || p->is_bad() || already.count(p)) continue;
    Projection proj;
    if (!ProjectInto(data, camera_from_world, p->position(), &proj)) continue;
    const Eigen::Vector3d ray = p->position() - center;
    const float distance = static_cast<float>(ray.norm());
    if (distance < p->min_distance() || distance > p->max_distance()) continue;
    if (ray.dot(p->normal()) < 0.5 * distance) continue;
    const int level = p->PredictLevel(distance, pyramid);
    const auto candidates =
        data.grid.FeaturesInArea(proj.u, proj.v, static_cast<float>(radius) * pyramid.scale[level], -1, -1);
    int best = 256, best_index = -1;
    for (const auto index : candidates) {
      const size_t i = static_cast<size_t>(index);
      if (matched[i] != nullptr) continue;
      const int kp_level = data.features.keypoints[i].level;
      if (kp_level < level - 1 || kp_level > level) continue;
      const int dist = HammingDistance(p->descriptor(), data.features.descriptors[i]);
      if (dist < best) {
        best = dist;
        best_index = static_cast<int>(index);
      }
    }
    if (best > kLow) continue;
    matched[static_cast<size_t>(best_index)] = p;
    ++count;
  }
  return count;
}

int SearchBySim3(const KeyFrame& kf1, const KeyFrame& kf2, std::vector<MapPoint*>& matches12,
                 const Sim3d& kf1_from_kf2, float radius) {
  const Sim3d kf2_from_kf1 = kf1_from_kf2.Inverse();
  const auto& points1 = kf1.map_points();
  const auto& points2 = kf2.map_points();
  std::set<MapPoint*> already1, already2;
  for (size_t i = 0; i < matches12.size(); ++i) {
    if (matches12[i] != nullptr) {
      already1.insert(points1[i]);
      already2.insert(matches12[i]);
    }
  }
  // Projects the points of `src` (in the source camera frame) into `dst` with dst_from_src; returns for each
  // source keypoint the best destination keypoint index, or -1.
  auto project = [&](const KeyFrame& src, const KeyFrame& dst, const Sim3d& dst_from_src,
                     const std::set<MapPoint*>& skip) {
    std::vector<int> result(src.num_features(), -1);
    const FrameData& data = dst.data();
    const auto& pyramid = data.features.pyramid;
    for (size_t i = 0; i < src.num_features(); ++i) {
      MapPoint* p = src.map_point(static_cast<int>(i));
      if (p == nullptr || p->is_bad() || skip.count(p)) continue;
      const Eigen::Vector3d in_src = src.camera_from_world() * p->position();
      const Eigen::Vector3d in_dst = dst_from_src * in_src;
      if (in_dst.z() <= 0) continue;
      const Eigen::Vector2d uv = data.camera.Project(in_dst);
      if (!data.InBounds(static_cast<float>(uv.x()), static_cast<float>(uv.y()))) continue;
      const float distance = static_cast<float>(in_dst.norm());
      if (distance < p->min_distance() || distance > p->max_distance()) continue;
      const int level = p->PredictLevel(distance, pyramid);
      const auto candidates = data.grid.FeaturesInArea(static_cast<float>(uv.x()), static_cast<float>(uv.y()),
                                                       radius * pyramid.scale[level], -1, -1);
      int best = 256, best_index = -1;
      for (const auto index : candidates) {
        const int kp_level = data.features.keypoints[static_cast<size_t>(index)].level;
        if (kp_level < level - 1 || kp_level > level) continue;
        const int dist =
            HammingDistance(p->descriptor(), data.features.descriptors[static_cast<size_t>(index)]);
        if (dist < best) {
          best = dist;
          best_index = static_cast<int>(index);
        }
      }
      if (best <= kHigh) result[i] = best_index;
    }
    return result;
  };
  const std::vector<int> match12 = project(kf1, kf2, kf2_from_kf1, already1);
  const std::vector<int> match21 = project(kf2, kf1, kf1_from_kf2, already2);
  int count = 0;
  for (size_t i1 = 0; i1 < match12.size(); ++i1) {
    const int i2 = match12[i1];
    if (i2 < 0 || match21[static_cast<size_t>(i2)] != static_cast<int>(i1)) continue;
    matches12[i1] = points2[static_cast<size_t>(i2)];
    ++count;
  }
  return count;
}

}  // namespace semslam
