// Hierarchical k-majority clustering of binary descriptors (Galvez-Lopez & Tardos 2012, section IV; the
// vocabulary tree of Nister & Stewenius 2006 with the mean replaced by the bitwise majority, the centroid
// that minimizes the summed Hamming distance per bit), seeded with k-means++ (Arthur & Vassilvitskii 2007).

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <numeric>

#include "semslam/core/error.h"
#include "semslam/core/timing.h"
#include "semslam/place/vocabulary.h"

namespace semslam {
namespace {

// splitmix64: tiny, deterministic and the same everywhere.
class Random {
 public:
  explicit Random(std::uint64_t seed) : state_(seed) {}
  std::uint64_t Next() {
    std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  double Uniform() { return static_cast<double>(Next() >> 11) * 0x1.0p-53; }

 private:
  std::uint64_t state_;
};

std::uint64_t Mix(std::uint64_t a, std::uint64_t b) {
  Random r(a * 0x9E3779B97F4A7C15ull + b + 0x632BE59BD9B4E019ull);
  return r.Next();
}

constexpr size_t kParallelThreshold = 20000;  // members above which a node's steps run in parallel
constexpr size_t kChunks = 16;                // fixed chunking: sums do not depend on scheduling

template <typename Fn>
void ForChunks(bool parallel, size_t n, Fn&& fn) {
  const size_t chunks = (parallel && n >= kParallelThreshold) ? kChunks : 1;
  auto body = [&](size_t c) { fn(c, n * c / chunks, n * (c + 1) / chunks); };
  if (chunks == 1) {
    body(0);
  } else {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, chunks, 1), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t c = r.begin(); c != r.end(); ++c) body(c);
    });
  }
}

struct Clustering {
  std::vector<Descriptor> centers;
  std::vector<std::vector<std::uint32_t>> groups;
};

// Nearest center of a descriptor (first on ties).
int Nearest(const Descriptor& d, const std::vector<Descriptor>& centers) {
  int best = 0, best_distance = HammingDistance(d, centers[0]);
  for (size_t c = 1; c < centers.size(); ++c) {
    const int dist = HammingDistance(d, centers[c]);
    if (dist < best_distance) {
      best_distance = dist;
      best = static_cast<int>(c);
    }
  }
  return best;
}

