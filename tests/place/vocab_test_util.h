#pragma once
// Helpers shared by the place tests.

#include <random>
#include <vector>

#include "semslam/features/orb_types.h"

namespace semslam::testing {

// `clusters` random 256-bit centres; image i holds `per_image` descriptors of clusters i % clusters and
// (i + 1) % clusters, each a centre with up to `noise_bits` random bits flipped.
struct ClusteredData {
  std::vector<Descriptor> centers;
  std::vector<std::vector<Descriptor>> images;
  std::vector<std::vector<int>> labels;  // cluster of each descriptor
};

inline Descriptor FlipBits(Descriptor d, int bits, std::mt19937_64& rng) {
  std::uniform_int_distribution<int> bit(0, 255);
  for (int k = 0; k < bits; ++k) {
    const int b = bit(rng);
    d[static_cast<size_t>(b / 64)] ^= std::uint64_t{1} << (b % 64);
  }
  return d;
}

inline ClusteredData MakeClusteredData(int clusters, int num_images, int per_image, int noise_bits,
                                       std::uint64_t seed = 1) {
  std::mt19937_64 rng(seed);
  ClusteredData data;
  for (int c = 0; c < clusters; ++c) data.centers.push_back({rng(), rng(), rng(), rng()});
  std::uniform_int_distribution<int> noise(0, noise_bits);
  for (int i = 0; i < num_images; ++i) {
    std::vector<Descriptor> image;
    std::vector<int> labels;
    for (int k = 0; k < per_image; ++k) {
      const int c = (i + k % 2) % clusters;
      image.push_back(FlipBits(data.centers[static_cast<size_t>(c)], noise(rng), rng));
      labels.push_back(c);
    }
    data.images.push_back(image);
    data.labels.push_back(labels);
  }
  return data;
}

}  // namespace semslam::testing
