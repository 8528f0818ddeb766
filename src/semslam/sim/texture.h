#pragma once
// Procedural surface appearance of the town (grey levels), filtered by the pixel footprint: every pattern
// (lane markings, paving joints, bricks, windows, leaves, grain) is box-filtered over the area a pixel
// covers on the surface, and noise octaves finer than about two pixels fade out, so that distant detail
// turns into its average grey instead of aliasing and shimmering from frame to frame.

#include <Eigen/Core>
#include <cstdint>

#include "semslam/sim/city.h"

namespace semslam::sim {

// What the shader knows about a surface point.
struct SurfaceSample {
  Eigen::Vector3f point;   // town frame
  Eigen::Vector3f normal;  // unit, facing the viewer
  Eigen::Vector3f dir;     // unit ray direction
  float t = 0;             // ray length
  float pixel_size = 0;    // metres covered by one pixel at distance 1 (1 / focal length)
  int axis = -1;           // box faces: the axis of the normal; -1 for curved surfaces
};

// Reflectance (grey level, 0..255 before lighting) of the ground plane (road) at a point.
float ShadeGround(const City& city, const SurfaceSample& s);
// Reflectance of a primitive's surface.
float ShadePrimitive(const City& city, const Primitive& primitive, const SurfaceSample& s);

}  // namespace semslam::sim
