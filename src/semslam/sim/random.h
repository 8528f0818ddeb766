#pragma once
// Deterministic random numbers for the synthetic city. The standard library's distributions are
// implementation-defined, so the town of a seed would differ between standard libraries; these are our own:
// SplitMix64 (Steele, Lea, Flood 2014) as the generator and as a hash, uniform and Gaussian draws on top.
// For the same reason every draw is a statement of its own, never one of several arguments of one call: the
// order in which a call evaluates its arguments is the compiler's.

#include <cmath>
#include <cstdint>
#include <vector>

namespace semslam::sim {

// One SplitMix64 step: a bijective 64-bit mix with good avalanche.
constexpr std::uint64_t Mix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

// Hash of several integers (order matters).
constexpr std::uint64_t HashCombine(std::uint64_t a, std::uint64_t b) { return Mix64(a ^ Mix64(b)); }
constexpr std::uint64_t Hash3(std::uint64_t a, std::uint64_t b, std::uint64_t c) {
  return HashCombine(HashCombine(a, b), c);
}

// Cheap 32-bit integer hash for per-pixel and per-lattice-point noise (inner loops).
constexpr std::uint32_t Hash32(std::uint32_t x) {
  x ^= x >> 16;
  x *= 0x7FEB352Du;
  x ^= x >> 15;
  x *= 0x846CA68Bu;
  x ^= x >> 16;
  return x;
}
constexpr std::uint32_t Hash32(std::uint32_t a, std::uint32_t b) {
  return Hash32(a ^ Hash32(b + 0x9E3779B9u));
}
constexpr std::uint32_t Hash32(std::uint32_t a, std::uint32_t b, std::uint32_t c) {
  return Hash32(Hash32(a, b) ^ Hash32(c + 0x68E31DA4u));
}
// A hash mapped to [0, 1).
constexpr float HashToUnit(std::uint32_t h) { return static_cast<float>(h >> 8) * (1.0f / 16777216.0f); }

class Rng {
 public:
  explicit Rng(std::uint64_t seed) : state_(Mix64(seed)) {}
  // A generator for a named sub-stream: the same parent seed and stream give the same numbers, whatever
  // else was drawn before.
  static Rng Stream(std::uint64_t seed, std::uint64_t stream) { return Rng(HashCombine(seed, stream)); }

  std::uint64_t Next() {
    state_ += 0x9E3779B97F4A7C15ull;
    std::uint64_t z = state_;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  // Uniform in [0, 1).
  double Uniform() { return static_cast<double>(Next() >> 11) * (1.0 / 9007199254740992.0); }
  double Uniform(double lo, double hi) { return lo + (hi - lo) * Uniform(); }
  // Uniform integer in [lo, hi].
  int UniformInt(int lo, int hi) {
    const auto span = static_cast<std::uint64_t>(static_cast<std::int64_t>(hi) - lo + 1);
    return lo + static_cast<int>(Next() % span);
  }
  bool Bernoulli(double p) { return Uniform() < p; }
  // Standard normal (Box-Muller, one value per call).
  double Gaussian() {
    const double u1 = 1.0 - Uniform();  // (0, 1]
    const double u2 = Uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2);
  }
  template <typename T>
  const T& Pick(const std::vector<T>& items) {
    return items[static_cast<size_t>(UniformInt(0, static_cast<int>(items.size()) - 1))];
  }

 private:
  std::uint64_t state_;
};

}  // namespace semslam::sim
