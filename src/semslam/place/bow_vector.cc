#include "semslam/place/bow_vector.h"

#include <algorithm>
#include <cmath>

namespace semslam {

BowVector::BowVector(std::vector<Entry> entries) {
  std::sort(entries.begin(), entries.end(), [](const Entry& a, const Entry& b) { return a.first < b.first; });
  entries_.reserve(entries.size());
  for (const Entry& e : entries) {
    if (!entries_.empty() && entries_.back().first == e.first) {
      entries_.back().second += e.second;
    } else {
      entries_.push_back(e);
    }
  }
}

double BowVector::Weight(WordId word) const {
  const auto it = std::lower_bound(entries_.begin(), entries_.end(), word,
                                   [](const Entry& e, WordId w) { return e.first < w; });
  return it != entries_.end() && it->first == word ? it->second : 0.0;
}

double BowVector::L1Norm() const {
  double sum = 0.0;
  for (const Entry& e : entries_) sum += std::abs(e.second);
  return sum;
}

void BowVector::NormalizeL1() {
  const double norm = L1Norm();
  if (norm <= 0.0) return;
  for (Entry& e : entries_) e.second /= norm;
}

double ScoreL1(const BowVector& a, const BowVector& b) {
  // For L1-normalized non-negative vectors, 1 - |a - b|_1 / 2 = sum over common words of min(a_i, b_i),
  // since |a_i - b_i| = a_i + b_i - 2 min(a_i, b_i) and words in only one vector add their weight.
  double score = 0.0;
  auto ia = a.begin(), ib = b.begin();
  while (ia != a.end() && ib != b.end()) {
    if (ia->first == ib->first) {
      score += std::min(ia->second, ib->second);
      ++ia;
      ++ib;
    } else if (ia->first < ib->first) {
      ++ia;
    } else {
      ++ib;
    }
  }
  return std::clamp(score, 0.0, 1.0);
}

}  // namespace semslam
