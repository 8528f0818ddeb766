#pragma once
// Inverted index over keyframes' bag-of-words vectors (Sivic & Zisserman 2003; Galvez-Lopez & Tardos 2012):
// for every word, the keyframes that contain it with its weight there. A query scores only keyframes that
// share words with it, with the L1 score. Thread-safe: the tracking, mapping and loop-closing threads add,
// erase and query concurrently.

#include <cstdint>
#include <functional>
#include <shared_mutex>
#include <unordered_map>
#include <vector>

#include "semslam/place/bow_vector.h"

namespace semslam {

struct DatabaseResult {
  std::uint64_t id = 0;
  double score = 0.0;    // L1 score with the query, in [0, 1]
  int shared_words = 0;  // words the keyframe has in common with the query
};

struct DatabaseQueryOptions {
  size_t max_results = 0;  // 0: all
  int min_shared_words = 1;
  double min_score = 0.0;
  // Keyframes for which it returns false are skipped (e.g. the query's own covisible keyframes).
  std::function<bool(std::uint64_t)> filter;
};

class KeyFrameDatabase {
 public:
  // `num_words` is the vocabulary's size; words beyond it are an error (InvalidArgument).
  explicit KeyFrameDatabase(size_t num_words);

  // Adds a keyframe (replaces it if its id is already present).
  void Add(std::uint64_t id, const BowVector& bow);
  // Removes a keyframe; unknown ids are ignored.
  void Erase(std::uint64_t id);
  void Clear();
  size_t size() const;
  bool Contains(std::uint64_t id) const;
  size_t num_words() const { return inverted_.size(); }

  // Keyframes sharing words with `bow`, best score first (ties by id).
  std::vector<DatabaseResult> Query(const BowVector& bow, const DatabaseQueryOptions& options = {}) const;

 private:
  struct Posting {
    std::uint32_t slot;
    double weight;
  };
  void EraseLocked(std::uint64_t id);

  mutable std::shared_mutex mutex_;
  std::vector<std::vector<Posting>> inverted_;  // word -> postings
  std::unordered_map<std::uint64_t, std::uint32_t> slot_of_;
  std::vector<std::uint64_t> id_of_slot_;
  std::vector<std::vector<WordId>> words_of_slot_;  // to erase postings
  std::vector<std::uint32_t> free_slots_;
};

}  // namespace semslam
