#include "semslam/sim/texture.h"

#include <algorithm>
#include <cmath>

#include "semslam/sim/pattern_filter.h"
#include "semslam/sim/random.h"

namespace semslam::sim {
namespace {

using namespace pattern;

inline float HashSigned(std::uint32_t h) { return HashToUnit(h) * 2.0f - 1.0f; }
inline int FloorInt(float v) { return static_cast<int>(std::floor(v)); }
inline std::uint32_t U(int v) { return static_cast<std::uint32_t>(v); }

// In-plane coordinates of a box face: u horizontal (or x on top faces), v vertical (or y), with footprints.
struct FaceCoords {
  float u = 0, v = 0;  // from the face's lower corner
  float width = 0, height = 0;
  float fu = 0, fv = 0;  // filter widths
};
FaceCoords BoxFace(const Primitive& p, const SurfaceSample& s) {
  FaceCoords f;
  const float w = s.t * s.pixel_size;
  const Eigen::Vector3f& d = s.dir;
  if (s.axis == 2) {
    f.u = s.point.x() - p.lo.x();
    f.v = s.point.y() - p.lo.y();
    f.width = p.hi.x() - p.lo.x();
    f.height = p.hi.y() - p.lo.y();
    f.fu = kFilterPixels * AxisFootprint(w, d.x(), d.z());
    f.fv = kFilterPixels * AxisFootprint(w, d.y(), d.z());
  } else {
    const int a = s.axis == 0 ? 1 : 0;  // horizontal in-plane axis
    f.u = s.point[a] - p.lo[a];
    f.v = s.point.z() - p.lo.z();
    f.width = p.hi[a] - p.lo[a];
    f.height = p.hi.z() - p.lo.z();
    f.fu = kFilterPixels * AxisFootprint(w, d[a], d[s.axis]);
    f.fv = kFilterPixels * AxisFootprint(w, d.z(), d[s.axis]);
  }
  return f;
}

float CurvedFootprint(const SurfaceSample& s) {
  return kFilterPixels * s.t * s.pixel_size / std::max(std::abs(s.normal.dot(s.dir)), 0.3f);
}

// ---- materials ------------------------------------------------------------------------------------------

float Brick(float u, float v, float fu, float fv, float base, std::uint32_t seed) {
  constexpr float kRow = 0.075f, kLength = 0.24f, kMortar = 0.012f;
  const float detail = Detail(kRow, fv);
  const int row = FloorInt(v / kRow);
  const float shift = (row & 1) ? 0.5f * kLength : 0.0f;
  const float mortar_h = PulseCoverage(v, kRow, kMortar, fv);
  const float mortar_v =
      PulseCoverage(u + shift, kLength, kMortar, fu) * detail + (1.0f - detail) * (kMortar / kLength);
  const float mortar = mortar_h + mortar_v - mortar_h * mortar_v;
  const int col = FloorInt((u + shift) / kLength);
  const float brick_var =
      0.12f * HashSigned(Hash32(U(row), U(col), seed)) * Detail(kLength * 0.5f, std::max(fu, fv));
  const float brick = base * (1.0f + brick_var);
  return Mix(brick, std::min(250.0f, base * 1.55f + 20.0f), mortar);
}

float Plaster(float u, float v, float fu, float fv, float base, float floor_height, std::uint32_t seed) {
  const float fp = std::max(fu, fv);
  float g = base * (1.0f + 0.07f * FilteredNoise2(u, v, seed, 0.35f, 3, fp) +
                    0.05f * FilteredNoise2(u, v, seed + 7, 6.0f, 3, fp));
  // Cornice bands at the floor lines.
  const float band = PulseCoverage(v + 0.1f, floor_height, 0.18f, fv);
  return Mix(g, std::min(250.0f, base * 1.18f + 10.0f), band);
}

float FacadeWall(const City& city, const Primitive& p, const FaceCoords& f, std::uint32_t seed) {
  const FacadeStyle& st = city.styles[p.style];
  const float base = st.wall_grey * (0.92f + 0.16f * p.tone);
  return st.brick ? Brick(f.u, f.v, f.fu, f.fv, base, seed)
                  : Plaster(f.u, f.v, f.fu, f.fv, base, st.floor_height, seed);
}

float Facade(const City& city, const Primitive& p, const SurfaceSample& s) {
  if (s.axis == 2) {  // roof
    const float fp = kFilterPixels * s.t * s.pixel_size;
    return 80.0f + 20.0f * p.tone + 10.0f * FilteredNoise2(s.point.x(), s.point.y(), p.variant, 1.0f, 4, fp);
  }
  const FacadeStyle& st = city.styles[p.style];
  const FaceCoords f = BoxFace(p, s);
  const std::uint32_t seed =
      p.variant ^ static_cast<std::uint32_t>(s.axis * 2 + (s.normal[s.axis] > 0 ? 1 : 0));
  float g = FacadeWall(city, p, f, seed);
  const bool ground_box = p.lo.z() < 1.0f;
  const float fh = st.floor_height;
  // Plinth.
  if (ground_box) g = Mix(g, g * 0.68f, IntervalCoverage(f.v, -1.0f, st.plinth_height, f.fv));

  // Window grid.
  const float period = st.window_period;
  const int columns = static_cast<int>(std::floor((f.width - 1.2f) / period));
  if (columns >= 1) {
    const float offset = 0.5f * (f.width - static_cast<float>(columns) * period);
    const float ww = st.window_width, wh = st.window_height, fw = st.frame_width;
    const float first_row = ground_box ? fh : 0.0f;
    const float rows_on = IntervalCoverage(f.v, first_row, f.height - 0.5f, f.fv);
    const float row_frame =
        rows_on > 0 ? PulseCoverage(f.v - st.sill_height + fw, fh, wh + 2 * fw, f.fv) * rows_on : 0.0f;
    const float row_sill =
        rows_on > 0 ? PulseCoverage(f.v - st.sill_height + fw + 0.07f, fh, 0.07f, f.fv) * rows_on : 0.0f;
    if (row_frame > 0 || row_sill > 0) {
      const float inside = IntervalCoverage(f.u, offset, f.width - offset, f.fu);
      const float col_sill =
          PulseCoverage(f.u - offset - 0.5f * (period - ww) + fw + 0.08f, period, ww + 2 * fw + 0.16f, f.fu) *
          inside;
      if (col_sill > 0) {
        const float col_glass = PulseCoverage(f.u - offset - 0.5f * (period - ww), period, ww, f.fu) * inside;
        const float col_frame =
            PulseCoverage(f.u - offset - 0.5f * (period - ww) + fw, period, ww + 2 * fw, f.fu) * inside;
        const float row_glass = PulseCoverage(f.v - st.sill_height, fh, wh, f.fv) * rows_on;
        // Glass varies per window (reflections, curtains); the variation fades with the window size.
        const int col = FloorInt((f.u - offset) / period);
        const int row = FloorInt(f.v / fh);
        const float var = HashSigned(Hash32(U(col), U(row), p.variant)) * Detail(period, f.fu);
        const float local_v =
            f.v - static_cast<float>(row) * fh - st.sill_height;  // height inside the window
        float glass = st.glass_grey + 28.0f * var + 18.0f * Clamp01(var);
        // Lighter curtain in the upper part of some windows.
        if (var > 0.3f) {
          glass =
              Mix(glass, 150.0f, IntervalCoverage(local_v, wh * 0.65f, wh, f.fv) * Detail(wh * 0.3f, f.fv));
        }
        // Mullion (wide windows) and transom.
        const float local_u = f.u - offset - static_cast<float>(col) * period - 0.5f * period;
        float bars = 0;
        if (ww > 1.2f) bars = IntervalCoverage(local_u, -0.5f * fw, 0.5f * fw, f.fu);
        bars = std::max(bars, IntervalCoverage(local_v, wh * 0.7f, wh * 0.7f + fw * 0.7f, f.fv));
        bars *= Detail(fw, std::max(f.fu, f.fv));
        g = Mix(g, std::min(250.0f, st.frame_grey * 0.9f + 20.0f), col_sill * row_sill);
        g = Mix(g, st.frame_grey, col_frame * row_frame);
        g = Mix(g, Mix(glass, st.frame_grey, bars), col_glass * row_glass);
      }
    }
  }

  if (ground_box && f.v < fh + 0.5f) {
    // Door: one per face, placed by the variant bits.
    const float door_w = 1.3f;
    const float door_u = 0.8f + HashToUnit(Hash32(p.variant, 17u)) * std::max(0.0f, f.width - 1.6f - door_w);
    const float door =
        IntervalCoverage(f.u, door_u, door_u + door_w, f.fu) * IntervalCoverage(f.v, -1.0f, 2.3f, f.fv);
    const float door_frame = IntervalCoverage(f.u, door_u - 0.12f, door_u + door_w + 0.12f, f.fu) *
                             IntervalCoverage(f.v, -1.0f, 2.42f, f.fv);
    if (st.shop_front) {
      // Shop windows and a sign band with letters.
      const float band_lo = fh - 0.8f, band_hi = fh - 0.2f;
      const float shop = IntervalCoverage(f.u, 0.6f, f.width - 0.6f, f.fu) *
                         IntervalCoverage(f.v, 0.5f, band_lo - 0.15f, f.fv);
      const float shop_frame = IntervalCoverage(f.u, 0.45f, f.width - 0.45f, f.fu) *
                               IntervalCoverage(f.v, 0.35f, band_lo - 0.02f, f.fv);
      const float posts = PulseCoverage(f.u - 0.6f, 2.4f, 0.1f, f.fu) * Detail(0.1f, f.fu);
      const float reflection =
          25.0f * FilteredNoise2(f.u * 0.4f, f.v, p.variant + 3, 0.8f, 2, std::max(f.fu, f.fv));
      g = Mix(g, st.frame_grey * 0.8f, shop_frame);
      g = Mix(g, Mix(st.glass_grey + 20.0f + reflection, st.frame_grey * 0.8f, posts), shop);
      const float band =
          IntervalCoverage(f.u, 0.4f, f.width - 0.4f, f.fu) * IntervalCoverage(f.v, band_lo, band_hi, f.fv);
      const float letter_cell = 0.42f;
      const int cell = FloorInt(f.u / letter_cell);
      const float text_lo = f.width * 0.2f, text_hi = f.width * 0.8f;
      const bool present = (Hash32(U(cell), p.variant, 23u) & 3u) != 0u;
      float letter = present ? PulseCoverage(f.u - 0.06f, letter_cell, letter_cell - 0.12f, f.fu) *
                                   IntervalCoverage(f.v, band_lo + 0.12f, band_hi - 0.12f, f.fv) *
                                   IntervalCoverage(f.u, text_lo, text_hi, f.fu)
                             : 0.0f;
      letter *= Detail(letter_cell * 0.5f, std::max(f.fu, f.fv));
      const float ink = st.sign_grey > 128 ? 35.0f : 230.0f;
      g = Mix(g, Mix(st.sign_grey, ink, letter), band);
    }
    g = Mix(g, 200.0f, door_frame);
    g = Mix(g, 50.0f + 30.0f * p.tone, door);
  }
  return g;
}

float Sidewalk(const Primitive& p, const SurfaceSample& s) {
  if (s.axis != 2) {  // curb stone
    const FaceCoords f = BoxFace(p, s);
    const float fp = std::max(f.fu, f.fv);
    float g = 170.0f + 14.0f * FilteredNoise2(f.u, f.v, p.variant, 4.0f, 4, fp);
    g = Mix(g, g * 0.75f, PulseCoverage(f.u, 1.0f, 0.01f, f.fu));  // joints between curb stones
    return g;
  }
  const float w = s.t * s.pixel_size;
  const float fx = kFilterPixels * AxisFootprint(w, s.dir.x(), s.dir.z());
  const float fy = kFilterPixels * AxisFootprint(w, s.dir.y(), s.dir.z());
  const float x = s.point.x(), y = s.point.y();
  // Curb edge: a light band along the slab border.
  const float edge = 1.0f - IntervalCoverage(x, p.lo.x() + 0.25f, p.hi.x() - 0.25f, fx) *
                                IntervalCoverage(y, p.lo.y() + 0.25f, p.hi.y() - 0.25f, fy);
  const float tile = (p.variant & 1u) ? 0.3f : 0.45f;
  const float joint_x = PulseCoverage(x, tile, 0.014f, fx);
  const float joint_y = PulseCoverage(y, tile, 0.014f, fy);
  const float joint = joint_x + joint_y - joint_x * joint_y;
  const float fp = std::max(fx, fy);
  const float tile_var =
      16.0f * HashSigned(Hash32(U(FloorInt(x / tile)), U(FloorInt(y / tile)), p.variant)) * Detail(tile, fp);
  float g = 132.0f + 25.0f * p.tone + tile_var + 9.0f * FilteredNoise2(x, y, p.variant, 8.0f, 4, fp) +
            8.0f * FilteredNoise2(x, y, p.variant + 1, 0.2f, 2, fp);
  g = Mix(g, g * 0.55f, joint);
  return Mix(g, 185.0f, edge);
}

float Grass(const Primitive& p, const SurfaceSample& s) {
  const float fp = kFilterPixels * s.t * s.pixel_size / std::max(std::abs(s.dir.z()), 0.25f);
  return 88.0f + 14.0f * p.tone + 26.0f * FilteredNoise2(s.point.x(), s.point.y(), p.variant, 3.0f, 4, fp) +
         14.0f * FilteredNoise2(s.point.x(), s.point.y(), p.variant + 5, 0.15f, 2, fp);
}

float Foliage(const Primitive& p, const SurfaceSample& s) {
  const float fp = CurvedFootprint(s);
  // Clusters of leaves (about a metre) made of single leaves and gaps (a few centimetres to decimetres).
  const float clusters = FilteredNoise3(s.point, p.variant, 1.3f, 2, fp);
  const float leaves = FilteredNoise3(s.point, p.variant + 77u, 5.0f, 3, fp);
  // A soft threshold whose softness grows with the footprint (no sharp edge below a pixel).
  const float soft = 0.12f + 3.0f * fp;
  const float leaf = SmoothStep(-soft, soft, 0.7f * clusters + 0.9f * leaves + 0.2f * (p.tone - 0.5f));
  // The crown shades its own underside.
  const float underside = 0.72f + 0.28f * (0.5f + 0.5f * s.normal.z());
  return (34.0f + 100.0f * leaf + 16.0f * p.tone) * underside;
}

float Bark(const Primitive& p, const SurfaceSample& s) {
  const float fp = CurvedFootprint(s);
  const Eigen::Vector3f q(s.point.x() * 6.0f, s.point.y() * 6.0f, s.point.z() * 0.8f);
  return 55.0f + 12.0f * p.tone + 14.0f * FilteredNoise3(q, p.variant, 1.0f, 3, fp * 4.0f);
}

// Horizontal coordinate around a vertical cylinder (arc length) and its height.
FaceCoords CylinderFace(const Primitive& p, const SurfaceSample& s) {
  FaceCoords f;
  const float r = 0.5f * (p.hi.x() - p.lo.x());
  const float cx = 0.5f * (p.lo.x() + p.hi.x()), cy = 0.5f * (p.lo.y() + p.hi.y());
  f.u = (std::atan2(s.point.y() - cy, s.point.x() - cx) + 3.14159265f) * r;
  f.v = s.point.z() - p.lo.z();
  f.width = 6.2831853f * r;
  f.height = p.hi.z() - p.lo.z();
  f.fu = f.fv = CurvedFootprint(s);
  return f;
}

FaceCoords AnyFace(const Primitive& p, const SurfaceSample& s) {
  return p.shape == Shape::kBox && s.axis >= 0 ? BoxFace(p, s) : CylinderFace(p, s);
}

float Wall(const Primitive& p, const SurfaceSample& s) {
  const FaceCoords f = AnyFace(p, s);
  const float base = 112.0f + 60.0f * p.tone;
  if (s.axis == 2) return base * 1.1f;
  constexpr float kRow = 0.25f, kLength = 0.5f, kJoint = 0.015f;
  const int row = FloorInt(f.v / kRow);
  const float shift = (row & 1) ? 0.5f * kLength : 0.0f;
  const float detail = Detail(kRow, f.fv);
  const float jh = PulseCoverage(f.v, kRow, kJoint, f.fv);
  const float jv =
      PulseCoverage(f.u + shift, kLength, kJoint, f.fu) * detail + (1.0f - detail) * (kJoint / kLength);
  const float joint = jh + jv - jh * jv;
  const float stone =
      base * (1.0f + 0.1f * HashSigned(Hash32(U(row), U(FloorInt((f.u + shift) / kLength)), p.variant)) *
                         Detail(kLength * 0.5f, std::max(f.fu, f.fv)));
  float g = Mix(stone, base * 0.6f, joint);
  g += 8.0f * FilteredNoise2(f.u, f.v, p.variant + 9, 5.0f, 3, std::max(f.fu, f.fv));
  // Coping stones on top.
  return Mix(g, std::min(240.0f, base * 1.35f),
             IntervalCoverage(f.v, f.height - 0.09f, f.height + 1.0f, f.fv));
}

float Fence(const Primitive& p, const SurfaceSample& s) {
  const FaceCoords f = BoxFace(p, s);
  const float wood = 135.0f + 70.0f * p.tone;
  if (s.axis == 2) return wood;
  const float slats = PulseCoverage(f.u, 0.14f, 0.095f, f.fu);
  const float rails = std::max(IntervalCoverage(f.v, 0.22f, 0.32f, f.fv),
                               IntervalCoverage(f.v, f.height - 0.32f, f.height - 0.22f, f.fv));
  float g = Mix(42.0f, wood, slats);
  g = Mix(g, wood * 0.85f, rails);
  return g + 7.0f * FilteredNoise2(f.u * 0.3f, f.v * 3.0f, p.variant, 4.0f, 2, std::max(f.fu, f.fv));
}

float Pole(const Primitive& p, const SurfaceSample& s) {
  const FaceCoords f = AnyFace(p, s);
  const float base = 95.0f + 90.0f * p.tone;
  // Darker foot and a reflective band at eye height.
  float g = Mix(base, base * 0.6f, IntervalCoverage(f.v, -1.0f, 0.45f, f.fv));
  g = Mix(g, 225.0f, IntervalCoverage(f.v, 1.9f, 2.1f, f.fv) * ((p.variant & 3u) == 0u ? 1.0f : 0.0f));
  return g;
}

// Which face of a box looks along `facing` (0..3: +x, +y, -x, -y).
bool IsFront(const SurfaceSample& s, int facing) {
  const int axis = facing % 2;
  const float sign = facing < 2 ? 1.0f : -1.0f;
  return s.axis == axis && s.normal[axis] * sign > 0.5f;
}

float TrafficLight(const Primitive& p, const SurfaceSample& s) {
  const float housing = 32.0f + 15.0f * p.tone;
  if (!IsFront(s, p.facing)) return housing;
  const FaceCoords f = BoxFace(p, s);
  const float cu = 0.5f * f.width;
  const int lit = static_cast<int>(p.variant % 3u);
  float g = housing;
  for (int k = 0; k < 3; ++k) {
    const float cv = f.height * (0.2f + 0.3f * static_cast<float>(k));
    const float d = std::hypot(f.u - cu, f.v - cv);
    const float fw = std::max(f.fu, f.fv);
    g = Mix(g, 12.0f, DiscCoverage(d, 0.12f, fw));  // visor shadow ring
    g = Mix(g, k == lit ? 240.0f : 75.0f, DiscCoverage(d, 0.09f, fw));
  }
  return g;
}

float Sign(const Primitive& p, const SurfaceSample& s) {
  if (!IsFront(s, p.facing)) return 115.0f + 30.0f * p.tone;
  const FaceCoords f = BoxFace(p, s);
  const float fw = std::max(f.fu, f.fv);
  const float half = 0.5f * f.height;
  const float du = f.u - 0.5f * f.width, dv = f.v - half;
  float border, plate, symbol;
  if (p.variant & 1u) {  // round sign
    const float d = std::hypot(du, dv);
    border = DiscCoverage(d, half, fw);
    plate = DiscCoverage(d, half * 0.78f, fw);
  } else {  // square sign
    border = IntervalCoverage(du, -half, half, f.fu) * IntervalCoverage(dv, -half, half, f.fv);
    plate = IntervalCoverage(du, -half * 0.85f, half * 0.85f, f.fu) *
            IntervalCoverage(dv, -half * 0.85f, half * 0.85f, f.fv);
  }
  if (p.variant & 2u) {  // bar
    symbol = IntervalCoverage(du, -half * 0.5f, half * 0.5f, f.fu) *
             IntervalCoverage(dv, -half * 0.14f, half * 0.14f, f.fv);
  } else {  // dot
    symbol = DiscCoverage(std::hypot(du, dv), half * 0.3f, fw);
  }
  float g = 110.0f;
  g = Mix(g, (p.variant & 4u) ? 45.0f : 70.0f, border);
  g = Mix(g, 228.0f, plate);
  return Mix(g, 30.0f, symbol);
}

float CarBody(const Primitive& p, const SurfaceSample& s, bool cabin) {
  const float paint = 28.0f + 205.0f * p.tone;
  if (s.axis == 2) return paint;
  const FaceCoords f = BoxFace(p, s);
  const float fw = std::max(f.fu, f.fv);
  const int long_axis = (p.hi.x() - p.lo.x()) > (p.hi.y() - p.lo.y()) ? 0 : 1;
  const bool end_face = s.axis == long_axis;
  if (cabin) {
    // Glass with pillars at both ends and in the middle.
    const float glass = IntervalCoverage(f.u, 0.12f, f.width - 0.12f, f.fu) *
                        IntervalCoverage(f.v, 0.04f, f.height - 0.07f, f.fv);
    const float pillar =
        end_face ? 0.0f : IntervalCoverage(f.u, 0.45f * f.width, 0.45f * f.width + 0.1f, f.fu);
    return Mix(paint, 30.0f + 25.0f * FilteredNoise2(f.u, f.v, p.variant, 1.5f, 2, fw),
               glass * (1.0f - pillar));
  }
  float g = Mix(paint, paint * 0.45f, IntervalCoverage(f.v, -1.0f, 0.14f, f.fv));  // sill shadow
  if (end_face) {
    // Lights near the corners and a licence plate in the middle.
    const float lights = (IntervalCoverage(f.u, 0.12f, 0.42f, f.fu) +
                          IntervalCoverage(f.u, f.width - 0.42f, f.width - 0.12f, f.fu)) *
                         IntervalCoverage(f.v, f.height - 0.3f, f.height - 0.14f, f.fv);
    const float plate = IntervalCoverage(f.u, 0.5f * f.width - 0.26f, 0.5f * f.width + 0.26f, f.fu) *
                        IntervalCoverage(f.v, 0.12f, 0.24f, f.fv);
    g = Mix(g, (p.variant & 1u) ? 235.0f : 70.0f, lights);
    g = Mix(g, 225.0f, plate);
  } else {
    // Door seams and handles.
    const float seam =
        Detail(0.02f, fw) * (IntervalCoverage(f.u, 0.38f * f.width, 0.38f * f.width + 0.02f, f.fu) +
                             IntervalCoverage(f.u, 0.62f * f.width, 0.62f * f.width + 0.02f, f.fu));
    g = Mix(g, paint * 0.35f, seam);
    const float handles = (IntervalCoverage(f.u, 0.45f * f.width, 0.45f * f.width + 0.15f, f.fu) +
                           IntervalCoverage(f.u, 0.68f * f.width, 0.68f * f.width + 0.15f, f.fu)) *
                          IntervalCoverage(f.v, f.height - 0.16f, f.height - 0.12f, f.fv);
    g = Mix(g, paint > 120 ? 40.0f : 200.0f, handles);
  }
  return g;
}

// ---- the road -------------------------------------------------------------------------------------------

// The street line nearest to `v` among sorted `lines`: its index.
int NearestLine(const std::vector<double>& lines, float v) {
  const auto it = std::lower_bound(lines.begin(), lines.end(), static_cast<double>(v));
  if (it == lines.begin()) return 0;
  if (it == lines.end()) return static_cast<int>(lines.size()) - 1;
  const int k = static_cast<int>(it - lines.begin());
  return (static_cast<double>(v) - lines[static_cast<size_t>(k - 1)] <
          lines[static_cast<size_t>(k)] - static_cast<double>(v))
             ? k - 1
             : k;
}

}  // namespace

float ShadeGround(const City& city, const SurfaceSample& s) {
  const StreetGrid& g = city.grid;
  const float w = s.t * s.pixel_size;
  const float fx = kFilterPixels * AxisFootprint(w, s.dir.x(), s.dir.z());
  const float fy = kFilterPixels * AxisFootprint(w, s.dir.y(), s.dir.z());
  const float fp = std::max(fx, fy);
  const float x = s.point.x(), y = s.point.y();
  const std::uint32_t seed = static_cast<std::uint32_t>(city.options.seed * 2654435761ull);
  // Asphalt: fine grain, larger stains, and repaired patches.
  float asphalt = 88.0f + 20.0f * FilteredNoise2(x, y, seed, 3.0f, 5, fp) +
                  9.0f * FilteredNoise2(x, y, seed + 1, 0.08f, 3, fp);
  {
    constexpr float kCell = 11.0f;
    const int cx = FloorInt(x / kCell), cy = FloorInt(y / kCell);
    const std::uint32_t h = Hash32(U(cx), U(cy), seed + 2);
    if ((h & 3u) == 0u) {
      const float px = (static_cast<float>(cx) + 0.1f + 0.4f * HashToUnit(Hash32(h, 1u))) * kCell;
      const float py = (static_cast<float>(cy) + 0.1f + 0.4f * HashToUnit(Hash32(h, 2u))) * kCell;
      const float sx = 0.8f + 3.5f * HashToUnit(Hash32(h, 3u)), sy = 0.8f + 3.5f * HashToUnit(Hash32(h, 4u));
      const float patch = IntervalCoverage(x, px, px + sx, fx) * IntervalCoverage(y, py, py + sy, fy);
      asphalt = Mix(asphalt, asphalt + ((h & 4u) ? 16.0f : -14.0f), patch);
    }
  }
  const int i = NearestLine(g.xs, x), j = NearestLine(g.ys, y);
  const float dx = x - static_cast<float>(g.xs[static_cast<size_t>(i)]);
  const float dy = y - static_cast<float>(g.ys[static_cast<size_t>(j)]);
  const float rw = static_cast<float>(g.road_half_width);
  const bool ns = std::abs(dx) <= rw, ew = std::abs(dy) <= rw;
  if (ns == ew) return asphalt;  // inside an intersection (or off the streets)
  // Street coordinates: across (from the centre line), along, distance to the nearest crossing street,
  // and the footprints in both directions.
  const float across = ns ? dx : dy;
  const float along = ns ? y : x;
  const float to_cross = ns ? std::abs(dy) : std::abs(dx);
  const float f_across = ns ? fx : fy, f_along = ns ? fy : fx;
  // Sign of the lane that drives towards the nearest crossing (right-hand traffic).
  const float ahead = ns ? (dy < 0 ? 1.0f : -1.0f) : (dx < 0 ? -1.0f : 1.0f);
  float paint = 0;
  const float zebra_lo = rw + 1.0f, zebra_hi = rw + 4.5f;
  if (to_cross > zebra_hi + 1.5f) {
    // Dashed centre line and the solid lines of the parking strips.
    const float centre =
        IntervalCoverage(across, -0.075f, 0.075f, f_across) * PulseCoverage(along, 9.0f, 4.5f, f_along);
    const float pi = static_cast<float>(g.parking_inner);
    const float edges = IntervalCoverage(std::abs(across), pi - 0.06f, pi + 0.06f, f_across);
    paint = std::max(centre, edges);
    // Stop line before the crossing, on the arriving lane.
    const float stop = IntervalCoverage(to_cross, zebra_hi + 1.6f, zebra_hi + 2.1f, f_along) *
                       IntervalCoverage(across * ahead, 0.1f, pi, f_across);
    paint = std::max(paint, stop);
  } else if (to_cross >= zebra_lo - 0.5f) {
    // Zebra crossing: stripes along the street, side by side across it.
    paint = IntervalCoverage(to_cross, zebra_lo, zebra_hi, f_along) *
            PulseCoverage(across + 0.25f, 1.0f, 0.5f, f_across) *
            IntervalCoverage(across, -rw + 0.4f, rw - 0.4f, f_across);
  }
  if (paint <= 0.0f) return asphalt;
  const float worn = 0.85f + 0.15f * FilteredNoise2(x, y, seed + 4, 2.0f, 2, fp);
  return Mix(asphalt, 218.0f * worn, paint);
}

float ShadePrimitive(const City& city, const Primitive& p, const SurfaceSample& s) {
  switch (p.material) {
    case Material::kSidewalk:
      return Sidewalk(p, s);
    case Material::kFacade:
      return Facade(city, p, s);
    case Material::kRoof: {
      const float fp = kFilterPixels * s.t * s.pixel_size;
      return 75.0f + 25.0f * p.tone +
             10.0f * FilteredNoise2(s.point.x() + s.point.z(), s.point.y(), p.variant, 1.0f, 3, fp);
    }
    case Material::kWall:
      return Wall(p, s);
    case Material::kFence:
      return Fence(p, s);
    case Material::kFoliage:
      return Foliage(p, s);
    case Material::kBark:
      return Bark(p, s);
    case Material::kGrass:
      return Grass(p, s);
    case Material::kPole:
      return Pole(p, s);
    case Material::kLamp:
      return 60.0f + 20.0f * p.tone;
    case Material::kTrafficLight:
      return TrafficLight(p, s);
    case Material::kSign:
      return Sign(p, s);
    case Material::kCarBody:
      return CarBody(p, s, false);
    case Material::kCarCabin:
      return CarBody(p, s, true);
    case Material::kTire:
      return 28.0f;
    case Material::kClothes:
      return 25.0f + 170.0f * p.tone;
    case Material::kSkin:
      return 165.0f;
    case Material::kBicycle:
      return 40.0f + 30.0f * p.tone;
  }
  return 128.0f;
}

}  // namespace semslam::sim