// Splits `members` (indices into `all`) into at most k groups.
Clustering KMajority(const std::vector<Descriptor>& all, const std::vector<std::uint32_t>& members, int k,
                     int max_iterations, std::uint64_t seed, bool parallel) {
  const size_t n = members.size();
  Clustering out;
  // k-means++ seeding: the first center at random, then each next one with probability proportional to the
  // squared distance to the nearest center chosen so far.
  Random random(seed);
  std::vector<Descriptor>& centers = out.centers;
  centers.push_back(all[members[random.Next() % n]]);
  std::vector<double> d2(n);
  auto update_d2 = [&](bool first) {
    ForChunks(parallel, n, [&](size_t, size_t b, size_t e) {
      for (size_t i = b; i < e; ++i) {
        const double d = HammingDistance(all[members[i]], centers.back());
        d2[i] = first ? d * d : std::min(d2[i], d * d);
      }
    });
  };
  update_d2(true);
  while (static_cast<int>(centers.size()) < k) {
    const double total = std::accumulate(d2.begin(), d2.end(), 0.0);
    if (total <= 0.0) break;  // every member equals a center already
    double target = random.Uniform() * total;
    size_t pick = n - 1;
    for (size_t i = 0; i < n; ++i) {
      target -= d2[i];
      if (target < 0.0 && d2[i] > 0.0) {
        pick = i;
        break;
      }
    }
    if (d2[pick] <= 0.0) break;
    centers.push_back(all[members[pick]]);
    update_d2(false);
  }
  const size_t num_centers = centers.size();

  std::vector<int> assignment(n, -1);
  for (int iteration = 0; iteration < max_iterations; ++iteration) {
    // Assignment step.
    std::vector<int> changed(kChunks, 0);
    ForChunks(parallel, n, [&](size_t chunk, size_t b, size_t e) {
      int count = 0;
      for (size_t i = b; i < e; ++i) {
        const int c = Nearest(all[members[i]], centers);
        count += c != assignment[i];
        assignment[i] = c;
      }
      changed[chunk] = count;
    });
    if (iteration > 0 && std::accumulate(changed.begin(), changed.end(), 0) == 0) break;
    // Update step: bitwise majority of each group (ties give 0).
    std::vector<std::vector<std::uint32_t>> counts(kChunks);
    std::vector<std::vector<std::uint32_t>> sizes(kChunks);
    ForChunks(parallel, n, [&](size_t chunk, size_t b, size_t e) {
      auto& cnt = counts[chunk];
      auto& sz = sizes[chunk];
      cnt.assign(num_centers * 256, 0);
      sz.assign(num_centers, 0);
      for (size_t i = b; i < e; ++i) {
        const size_t c = static_cast<size_t>(assignment[i]);
        const Descriptor& d = all[members[i]];
        std::uint32_t* row = cnt.data() + c * 256;
        for (size_t w = 0; w < 4; ++w) {
          const std::uint64_t bits = d[w];
          for (size_t bit = 0; bit < 64; ++bit)
            row[w * 64 + bit] += static_cast<std::uint32_t>((bits >> bit) & 1u);
        }
        ++sz[c];
      }
    });
    for (size_t c = 0; c < num_centers; ++c) {
      std::uint32_t size = 0;
      std::array<std::uint32_t, 256> total{};
      for (size_t chunk = 0; chunk < kChunks; ++chunk) {
        if (sizes[chunk].empty()) continue;
        size += sizes[chunk][c];
        for (size_t bit = 0; bit < 256; ++bit) total[bit] += counts[chunk][c * 256 + bit];
      }
      if (size == 0) continue;  // empty: keeps its old center (dropped at the end if still empty)
      Descriptor center{};
      for (size_t bit = 0; bit < 256; ++bit) {
        if (2 * total[bit] > size) center[bit / 64] |= std::uint64_t{1} << (bit % 64);
      }
      centers[c] = center;
    }
  }
  // Final groups from the last assignment (which matches the final centers unless max_iterations ran out,
  // where it is still a valid partition); empty groups dropped.
  for (size_t i = 0; i < n; ++i) assignment[i] = Nearest(all[members[i]], centers);
  std::vector<std::vector<std::uint32_t>> groups(num_centers);
  for (size_t i = 0; i < n; ++i) groups[static_cast<size_t>(assignment[i])].push_back(members[i]);
  Clustering result;
  for (size_t c = 0; c < num_centers; ++c) {
    if (groups[c].empty()) continue;
    result.centers.push_back(centers[c]);
    result.groups.push_back(std::move(groups[c]));
  }
  return result;
}

}  // namespace

