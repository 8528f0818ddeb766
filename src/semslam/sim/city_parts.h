#pragma once
// What a synthetic town is built of: primitives grouped into objects (Builder), and the street objects drawn
// from a random stream (trees, bushes, traffic lights and signs, parked cars, persons, bicycles). city.cc
// lays the town out and places them.

#include <Eigen/Core>
#include <cstdint>
#include <string>

#include "semslam/semantics/class_table.h"
#include "semslam/sim/city.h"
#include "semslam/sim/random.h"

namespace semslam::sim::city_parts {

constexpr float kSidewalkHeight = 0.15f;

inline std::uint32_t Bits(Rng& rng) { return static_cast<std::uint32_t>(rng.Next() >> 32); }
inline float F(double v) { return static_cast<float>(v); }

// A primitive's tone and texture variant.
struct Look {
  float tone = 0;
  std::uint32_t variant = 0;
};
// The variant is drawn before the tone: the towns of the benchmark and the tests were made so (GCC evaluates
// a call's arguments last to first).
inline Look DrawLook(Rng& rng) {
  Look look;
  look.variant = Bits(rng);
  look.tone = F(rng.Uniform());
  return look;
}

// Appends objects and their primitives to a town.
class Builder {
 public:
  explicit Builder(City& city) : city_(city) {}

  std::uint32_t NewObject(const std::string& kind, SemanticClass label, const std::string& name = {}) {
    city_.objects.push_back({kind, static_cast<std::uint8_t>(TrainId(label)), name});
    return static_cast<std::uint32_t>(city_.objects.size() - 1);
  }
  Primitive& Box(std::uint32_t object, Material material, SemanticClass label, const Eigen::Vector3f& lo,
                 const Eigen::Vector3f& hi, float tone, std::uint32_t variant) {
    Primitive p;
    p.shape = Shape::kBox;
    p.material = material;
    p.label = static_cast<std::uint8_t>(TrainId(label));
    p.object = object;
    p.lo = lo.cwiseMin(hi);
    p.hi = lo.cwiseMax(hi);
    p.tone = tone;
    p.variant = variant;
    city_.primitives.push_back(p);
    return city_.primitives.back();
  }
  Primitive& Cylinder(std::uint32_t object, Material material, SemanticClass label, float cx, float cy,
                      float r, float z0, float z1, float tone, std::uint32_t variant) {
    Primitive& p = Box(object, material, label, {cx - r, cy - r, z0}, {cx + r, cy + r, z1}, tone, variant);
    p.shape = Shape::kCylinder;
    return p;
  }
  Primitive& Ellipsoid(std::uint32_t object, Material material, SemanticClass label, const Eigen::Vector3f& c,
                       const Eigen::Vector3f& r, float tone, std::uint32_t variant) {
    Primitive& p = Box(object, material, label, c - r, c + r, tone, variant);
    p.shape = Shape::kEllipsoid;
    return p;
  }

 private:
  City& city_;
};

// Street objects at ground position (x, y) (`axis` 0: along x, 1: along y; `facing` 0-3: +x, +y, -x, -y).
void AddTree(Builder& b, Rng& rng, double x, double y, float z0, double scale = 1.0);
void AddBush(Builder& b, Rng& rng, double x, double y);
void AddTrafficLight(Builder& b, Rng& rng, const Eigen::Vector2d& p, int facing);
void AddTrafficSign(Builder& b, Rng& rng, const Eigen::Vector2d& p, int facing);
void AddCar(Builder& b, Rng& rng, int axis, double along, double across, double length);
void AddPerson(Builder& b, Rng& rng, double x, double y);
void AddBicycle(Builder& b, Rng& rng, int axis, double x, double y);

}  // namespace semslam::sim::city_parts
