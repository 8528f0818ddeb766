#pragma once
// Hierarchical vocabulary of binary words (Nister & Stewenius 2006, "vocabulary tree"; Galvez-Lopez &
// Tardos 2012, binary descriptors): a tree of branching k and depth L whose nodes are descriptors. A
// descriptor's word is found by descending from the root to the nearest child at every level (k * L
// Hamming distances). Trained by hierarchical k-majority clustering (k-medians for bit vectors: k-means++
// seeding with the Hamming distance, centroids by bitwise majority). Leaves carry IDF weights; images
// become L1-normalized TF-IDF vectors compared with the L1 score.
//
// Files: our own versioned binary format with a checksum (Save / Load), and DBoW2's text format
// (ORBvoc.txt, as distributed with ORB-SLAM2) for users who have one.

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "semslam/features/orb_extractor.h"
#include "semslam/features/orb_types.h"
#include "semslam/place/bow_vector.h"

namespace semslam {

// How word weights enter a BoW vector (values as in DBoW2's files).
enum class BowWeighting : std::uint32_t {
  kTfIdf = 0,  // term frequency x inverse document frequency (the default)
  kTf = 1,
  kIdf = 2,
  kBinary = 3,
};

struct VocabularyTrainingOptions {
  int branching = 10;       // k
  int depth = 4;            // L: levels below the root (at most k^L words)
  int max_iterations = 10;  // k-majority iterations per node
  std::uint64_t seed = 1;   // k-means++ seeding
  BowWeighting weighting = BowWeighting::kTfIdf;
  OrbDescriptorPattern pattern = OrbDescriptorPattern::kSemslam;  // what the descriptors were made with
  bool parallel = true;
  void Check() const;
};

class Vocabulary {
 public:
  // An empty vocabulary (no words). Transform gives empty vectors.
  Vocabulary() = default;

  // Trains on the descriptors of a set of images (one vector per image; the images are the documents of
  // the IDF weights). `progress` (optional) is called with a line of text now and then.
  static Vocabulary Train(const std::vector<std::vector<Descriptor>>& images,
                          const VocabularyTrainingOptions& options,
                          const std::function<void(const std::string&)>& progress = {});

  // Reads a vocabulary saved by Save(); a file in DBoW2's text format is recognized and read too.
  // Throws InputError naming the file on any problem (missing, truncated, corrupt, wrong format).
  static Vocabulary Load(const std::filesystem::path& path);
  // DBoW2's text format: a header line "k L scoring weighting", then one line per node (root excluded,
  // nodes numbered from 1 in file order): "parent_id is_leaf b0 b1 ... b31 weight" with the 32 descriptor
  // bytes in decimal. Words are the leaves in file order. Descriptors are OpenCV ORB bytes.
  static Vocabulary LoadDbow2Text(const std::filesystem::path& path);
  // Writes our binary format atomically. Throws std::runtime_error if it cannot be written.
  void Save(const std::filesystem::path& path) const;

  bool empty() const { return words_.empty(); }
  size_t size() const { return words_.size(); }  // number of words
  size_t num_nodes() const { return descriptors_.size(); }
  int branching() const { return branching_; }
  int depth() const { return depth_; }
  BowWeighting weighting() const { return weighting_; }
  // Which ORB pattern the descriptors must be computed with for this vocabulary to make sense.
  OrbDescriptorPattern descriptor_pattern() const { return pattern_; }

  // The word of one descriptor (empty vocabulary: 0).
  WordId Word(const Descriptor& descriptor) const;
  // The word of a descriptor, and the node it passed through at `level` (0 = root; a leaf above `level`
  // is its own node).
  WordId Word(const Descriptor& descriptor, int level, NodeId* node_at_level) const;
  double WordWeight(WordId word) const { return word_weight_[word]; }
  NodeId WordNode(WordId word) const { return words_[word]; }
  int NodeLevel(NodeId node) const { return node_level_[node]; }

  // BoW vector (L1-normalized) and, if asked, the direct index at `direct_index_level` levels below the
  // root (default: DefaultDirectIndexLevel()).
  void Transform(const std::vector<Descriptor>& descriptors, BowVector* bow,
                 FeatureVector* features = nullptr, int direct_index_level = -1) const;
  BowVector Transform(const std::vector<Descriptor>& descriptors) const;
  // The L1 score of two vectors of this vocabulary, in [0, 1].
  double Score(const BowVector& a, const BowVector& b) const { return ScoreL1(a, b); }

  // Level of the direct index by default: 2 below the root (k^2 nodes, e.g. 100 for k = 10), or the
  // leaves' level if the tree is shallower.
  int DefaultDirectIndexLevel() const { return std::min(2, depth_); }

  // Tree access (BFS order: the root is node 0, a node's children are contiguous and come after it).
  const Descriptor& NodeDescriptor(NodeId node) const { return descriptors_[node]; }
  NodeId Parent(NodeId node) const { return parent_[node]; }
  bool IsLeaf(NodeId node) const { return num_children_[node] == 0; }

  bool operator==(const Vocabulary&) const = default;

  // Builds a vocabulary from its tree (BFS order as above, parent[0] == 0 for the root). Leaves are the
  // nodes without children; word w is the w-th leaf in node order, with weight leaf_weights[w].
  // Throws InvalidArgument if the tree is not in that form.
  static Vocabulary FromTree(int branching, int depth, BowWeighting weighting, OrbDescriptorPattern pattern,
                             std::vector<NodeId> parent, std::vector<Descriptor> descriptors,
                             std::vector<double> leaf_weights);

 private:
  void BuildIndex();  // children ranges, levels, words from parent_

  int branching_ = 0;
  int depth_ = 0;
  BowWeighting weighting_ = BowWeighting::kTfIdf;
  OrbDescriptorPattern pattern_ = OrbDescriptorPattern::kSemslam;
  std::vector<NodeId> parent_;
  std::vector<Descriptor> descriptors_;
  std::vector<double> word_weight_;  // per word
  // Derived:
  std::vector<NodeId> first_child_;
  std::vector<std::uint32_t> num_children_;
  std::vector<int> node_level_;
  std::vector<std::int64_t> node_word_;  // -1 for inner nodes
  std::vector<NodeId> words_;            // word -> node
};

// The vocabulary semslam uses unless told otherwise: $SEMSLAM_VOCABULARY if set; else
// share/semslam/vocabulary/semslam.voc next to the installed executable (../share relative to its directory);
// else data/vocabulary/semslam.voc in the source tree; else the one under the install prefix. Returns the first
// that exists, or the source-tree path if none does (so the error names a sensible file).
std::filesystem::path DefaultVocabularyPath();

}  // namespace semslam
