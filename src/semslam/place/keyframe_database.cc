#include "semslam/place/keyframe_database.h"

#include <algorithm>
#include <mutex>

#include "semslam/core/error.h"

namespace semslam {

KeyFrameDatabase::KeyFrameDatabase(size_t num_words) : inverted_(num_words) {}

void KeyFrameDatabase::Add(std::uint64_t id, const BowVector& bow) {
  for (const auto& [word, weight] : bow) {
    Require(word < inverted_.size(), "KeyFrameDatabase: word id beyond the vocabulary");
  }
  std::unique_lock lock(mutex_);
  EraseLocked(id);
  std::uint32_t slot;
  if (!free_slots_.empty()) {
    slot = free_slots_.back();
    free_slots_.pop_back();
  } else {
    slot = static_cast<std::uint32_t>(id_of_slot_.size());
    id_of_slot_.push_back(0);
    words_of_slot_.emplace_back();
  }
  id_of_slot_[slot] = id;
  slot_of_[id] = slot;
  auto& words = words_of_slot_[slot];
  words.clear();
  words.reserve(bow.size());
  for (const auto& [word, weight] : bow) {
    if (weight <= 0.0) continue;
    inverted_[word].push_back({slot, weight});
    words.push_back(word);
  }
}

void KeyFrameDatabase::Erase(std::uint64_t id) {
  std::unique_lock lock(mutex_);
  EraseLocked(id);
}

void KeyFrameDatabase::EraseLocked(std::uint64_t id) {
  const auto it = slot_of_.find(id);
  if (it == slot_of_.end()) return;
  const std::uint32_t slot = it->second;
  for (const WordId word : words_of_slot_[slot]) {
    auto& postings = inverted_[word];
    const auto p =
        std::find_if(postings.begin(), postings.end(), [&](const Posting& q) { return q.slot == slot; });
    if (p != postings.end()) {
      *p = postings.back();
      postings.pop_back();
    }
  }
  words_of_slot_[slot].clear();
  slot_of_.erase(it);
  free_slots_.push_back(slot);
}

void KeyFrameDatabase::Clear() {
  std::unique_lock lock(mutex_);
  for (auto& postings : inverted_) postings.clear();
  slot_of_.clear();
  id_of_slot_.clear();
  words_of_slot_.clear();
  free_slots_.clear();
}

size_t KeyFrameDatabase::size() const {
  std::shared_lock lock(mutex_);
  return slot_of_.size();
}

bool KeyFrameDatabase::Contains(std::uint64_t id) const {
  std::shared_lock lock(mutex_);
  return slot_of_.count(id) > 0;
}

std::vector<DatabaseResult> KeyFrameDatabase::Query(const BowVector& bow,
                                                    const DatabaseQueryOptions& options) const {
  std::shared_lock lock(mutex_);
  // Accumulate per keyframe slot, word by word in increasing word order (the order ScoreL1 sums in, so the
  // scores are exactly those of Vocabulary::Score).
  std::vector<double> score(id_of_slot_.size(), 0.0);
  std::vector<int> shared(id_of_slot_.size(), 0);
  std::vector<std::uint32_t> touched;
  for (const auto& [word, weight] : bow) {
    if (word >= inverted_.size()) continue;
    for (const Posting& p : inverted_[word]) {
      if (shared[p.slot] == 0) touched.push_back(p.slot);
      ++shared[p.slot];
      score[p.slot] += std::min(weight, p.weight);
    }
  }
  std::vector<DatabaseResult> results;
  results.reserve(touched.size());
  for (const std::uint32_t slot : touched) {
    if (shared[slot] < options.min_shared_words) continue;
    const double s = std::clamp(score[slot], 0.0, 1.0);
    if (s < options.min_score) continue;
    const std::uint64_t id = id_of_slot_[slot];
    if (options.filter && !options.filter(id)) continue;
    results.push_back({id, s, shared[slot]});
  }
  std::sort(results.begin(), results.end(), [](const DatabaseResult& a, const DatabaseResult& b) {
    return a.score > b.score || (a.score == b.score && a.id < b.id);
  });
  if (options.max_results > 0 && results.size() > options.max_results) results.resize(options.max_results);
  return results;
}

}  // namespace semslam
