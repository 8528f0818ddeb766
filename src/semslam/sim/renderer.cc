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
  if (options_.parallel) {
    tbb::parallel_for(tbb::blocked_range<int>(0, camera_.height, 4), [&](const tbb::blocked_range<int>& r) {
      RenderRows(r.begin(), r.end(), rotation, origin, noise_key, grey, labels, depth);
    });
  } else {
    RenderRows(0, camera_.height, rotation, origin, noise_key, grey, labels, depth);
  }
}

void Renderer::RenderRows(int row_begin, int row_end, const Eigen::Matrix3f& rotation,
                          const Eigen::Vector3f& origin, std::uint32_t noise_key, cv::Mat* grey,
                          cv::Mat* labels, cv::Mat* depth) const {
  const float pixel_size = static_cast<float>(1.0 / camera_.fx);
  const float max_distance = static_cast<float>(options_.max_distance);
  const float inv_haze = static_cast<float>(1.0 / options_.haze_distance);
  const float ambient = static_cast<float>(options_.ambient),
              sun_strength = static_cast<float>(options_.sun_strength);
  const float noise_scale = static_cast<float>(options_.sensor_noise * std::sqrt(6.0));
  constexpr float kHazeGrey = 200.0f;
  const auto sky_label = static_cast<std::uint8_t>(SemanticClass::kSky);
  const auto road_label = static_cast<std::uint8_t>(SemanticClass::kRoad);
  for (int v = row_begin; v < row_end; ++v) {
    std::uint8_t* g_row = grey->ptr<std::uint8_t>(v);
    std::uint8_t* l_row = labels != nullptr ? labels->ptr<std::uint8_t>(v) : nullptr;
    std::uint16_t* d_row = depth != nullptr ? depth->ptr<std::uint16_t>(v) : nullptr;
    const float yn = yn_[static_cast<size_t>(v)];
    for (int u = 0; u < camera_.width; ++u) {
      const float xn = xn_[static_cast<size_t>(u)];
      const float inv_norm = 1.0f / std::sqrt(xn * xn + yn * yn + 1.0f);
      const Eigen::Vector3f dir = rotation * Eigen::Vector3f(xn * inv_norm, yn * inv_norm, inv_norm);
      RayHit hit;
      float value;
      std::uint8_t label = sky_label;
      float z = 0;
      if (index_.Intersect(origin, dir, max_distance, &hit)) {
        SurfaceSample s;
        s.point = origin + dir * hit.t;
        s.normal = hit.normal;
        if (s.normal.dot(dir) > 0) s.normal = -s.normal;
        s.dir = dir;
        s.t = hit.t;
        s.pixel_size = pixel_size;
        s.axis = hit.axis;
        float albedo;
        if (hit.primitive < 0) {
          albedo = ShadeGround(city_, s);
          label = road_label;
        } else {
          const Primitive& p = city_.primitives[static_cast<size_t>(hit.primitive)];
          albedo = ShadePrimitive(city_, p, s);
          label = p.label;
        }
        float light = ambient + sun_strength * std::max(0.0f, s.normal.dot(sun_));
        if (std::abs(s.normal.z()) < 0.5f) {
          // Ambient occlusion at the foot of walls.
          const float h = std::min(1.0f, std::max(0.0f, s.point.z() / 1.2f));
          light *= 0.82f + 0.18f * h;
        }
        const float haze = 1.0f - std::exp(-hit.t * inv_haze);
        value = albedo * light + (kHazeGrey - albedo * light) * haze;
        z = hit.t * inv_norm;
      } else {
        value = SkyGrey(dir);
      }
      if (noise_scale > 0) {
        const std::uint32_t h =
            Hash32(noise_key, static_cast<std::uint32_t>(u), static_cast<std::uint32_t>(v));
        const float n = static_cast<float>(h & 0xFFFFu) * (1.0f / 65535.0f) +
                        static_cast<float>(h >> 16) * (1.0f / 65535.0f) - 1.0f;
        value += noise_scale * n;
      }
      g_row[u] = static_cast<std::uint8_t>(std::clamp(value, 0.0f, 255.0f) + 0.5f);
      if (l_row != nullptr) l_row[u] = label;
      if (d_row != nullptr) {
        d_row[u] = z <= 0 ? 0
                          : static_cast<std::uint16_t>(
                                std::min(65535.0, std::round(static_cast<double>(z) * kDepthScale)));
        if (z > 0 && d_row[u] == 0) d_row[u] = 1;
      }
    }
  }
}

}  // namespace semslam::sim
