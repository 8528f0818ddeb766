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

// Filtering helpers, exposed for tests.
// Fraction of [x - w/2, x + w/2] covered by the pulses [k * period, k * period + width), k integer.
float PulseCoverage(float x, float period, float width, float w);
// Fraction of [x - w/2, x + w/2] inside [a, b].
float IntervalCoverage(float x, float a, float b, float w);
// Value noise in [-1, 1] on a unit lattice.
float ValueNoise2(float x, float y, std::uint32_t seed);
float ValueNoise3(float x, float y, float z, std::uint32_t seed);
// Octave sum of ValueNoise2 starting at `frequency` (cycles per metre), octaves whose wavelength is below
// about two footprints `footprint` fade out. Normalized to about [-1, 1].
float FilteredNoise2(float x, float y, std::uint32_t seed, float frequency, int octaves, float footprint);
float FilteredNoise3(const Eigen::Vector3f& p, std::uint32_t seed, float frequency, int octaves,
                     float footprint);

}  // namespace semslam::sim
