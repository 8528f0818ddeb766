#include "semslam/map/frame.h"

#include <algorithm>
#include <cmath>

namespace semslam {

std::shared_ptr<FrameData> MakeFrameData(const PinholeCamera& camera, const std::optional<StereoRig>& stereo,
                                         FeatureSet features, std::vector<float> right_u,
                                         std::vector<float> depth) {
  auto data = std::make_shared<FrameData>();
  data->camera = camera;
  data->camera.distortion = {};
  data->stereo = stereo;
  if (data->stereo) data->stereo->left = data->camera;
  data->min_x = 0;
  data->min_y = 0;
  data->max_x = static_cast<float>(camera.width);
  data->max_y = static_cast<float>(camera.height);
  if (!camera.distortion.IsZero()) {
    // Undistort keypoints: pixel = K * normalized. Bounds from the undistorted image corners.
    const Eigen::Matrix3d k = data->camera.K();
    for (auto& kp : features.keypoints) {
      const Eigen::Vector2d n = camera.PixelToNormalized(kp.pixel.cast<double>());
      kp.pixel = (k * n.homogeneous()).hnormalized().cast<float>();
    }
    const double w = camera.width - 1.0, h = camera.height - 1.0;
    auto undistort = [&](double u, double v) {
      const Eigen::Vector2d pixel(u, v);
      return Eigen::Vector2d((k * camera.PixelToNormalized(pixel).homogeneous()).hnormalized());
    };
    const Eigen::Vector2d tl = undistort(0, 0), tr = undistort(w, 0), bl = undistort(0, h),
                          br = undistort(w, h);
    data->min_x = static_cast<float>(std::min(tl.x(), bl.x()));
    data->max_x = static_cast<float>(std::max(tr.x(), br.x()));
    data->min_y = static_cast<float>(std::min(tl.y(), tr.y()));
    data->max_y = static_cast<float>(std::max(bl.y(), br.y()));
  }
  data->features = std::move(features);
  data->right_u = std::move(right_u);
  data->depth = std::move(depth);
  data->grid = FeatureGrid(data->features, data->min_x, data->min_y, data->max_x, data->max_y);
  return data;
}

Frame::Frame(std::uint64_t id, double timestamp, std::shared_ptr<const FrameData> data)
    : id_(id), timestamp_(timestamp), data_(std::move(data)) {
  // Not in the initializer list: these members are declared before data_.
  map_points.assign(data_->features.size(), nullptr);
  outliers.assign(data_->features.size(), false);
}

void Frame::SetPose(const Rigid3d& camera_from_world) {
  camera_from_world_ = camera_from_world;
  world_from_camera_ = camera_from_world.Inverse();
}

void Frame::ClearMatches() {
  std::fill(map_points.begin(), map_points.end(), nullptr);
  std::fill(outliers.begin(), outliers.end(), false);
  reference_keyframe = nullptr;
}

int Frame::CountMatches() const {
  int n = 0;
  for (size_t i = 0; i < map_points.size(); ++i) {
    if (map_points[i] != nullptr && !outliers[i]) ++n;
  }
  return n;
}

}  // namespace semslam
