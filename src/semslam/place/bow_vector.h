#pragma once
// Bag-of-words vectors of an image (Sivic & Zisserman 2003; Nister & Stewenius 2006; Galvez-Lopez &
// Tardos 2012): the weights of the visual words it contains, and the "direct index" that groups its
// features by vocabulary node for fast matching.

#include <cstddef>
#include <cstdint>
#include <map>
#include <utility>
#include <vector>

namespace semslam {

using WordId = std::uint32_t;
using NodeId = std::uint32_t;

// Sparse vector of word weights, sorted by word id with unique words. Vocabulary::Transform makes it
// L1-normalized (weights >= 0, summing to 1).
class BowVector {
 public:
  using Entry = std::pair<WordId, double>;

  BowVector() = default;
  // From (word, weight) pairs in any order; repeated words are summed.
  explicit BowVector(std::vector<Entry> entries);

  const std::vector<Entry>& entries() const { return entries_; }
  size_t size() const { return entries_.size(); }
  bool empty() const { return entries_.empty(); }
  auto begin() const { return entries_.begin(); }
  auto end() const { return entries_.end(); }
  void clear() { entries_.clear(); }

  // Weight of a word, 0 if absent.
  double Weight(WordId word) const;
  double L1Norm() const;
  // Scales the weights to sum 1 (no-op for an all-zero vector).
  void NormalizeL1();

  bool operator==(const BowVector&) const = default;

 private:
  std::vector<Entry> entries_;
};

// L1 similarity of two L1-normalized vectors with non-negative weights:
// s = 1 - ||a - b||_1 / 2, in [0, 1] (1 for identical vectors, 0 for vectors without common words).
// Computed over common words only: s = sum_i min(a_i, b_i).
double ScoreL1(const BowVector& a, const BowVector& b);

// Direct index: vocabulary node (at a chosen level of the tree) -> indices of the image's features whose
// descriptors fall under it, in increasing order.
using FeatureVector = std::map<NodeId, std::vector<int>>;

}  // namespace semslam
