#include "semslam/sim/city_parts.h"

#include <cmath>

namespace semslam::sim::city_parts {
namespace {

// The horizontal unit vector a box face looks along (0..3: +x, +y, -x, -y).
Eigen::Vector2d FacingDirection(int facing) {
  return facing == 0   ? Eigen::Vector2d(1, 0)
         : facing == 1 ? Eigen::Vector2d(0, 1)
         : facing == 2 ? Eigen::Vector2d(-1, 0)
                       : Eigen::Vector2d(0, -1);
}

}  // namespace

void AddTree(Builder& b, Rng& rng, double x, double y, float z0, double scale) {
  const std::uint32_t obj = b.NewObject("tree", SemanticClass::kVegetation);
  const float tone = F(rng.Uniform());
  const std::uint32_t variant = Bits(rng);
  const double trunk = rng.Uniform(2.2, 3.2) * scale;
  const double r = rng.Uniform(0.13, 0.22) * scale;
  const double rx = rng.Uniform(1.8, 3.2) * scale, rz = rng.Uniform(2.2, 3.6) * scale;
  b.Cylinder(obj, Material::kBark, SemanticClass::kVegetation, F(x), F(y), F(r), z0, F(z0 + trunk + rz * 0.5),
             tone, variant);
  b.Ellipsoid(obj, Material::kFoliage, SemanticClass::kVegetation, {F(x), F(y), F(z0 + trunk + rz * 0.85)},
              {F(rx), F(rx * rng.Uniform(0.85, 1.15)), F(rz)}, tone, variant);
}

void AddBush(Builder& b, Rng& rng, double x, double y) {
  const std::uint32_t obj = b.NewObject("bush", SemanticClass::kVegetation);
  const double r = rng.Uniform(0.6, 1.4);
  const Look look = DrawLook(rng);
  const double ry = r * rng.Uniform(0.8, 1.2);
  b.Ellipsoid(obj, Material::kFoliage, SemanticClass::kVegetation, {F(x), F(y), kSidewalkHeight + F(r * 0.5)},
              {F(r), F(ry), F(r * 0.8)}, look.tone, look.variant);
}

void AddTrafficLight(Builder& b, Rng& rng, const Eigen::Vector2d& p, int facing) {
  const std::uint32_t post = b.NewObject("pole", SemanticClass::kPole);
  const float tone = F(rng.Uniform());
  b.Cylinder(post, Material::kPole, SemanticClass::kPole, F(p.x()), F(p.y()), 0.07f, kSidewalkHeight, 3.6f,
             tone, Bits(rng));
  const std::uint32_t obj = b.NewObject("traffic_light", SemanticClass::kTrafficLight);
  // Housing in front of the post, facing the arriving traffic.
  const Eigen::Vector2d n = FacingDirection(facing);
  const Eigen::Vector2d c = p + n * 0.2;
  const Eigen::Vector2d half(std::abs(n.x()) * 0.13 + std::abs(n.y()) * 0.17,
                             std::abs(n.y()) * 0.13 + std::abs(n.x()) * 0.17);
  Primitive& h = b.Box(obj, Material::kTrafficLight, SemanticClass::kTrafficLight,
                       {F(c.x() - half.x()), F(c.y() - half.y()), 2.55f},
                       {F(c.x() + half.x()), F(c.y() + half.y()), 3.5f}, tone, Bits(rng));
  h.facing = static_cast<std::uint8_t>(facing);
}

void AddTrafficSign(Builder& b, Rng& rng, const Eigen::Vector2d& p, int facing) {
  const std::uint32_t post = b.NewObject("pole", SemanticClass::kPole);
  const float tone = F(rng.Uniform());
  const float top = F(rng.Uniform(2.6, 3.0));
  b.Cylinder(post, Material::kPole, SemanticClass::kPole, F(p.x()), F(p.y()), 0.04f, kSidewalkHeight,
             top - 0.2f, tone, Bits(rng));
  const std::uint32_t obj = b.NewObject("traffic_sign", SemanticClass::kTrafficSign);
  const Eigen::Vector2d n = FacingDirection(facing);
  const Eigen::Vector2d c = p + n * 0.07;
  const double w = rng.Uniform(0.3, 0.4);
  const Eigen::Vector2d half(std::abs(n.x()) * 0.02 + std::abs(n.y()) * w,
                             std::abs(n.y()) * 0.02 + std::abs(n.x()) * w);
  Primitive& s = b.Box(obj, Material::kSign, SemanticClass::kTrafficSign,
                       {F(c.x() - half.x()), F(c.y() - half.y()), top - F(2 * w)},
                       {F(c.x() + half.x()), F(c.y() + half.y()), top}, tone, Bits(rng));
  s.facing = static_cast<std::uint8_t>(facing);
}

void AddCar(Builder& b, Rng& rng, int axis, double along, double across, double length) {
  const std::uint32_t obj = b.NewObject("car", SemanticClass::kCar);
  const double width = rng.Uniform(1.7, 1.9), height = rng.Uniform(1.4, 1.6);
  const float tone = F(rng.Uniform());
  const std::uint32_t variant = Bits(rng);
  auto box = [&](Material m, double a0, double a1, double c0, double c1, double z0, double z1) {
    Eigen::Vector3f lo, hi;
    if (axis == 0) {
      lo = {F(along + a0), F(across + c0), F(z0)};
      hi = {F(along + a1), F(across + c1), F(z1)};
    } else {
      lo = {F(across + c0), F(along + a0), F(z0)};
      hi = {F(across + c1), F(along + a1), F(z1)};
    }
    b.Box(obj, m, SemanticClass::kCar, lo, hi, tone, variant);
  };
  const double hl = length / 2, hw = width / 2;
  const double belt = height * 0.6;
  box(Material::kCarBody, -hl, hl, -hw, hw, 0.3, belt);
  const double cab0 = -hl * 0.55 + rng.Uniform(-0.2, 0.2), cab1 = hl * 0.35;
  box(Material::kCarCabin, cab0, cab1, -hw + 0.08, hw - 0.08, belt, height);
  for (int fa = -1; fa <= 1; fa += 2) {
    for (int sa = -1; sa <= 1; sa += 2) {
      const double wa = fa * (hl - 0.85), ws = sa * (hw - 0.12);
      box(Material::kTire, wa - 0.32, wa + 0.32, ws - 0.13, ws + 0.13, 0.0, 0.62);
    }
  }
}

void AddPerson(Builder& b, Rng& rng, double x, double y) {
  const std::uint32_t obj = b.NewObject("person", SemanticClass::kPerson);
  const float tone = F(rng.Uniform());
  const std::uint32_t variant = Bits(rng);
  const double h = rng.Uniform(1.55, 1.9);
  const float z0 = kSidewalkHeight;
  b.Box(obj, Material::kClothes, SemanticClass::kPerson, {F(x - 0.16), F(y - 0.12), z0},
        {F(x + 0.16), F(y + 0.12), z0 + F(h * 0.47)}, tone * 0.5f, variant);
  b.Box(obj, Material::kClothes, SemanticClass::kPerson, {F(x - 0.22), F(y - 0.14), z0 + F(h * 0.47)},
        {F(x + 0.22), F(y + 0.14), z0 + F(h * 0.86)}, tone, variant ^ 1u);
  b.Ellipsoid(obj, Material::kSkin, SemanticClass::kPerson, {F(x), F(y), z0 + F(h * 0.93)},
              {0.1f, 0.1f, F(h * 0.07)}, tone, variant);
}

void AddBicycle(Builder& b, Rng& rng, int axis, double x, double y) {
  const std::uint32_t obj = b.NewObject("bicycle", SemanticClass::kBicycle);
  const float tone = F(rng.Uniform());
  const std::uint32_t variant = Bits(rng);
  const float z0 = kSidewalkHeight;
  auto box = [&](double a0, double a1, double c0, double c1, double z_lo, double z_hi) {
    const Eigen::Vector3f lo = axis == 0 ? Eigen::Vector3f(F(x + a0), F(y + c0), z0 + F(z_lo))
                                         : Eigen::Vector3f(F(x + c0), F(y + a0), z0 + F(z_lo));
    const Eigen::Vector3f hi = axis == 0 ? Eigen::Vector3f(F(x + a1), F(y + c1), z0 + F(z_hi))
                                         : Eigen::Vector3f(F(x + c1), F(y + a1), z0 + F(z_hi));
    b.Box(obj, Material::kBicycle, SemanticClass::kBicycle, lo, hi, tone, variant);
  };
  box(-0.85, -0.2, -0.025, 0.025, 0.0, 0.66);  // rear wheel
  box(0.2, 0.85, -0.025, 0.025, 0.0, 0.66);    // front wheel
  box(-0.5, 0.55, -0.02, 0.02, 0.55, 0.62);    // top tube
  box(-0.3, -0.15, -0.1, 0.1, 0.85, 0.92);     // saddle
  box(0.45, 0.55, -0.28, 0.28, 0.95, 1.0);     // handlebar
}

}  // namespace semslam::sim::city_parts
