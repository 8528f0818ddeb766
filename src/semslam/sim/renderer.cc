#include "semslam/sim/renderer.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "semslam/core/error.h"
#include "semslam/semantics/class_table.h"
#include "semslam/sim/random.h"
#include "semslam/sim/texture.h"

namespace semslam::sim {
namespace {

constexpr double kPi = 3.14159265358979323846;

float SkyGrey(const Eigen::Vector3f& dir) {
  const float e = std::max(0.0f, dir.z());
  return 212.0f - 70.0f * std::sqrt(e) + 8.0f * e;
}

}  // namespace

void RenderOptions::Check() const {
  Require(std::isfinite(sensor_noise) && sensor_noise >= 0 && sensor_noise <= 50,
          "RenderOptions.sensor_noise must be in [0, 50] grey levels");
  Require(std::isfinite(max_distance) && max_distance >= 10, "RenderOptions.max_distance must be >= 10 m");
  Require(std::isfinite(haze_distance) && haze_distance > 0, "RenderOptions.haze_distance must be > 0");
  Require(std::isfinite(ambient) && ambient >= 0 && ambient <= 2, "RenderOptions.ambient must be in [0, 2]");
  Require(std::isfinite(sun_strength) && sun_strength >= 0 && sun_strength <= 2,
          "RenderOptions.sun_strength must be in [0, 2]");
  Require(std::isfinite(sun_azimuth_deg), "RenderOptions.sun_azimuth_deg must be finite");
  Require(std::isfinite(sun_elevation_deg) && sun_elevation_deg >= 0 && sun_elevation_deg <= 90,
          "RenderOptions.sun_elevation_deg must be in [0, 90]");
}

Renderer::Renderer(const City& city, const SceneIndex& index, const PinholeCamera& camera,
                   const RenderOptions& options)
    : city_(city), index_(index), camera_(camera), options_(options) {
  camera.Check();
  options.Check();
  Require(camera.distortion.IsZero(), "Renderer: the camera must be undistorted (rectified)");
  const double az = options.sun_azimuth_deg * kPi / 180.0, el = options.sun_elevation_deg * kPi / 180.0;
  sun_ = Eigen::Vector3f(static_cast<float>(std::cos(el) * std::cos(az)),
                         static_cast<float>(std::cos(el) * std::sin(az)), static_cast<float>(std::sin(el)));
  xn_.resize(static_cast<size_t>(camera.width));
  yn_.resize(static_cast<size_t>(camera.height));
  for (int u = 0; u < camera.width; ++u)
    xn_[static_cast<size_t>(u)] = static_cast<float>((u - camera.cx) / camera.fx);
  for (int v = 0; v < camera.height; ++v)
    yn_[static_cast<size_t>(v)] = static_cast<float>((v - camera.cy) / camera.fy);
}

void Renderer::Render(const Rigid3d& town_from_camera, std::uint32_t noise_key, cv::Mat* grey,
                      cv::Mat* labels, cv::Mat* depth) const {
  Require(grey != nullptr, "Renderer::Render: grey image required");
  grey->create(camera_.height, camera_.width, CV_8UC1);
  if (labels != nullptr) labels->create(camera_.height, camera_.width, CV_8UC1);
  if (depth != nullptr) depth->create(camera_.height, camera_.width, CV_16UC1);
  const Eigen::Matrix3f rotation = town_from_camera.rotation.toRotationMatrix().cast<float>();
  const Eigen::Vector3f origin = town_from_camera.translation.cast<float>();
  const bool level = options_.column_casting && (rotation.col(1) + Eigen::Vector3f::UnitZ()).norm() < 1e-5f;
  if (level) {
    auto columns = [&](const tbb::blocked_range<int>& r) {
      RenderColumns(r.begin(), r.end(), rotation, origin, noise_key, grey, labels, depth);
    };
    if (options_.parallel) {
      tbb::parallel_for(tbb::blocked_range<int>(0, camera_.width, 16), columns);
    } else {
      columns(tbb::blocked_range<int>(0, camera_.width));
    }
    return;
  }
  auto rows = [&](const tbb::blocked_range<int>& r) {
    RenderRows(r.begin(), r.end(), rotation, origin, noise_key, grey, labels, depth);
  };
  if (options_.parallel) {
    tbb::parallel_for(tbb::blocked_range<int>(0, camera_.height, 4), rows);
  } else {
    rows(tbb::blocked_range<int>(0, camera_.height));
  }
}

Renderer::Pixel Renderer::Shade(const Eigen::Vector3f& origin, const Eigen::Vector3f& dir, float t, float z,
                                int primitive, const Eigen::Vector3f& normal, int axis) const {
  constexpr float kHazeGrey = 200.0f;
  if (primitive < -1) return {SkyGrey(dir), static_cast<std::uint8_t>(SemanticClass::kSky), 0.0f};
  SurfaceSample s;
  s.point = origin + dir * t;
  s.normal = normal;
  if (s.normal.dot(dir) > 0) s.normal = -s.normal;
  s.dir = dir;
  s.t = t;
  s.pixel_size = static_cast<float>(1.0 / camera_.fx);
  s.axis = axis;
  float albedo;
  std::uint8_t label;
  if (primitive < 0) {
    albedo = ShadeGround(city_, s);
    label = static_cast<std::uint8_t>(SemanticClass::kRoad);
  } else {
    const Primitive& p = city_.primitives[static_cast<size_t>(primitive)];
    albedo = ShadePrimitive(city_, p, s);
    label = p.label;
  }
  float light = static_cast<float>(options_.ambient) +
                static_cast<float>(options_.sun_strength) * std::max(0.0f, s.normal.dot(sun_));
  if (std::abs(s.normal.z()) < 0.5f) {
    // Ambient occlusion at the foot of walls.
    const float h = std::min(1.0f, std::max(0.0f, s.point.z() / 1.2f));
    light *= 0.82f + 0.18f * h;
  }
  const float haze = 1.0f - std::exp(-t / static_cast<float>(options_.haze_distance));
  const float lit = albedo * light;
  return {lit + (kHazeGrey - lit) * haze, label, z};
}

void Renderer::Store(const Pixel& pixel, int u, int v, std::uint32_t noise_key, cv::Mat* grey,
                     cv::Mat* labels, cv::Mat* depth) const {
  float value = pixel.grey;
  if (options_.sensor_noise > 0) {
    const std::uint32_t h = Hash32(noise_key, static_cast<std::uint32_t>(u), static_cast<std::uint32_t>(v));
    const float n = static_cast<float>(h & 0xFFFFu) * (1.0f / 65535.0f) +
                    static_cast<float>(h >> 16) * (1.0f / 65535.0f) - 1.0f;
    value += static_cast<float>(options_.sensor_noise * std::sqrt(6.0)) * n;
  }
  grey->at<std::uint8_t>(v, u) = static_cast<std::uint8_t>(std::clamp(value, 0.0f, 255.0f) + 0.5f);
  if (labels != nullptr) labels->at<std::uint8_t>(v, u) = pixel.label;
  if (depth != nullptr) {
    std::uint16_t d = 0;
    if (pixel.z > 0) {
      d = static_cast<std::uint16_t>(
          std::min(65535.0, std::round(static_cast<double>(pixel.z) * kDepthScale)));
      if (d == 0) d = 1;
    }
    depth->at<std::uint16_t>(v, u) = d;
  }
}

void Renderer::RenderRows(int row_begin, int row_end, const Eigen::Matrix3f& rotation,
                          const Eigen::Vector3f& origin, std::uint32_t noise_key, cv::Mat* grey,
                          cv::Mat* labels, cv::Mat* depth) const {
  const float max_distance = static_cast<float>(options_.max_distance);
  for (int v = row_begin; v < row_end; ++v) {
    const float yn = yn_[static_cast<size_t>(v)];
    for (int u = 0; u < camera_.width; ++u) {
      const float xn = xn_[static_cast<size_t>(u)];
      const float inv_norm = 1.0f / std::sqrt(xn * xn + yn * yn + 1.0f);
      const Eigen::Vector3f dir = rotation * Eigen::Vector3f(xn * inv_norm, yn * inv_norm, inv_norm);
      RayHit hit;
      Pixel pixel;
      if (index_.Intersect(origin, dir, max_distance, &hit)) {
        pixel = Shade(origin, dir, hit.t, hit.t * inv_norm, hit.primitive, hit.normal, hit.axis);
      } else {
        pixel = Shade(origin, dir, 0, 0, -2, Eigen::Vector3f::UnitZ(), 2);
      }
      Store(pixel, u, v, noise_key, grey, labels, depth);
    }
  }
}

void Renderer::RenderColumns(int col_begin, int col_end, const Eigen::Matrix3f& rotation,
                             const Eigen::Vector3f& origin, std::uint32_t noise_key, cv::Mat* grey,
                             cv::Mat* labels, cv::Mat* depth) const {
  const int rows = camera_.height;
  ColumnScratch scratch;
  std::vector<ColumnHit> hits(static_cast<size_t>(rows));
  const float yn0 = yn_.front();
  const float dyn = static_cast<float>(1.0 / camera_.fy);
  for (int u = col_begin; u < col_end; ++u) {
    const float xn = xn_[static_cast<size_t>(u)];
    const Eigen::Vector3f horizontal = rotation.col(0) * xn + rotation.col(2);
    index_.CastColumn(origin, horizontal, yn0, dyn, rows, static_cast<float>(options_.max_distance), &scratch,
                      hits.data());
    for (int v = 0; v < rows; ++v) {
      const float yn = yn_[static_cast<size_t>(v)];
      const float norm = std::sqrt(xn * xn + yn * yn + 1.0f);
      const Eigen::Vector3f dir = (horizontal - yn * Eigen::Vector3f::UnitZ()) / norm;
      const ColumnHit& h = hits[static_cast<size_t>(v)];
      Store(Shade(origin, dir, h.lambda * norm, h.lambda, h.primitive, h.normal, h.axis), u, v, noise_key,
            grey, labels, depth);
    }
  }
}

}  // namespace semslam::sim