Vocabulary Vocabulary::Train(const std::vector<std::vector<Descriptor>>& images,
                             const VocabularyTrainingOptions& options,
                             const std::function<void(const std::string&)>& progress) {
  options.Check();
  std::vector<Descriptor> all;
  size_t total = 0;
  for (const auto& image : images) total += image.size();
  Require(total > 0, "vocabulary training: no descriptors");
  Require(total < std::numeric_limits<std::uint32_t>::max(), "vocabulary training: too many descriptors");
  all.reserve(total);
  for (const auto& image : images) all.insert(all.end(), image.begin(), image.end());

  Stopwatch watch;
  // The tree, built level by level so that nodes come out breadth first.
  std::vector<NodeId> parent = {0};
  std::vector<Descriptor> node_descriptor = {Descriptor{}};
  std::vector<std::vector<std::uint32_t>> level_members(1);
  level_members[0].resize(all.size());
  std::iota(level_members[0].begin(), level_members[0].end(), 0u);
  std::vector<NodeId> level_nodes = {0};
  for (int level = 0; level < options.depth; ++level) {
    std::vector<Clustering> splits(level_nodes.size());
    auto split = [&](size_t i) {
      const auto& members = level_members[i];
      if (members.size() <= 1) return;  // a leaf
      if (members.size() <= static_cast<size_t>(options.branching)) {
        // Few members: each distinct descriptor becomes a child.
        Clustering& c = splits[i];
        for (const std::uint32_t m : members) {
          const auto it = std::find(c.centers.begin(), c.centers.end(), all[m]);
          if (it == c.centers.end()) {
            c.centers.push_back(all[m]);
            c.groups.push_back({m});
          } else {
            c.groups[static_cast<size_t>(it - c.centers.begin())].push_back(m);
          }
        }
      } else {
        splits[i] = KMajority(all, members, options.branching, options.max_iterations,
                              Mix(options.seed, level_nodes[i]), options.parallel);
      }
      if (splits[i].centers.size() <= 1) splits[i] = {};  // identical descriptors: nothing to split
    };
    if (options.parallel) {
      tbb::parallel_for(tbb::blocked_range<size_t>(0, level_nodes.size(), 1),
                        [&](const tbb::blocked_range<size_t>& r) {
                          for (size_t i = r.begin(); i != r.end(); ++i) split(i);
                        });
    } else {
      for (size_t i = 0; i < level_nodes.size(); ++i) split(i);
    }
    std::vector<NodeId> next_nodes;
    std::vector<std::vector<std::uint32_t>> next_members;
    for (size_t i = 0; i < level_nodes.size(); ++i) {
      for (size_t c = 0; c < splits[i].centers.size(); ++c) {
        next_nodes.push_back(static_cast<NodeId>(parent.size()));
        parent.push_back(level_nodes[i]);
        node_descriptor.push_back(splits[i].centers[c]);
        next_members.push_back(std::move(splits[i].groups[c]));
      }
    }
    if (progress) {
      progress(fmt::format("vocabulary: level {}/{} done, {} nodes, {:.1f} s", level + 1, options.depth,
                           parent.size(), watch.ElapsedSeconds()));
    }
    if (next_nodes.empty()) break;
    level_nodes = std::move(next_nodes);
    level_members = std::move(next_members);
  }
  Require(parent.size() >= 2, "vocabulary training: all descriptors are identical; nothing to cluster");

  // Word weights: IDF over the training images, log(N / n_w) with n_w the images containing word w (a word
  // no image reaches by descent counts as seen once).
  size_t num_leaves = 0;
  {
    std::vector<std::uint32_t> children(parent.size(), 0);
    for (size_t i = 1; i < parent.size(); ++i) ++children[parent[i]];
    for (size_t i = 1; i < parent.size(); ++i) num_leaves += children[i] == 0;
  }
  Vocabulary vocabulary = FromTree(options.branching, options.depth, options.weighting, options.pattern,
                                   parent, node_descriptor, std::vector<double>(num_leaves, 1.0));
  if (options.weighting == BowWeighting::kTfIdf || options.weighting == BowWeighting::kIdf) {
    std::vector<std::vector<WordId>> image_words(images.size());
    auto words_of = [&](size_t i) {
      auto& w = image_words[i];
      w.reserve(images[i].size());
      for (const Descriptor& d : images[i]) w.push_back(vocabulary.Word(d));
      std::sort(w.begin(), w.end());
      w.erase(std::unique(w.begin(), w.end()), w.end());
    };
    if (options.parallel) {
      tbb::parallel_for(tbb::blocked_range<size_t>(0, images.size(), 1),
                        [&](const tbb::blocked_range<size_t>& r) {
                          for (size_t i = r.begin(); i != r.end(); ++i) words_of(i);
                        });
    } else {
      for (size_t i = 0; i < images.size(); ++i) words_of(i);
    }
    std::vector<std::uint32_t> documents(num_leaves, 0);
    for (const auto& w : image_words) {
      for (const WordId word : w) ++documents[word];
    }
    const double n = static_cast<double>(images.size());
    for (size_t w = 0; w < num_leaves; ++w) {
      // At float precision, as stored (see FromTree).
      const double idf = std::log(n / static_cast<double>(std::max<std::uint32_t>(documents[w], 1)));
      vocabulary.word_weight_[w] = static_cast<double>(static_cast<float>(idf));
    }
  }
  if (progress) {
    progress(fmt::format("vocabulary: {} words, {} nodes from {} descriptors of {} images in {:.1f} s",
                         vocabulary.size(), vocabulary.num_nodes(), all.size(), images.size(),
                         watch.ElapsedSeconds()));
  }
  return vocabulary;
}

}  // namespace semslam
