#pragma once
// Box-filtered patterns and value noise, the building blocks of the town's procedural textures (texture.h):
// a pattern is averaged over the surface a pixel covers, and noise octaves finer than about two pixels fade
// out. Inline: the shader evaluates them millions of times a frame.

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "semslam/sim/random.h"

namespace semslam::sim {
namespace pattern {

// Filters span this many pixel footprints: enough to keep sub-pixel patterns from shimmering.
inline constexpr float kFilterPixels = 1.5f;

inline float Clamp01(float v) { return std::min(1.0f, std::max(0.0f, v)); }
inline float Mix(float a, float b, float t) { return a + (b - a) * t; }
inline float SmoothStep(float e0, float e1, float x) {
  const float t = Clamp01((x - e0) / (e1 - e0));
  return t * t * (3.0f - 2.0f * t);
}
// Weight of a detail of size `feature` (metres) seen with footprint `fp`: 1 when it spans >= 4 pixels, 0
// at <= 2 pixels.
inline float Detail(float feature, float fp) {
  return Clamp01((feature / std::max(fp, 1e-6f) - 2.0f) * 0.5f);
}

// Footprint along one in-plane axis of a planar surface: w * sqrt(1 + (d_a / d_n)^2).
inline float AxisFootprint(float w, float d_axis, float d_normal) {
  const float dn = std::max(std::abs(d_normal), 0.03f);
  return w * std::sqrt(1.0f + (d_axis * d_axis) / (dn * dn));
}

// Coverage of a disc of radius r at distance d from its centre, filtered over `w`.
inline float DiscCoverage(float d, float r, float w) { return Clamp01((r - d) / std::max(w, 1e-4f) + 0.5f); }

// Lattice values for the noise: a permutation of 0..255 (twice, to skip a wrap) and 256 values in [-1, 1],
// drawn once from a fixed seed.
struct NoiseTable {
  std::uint8_t perm[512];
  float value[256];
  NoiseTable() {
    std::uint8_t p[256];
    for (int i = 0; i < 256; ++i) p[i] = static_cast<std::uint8_t>(i);
    std::uint64_t state = 0x5EED5EEDull;
    for (int i = 255; i > 0; --i) {
      state = Mix64(state);
      const int j = static_cast<int>(state % static_cast<std::uint64_t>(i + 1));
      std::swap(p[i], p[j]);
    }
    for (int i = 0; i < 512; ++i) perm[i] = p[i & 255];
    for (int i = 0; i < 256; ++i) {
      state = Mix64(state);
      value[i] = static_cast<float>(state >> 40) * (2.0f / 16777216.0f) - 1.0f;
    }
  }
};
inline const NoiseTable& Table() {
  static const NoiseTable table;
  return table;
}

}  // namespace pattern

// Fraction of [x - w/2, x + w/2] covered by the pulses [k * period, k * period + width), k integer.
inline float PulseCoverage(float x, float period, float width, float w) {
  if (w < 1e-6f) {
    const float f = x - std::floor(x / period) * period;
    return f < width ? 1.0f : 0.0f;
  }
  if (w < period) {
    // The window [x - w/2, x + w/2] meets at most the pulses of periods k - 1, k and k + 1.
    const float local = x - std::floor(x / period) * period;
    const float a = local - 0.5f * w, b = local + 0.5f * w;
    auto overlap = [&](float lo) { return std::max(0.0f, std::min(b, lo + width) - std::max(a, lo)); };
    return pattern::Clamp01((overlap(-period) + overlap(0.0f) + overlap(period)) / w);
  }
  if (w >= period * 8.0f) return width / period;  // fully averaged
  auto integral = [&](float v) {
    const float n = std::floor(v / period);
    return n * width + std::min(v - n * period, width);
  };
  return pattern::Clamp01((integral(x + 0.5f * w) - integral(x - 0.5f * w)) / w);
}

// Fraction of [x - w/2, x + w/2] inside [a, b].
inline float IntervalCoverage(float x, float a, float b, float w) {
  if (w < 1e-6f) return (x >= a && x < b) ? 1.0f : 0.0f;
  return pattern::Clamp01((std::min(x + 0.5f * w, b) - std::max(x - 0.5f * w, a)) / w);
}

// Value noise in [-1, 1] on a unit lattice.
inline float ValueNoise2(float x, float y, std::uint32_t seed) {
  const pattern::NoiseTable& nt = pattern::Table();
  const float fx = std::floor(x), fy = std::floor(y);
  const int ix = (static_cast<int>(fx) + static_cast<int>(seed & 255u)) & 255;
  const int iy = (static_cast<int>(fy) + static_cast<int>((seed >> 8) & 255u)) & 255;
  float tx = x - fx, ty = y - fy;
  tx = tx * tx * (3.0f - 2.0f * tx);
  ty = ty * ty * (3.0f - 2.0f * ty);
  const int a = nt.perm[ix], b = nt.perm[ix + 1];
  const float v00 = nt.value[nt.perm[a + iy]], v10 = nt.value[nt.perm[b + iy]];
  const float v01 = nt.value[nt.perm[a + iy + 1]], v11 = nt.value[nt.perm[b + iy + 1]];
  return pattern::Mix(pattern::Mix(v00, v10, tx), pattern::Mix(v01, v11, tx), ty);
}

// The same on a 3D lattice.
inline float ValueNoise3(float x, float y, float z, std::uint32_t seed) {
  const pattern::NoiseTable& nt = pattern::Table();
  const float fx = std::floor(x), fy = std::floor(y), fz = std::floor(z);
  const int ix = (static_cast<int>(fx) + static_cast<int>(seed & 255u)) & 255;
  const int iy = (static_cast<int>(fy) + static_cast<int>((seed >> 8) & 255u)) & 255;
  const int iz = (static_cast<int>(fz) + static_cast<int>((seed >> 16) & 255u)) & 255;
  float tx = x - fx, ty = y - fy, tz = z - fz;
  tx = tx * tx * (3.0f - 2.0f * tx);
  ty = ty * ty * (3.0f - 2.0f * ty);
  tz = tz * tz * (3.0f - 2.0f * tz);
  const int a = nt.perm[ix], b = nt.perm[ix + 1];
  const int aa = nt.perm[a + iy], ab = nt.perm[a + iy + 1], ba = nt.perm[b + iy], bb = nt.perm[b + iy + 1];
  auto v = [&](int h, int dz) { return nt.value[nt.perm[h + iz + dz]]; };
  const float x00 = pattern::Mix(v(aa, 0), v(ba, 0), tx), x10 = pattern::Mix(v(ab, 0), v(bb, 0), tx);
  const float x01 = pattern::Mix(v(aa, 1), v(ba, 1), tx), x11 = pattern::Mix(v(ab, 1), v(bb, 1), tx);
  return pattern::Mix(pattern::Mix(x00, x10, ty), pattern::Mix(x01, x11, ty), tz);
}

// Octave sum of ValueNoise2 starting at `frequency` (cycles per metre), octaves whose wavelength is below
// about two footprints `footprint` fade out. Normalized to about [-1, 1].
inline float FilteredNoise2(float x, float y, std::uint32_t seed, float frequency, int octaves,
                            float footprint) {
  float sum = 0, norm = 0, amplitude = 1, f = frequency;
  for (int o = 0; o < octaves; ++o) {
    const float weight = pattern::Detail(1.0f / f, footprint);
    if (weight > 0)
      sum += amplitude * weight * ValueNoise2(x * f, y * f, seed + static_cast<std::uint32_t>(o) * 0x2F1B3u);
    norm += amplitude;
    amplitude *= 0.55f;
    f *= 2.0f;
    if (weight == 0) {
      for (int r = o + 1; r < octaves; ++r) {
        norm += amplitude;
        amplitude *= 0.55f;
      }
      break;
    }
  }
  return sum / norm * 1.6f;
}

// The same with ValueNoise3.
inline float FilteredNoise3(const Eigen::Vector3f& p, std::uint32_t seed, float frequency, int octaves,
                            float footprint) {
  float sum = 0, norm = 0, amplitude = 1, f = frequency;
  for (int o = 0; o < octaves; ++o) {
    const float weight = pattern::Detail(1.0f / f, footprint);
    if (weight > 0) {
      sum += amplitude * weight *
             ValueNoise3(p.x() * f, p.y() * f, p.z() * f, seed + static_cast<std::uint32_t>(o) * 0x2F1B3u);
    }
    norm += amplitude;
    amplitude *= 0.55f;
    f *= 2.0f;
  }
  return sum / norm * 1.6f;
}

}  // namespace semslam::sim
