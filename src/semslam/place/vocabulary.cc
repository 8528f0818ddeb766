#include "semslam/place/vocabulary.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>

#include "semslam/core/binary_io.h"
#include "semslam/core/error.h"
#include "semslam/core/text_reader.h"

#ifndef SEMSLAM_SOURCE_DIR
#define SEMSLAM_SOURCE_DIR ""
#endif
#ifndef SEMSLAM_INSTALL_DATADIR
#define SEMSLAM_INSTALL_DATADIR ""
#endif

namespace semslam {
namespace {

constexpr std::string_view kMagic = "SEMSLVOC";
constexpr std::uint32_t kFormatVersion = 1;
constexpr int kMaxBranching = 256;
constexpr int kMaxDepth = 16;

}  // namespace

void VocabularyTrainingOptions::Check() const {
  Require(branching >= 2 && branching <= kMaxBranching, "vocabulary training: branching must be in [2, 256]");
  Require(depth >= 1 && depth <= kMaxDepth, "vocabulary training: depth must be in [1, 16]");
  Require(std::pow(static_cast<double>(branching), depth) <= 1e8,
          "vocabulary training: branching^depth must be <= 1e8 words");
  Require(max_iterations >= 1, "vocabulary training: max_iterations must be >= 1");
  Require(static_cast<std::uint32_t>(weighting) <= 3, "vocabulary training: bad weighting");
}

Vocabulary Vocabulary::FromTree(int branching, int depth, BowWeighting weighting,
                                OrbDescriptorPattern pattern, std::vector<NodeId> parent,
                                std::vector<Descriptor> descriptors, std::vector<double> leaf_weights) {
  Require(branching >= 2 && branching <= kMaxBranching, "vocabulary: branching must be in [2, 256]");
  Require(depth >= 1 && depth <= kMaxDepth, "vocabulary: depth must be in [1, 16]");
  Require(static_cast<std::uint32_t>(weighting) <= 3, "vocabulary: bad weighting");
  Require(parent.size() == descriptors.size(), "vocabulary: one parent per node needed");
  Require(parent.size() >= 2, "vocabulary: a tree needs a root and at least one child");
  Vocabulary v;
  v.branching_ = branching;
  v.depth_ = depth;
  v.weighting_ = weighting;
  v.pattern_ = pattern;
  v.parent_ = std::move(parent);
  v.descriptors_ = std::move(descriptors);
  v.word_weight_ = std::move(leaf_weights);
  // Weights are kept at float precision: what Save() stores, so that a loaded vocabulary equals the saved
  // one.
  for (double& w : v.word_weight_) w = static_cast<double>(static_cast<float>(w));
  v.BuildIndex();
  return v;
}

void Vocabulary::BuildIndex() {
  const size_t n = parent_.size();
  Require(parent_[0] == 0, "vocabulary: the root's parent must be itself (0)");
  first_child_.assign(n, 0);
  num_children_.assign(n, 0);
  node_level_.assign(n, 0);
  for (size_t i = 1; i < n; ++i) {
    const NodeId p = parent_[i];
    Require(p < i, fmt::format("vocabulary: node {} has parent {} that does not come before it", i, p));
    Require(i == 1 || p >= parent_[i - 1],
            fmt::format("vocabulary: node {} breaks breadth-first order (children not contiguous)", i));
    if (num_children_[p] == 0) first_child_[p] = static_cast<NodeId>(i);
    ++num_children_[p];
    Require(num_children_[p] <= static_cast<std::uint32_t>(branching_),
            fmt::format("vocabulary: node {} has more than k = {} children", p, branching_));
    node_level_[i] = node_level_[p] + 1;
    Require(node_level_[i] <= depth_, fmt::format("vocabulary: node {} is deeper than L = {}", i, depth_));
  }
  node_word_.assign(n, -1);
  words_.clear();
  for (size_t i = 1; i < n; ++i) {
    if (num_children_[i] == 0) {
      node_word_[i] = static_cast<std::int64_t>(words_.size());
      words_.push_back(static_cast<NodeId>(i));
    }
  }
  Require(word_weight_.size() == words_.size(),
          fmt::format("vocabulary: {} word weights for {} leaves", word_weight_.size(), words_.size()));
  for (const double w : word_weight_)
    Require(std::isfinite(w) && w >= 0.0, "vocabulary: word weights must be finite and >= 0");
}

WordId Vocabulary::Word(const Descriptor& descriptor) const {
  NodeId unused;
  return Word(descriptor, 0, &unused);
}

WordId Vocabulary::Word(const Descriptor& descriptor, int level, NodeId* node_at_level) const {
  if (words_.empty()) {
    *node_at_level = 0;
    return 0;
  }
  NodeId node = 0;
  *node_at_level = 0;
  while (num_children_[node] > 0) {
    const NodeId first = first_child_[node];
    const NodeId end = first + num_children_[node];
    NodeId best = first;
    int best_distance = HammingDistance(descriptor, descriptors_[first]);
    for (NodeId c = first + 1; c < end; ++c) {
      const int d = HammingDistance(descriptor, descriptors_[c]);
      if (d < best_distance) {
        best_distance = d;
        best = c;
      }
    }
    node = best;
    if (node_level_[node] <= level) *node_at_level = node;
  }
  return static_cast<WordId>(node_word_[node]);
}

void Vocabulary::Transform(const std::vector<Descriptor>& descriptors, BowVector* bow,
                           FeatureVector* features, int direct_index_level) const {
  if (direct_index_level < 0) direct_index_level = DefaultDirectIndexLevel();
  if (features != nullptr) features->clear();
  std::vector<WordId> words(descriptors.size());
  for (size_t i = 0; i < descriptors.size(); ++i) {
    NodeId node;
    words[i] = Word(descriptors[i], direct_index_level, &node);
    if (features != nullptr && !words_.empty()) (*features)[node].push_back(static_cast<int>(i));
  }
  if (bow == nullptr) return;
  if (words_.empty()) {
    *bow = BowVector();
    return;
  }
  std::sort(words.begin(), words.end());
  std::vector<BowVector::Entry> entries;
  for (size_t i = 0; i < words.size();) {
    size_t j = i;
    while (j < words.size() && words[j] == words[i]) ++j;
    const double count = static_cast<double>(j - i);
    const double idf = word_weight_[words[i]];
    double value = 0.0;
    switch (weighting_) {
      case BowWeighting::kTfIdf:
        value = count * idf;
        break;
      case BowWeighting::kTf:
        value = count;
        break;
      case BowWeighting::kIdf:
        value = idf;
        break;
      case BowWeighting::kBinary:
        value = 1.0;
        break;
    }
    if (value > 0.0) entries.emplace_back(words[i], value);
    i = j;
  }
  *bow = BowVector(std::move(entries));  // already sorted and unique
  bow->NormalizeL1();
}

BowVector Vocabulary::Transform(const std::vector<Descriptor>& descriptors) const {
  BowVector bow;
  Transform(descriptors, &bow, nullptr);
  return bow;
}

void Vocabulary::Save(const std::filesystem::path& path) const {
  BinaryWriter writer;
  writer.Put<std::uint32_t>(static_cast<std::uint32_t>(branching_));
  writer.Put<std::uint32_t>(static_cast<std::uint32_t>(depth_));
  writer.Put<std::uint32_t>(static_cast<std::uint32_t>(weighting_));
  writer.Put<std::uint32_t>(static_cast<std::uint32_t>(pattern_));
  // The tree as child counts in breadth-first order (parents follow from them), then the node descriptors,
  // then the word weights (float).
  std::vector<std::uint16_t> children(num_children_.begin(), num_children_.end());
  writer.PutVector(children);
  writer.PutVector(descriptors_);
  std::vector<float> weights(word_weight_.begin(), word_weight_.end());
  writer.PutVector(weights);
  WriteChecksummedFile(path, kMagic, kFormatVersion, writer.bytes());
}

Vocabulary Vocabulary::Load(const std::filesystem::path& path) {
  {
    std::ifstream in(path, std::ios::binary);
    if (!std::filesystem::exists(path)) throw InputError(path, "vocabulary file not found");
    if (!in) throw InputError(path, "cannot open vocabulary file");
    char head[8] = {};
    in.read(head, 8);
    if (in.gcount() != 8 || std::string_view(head, 8) != kMagic) {
      // Not ours: DBoW2's text format starts with four small integers.
      return LoadDbow2Text(path);
    }
  }
  const ChecksummedFile file = ReadChecksummedFile(path, kMagic);
  if (file.version != kFormatVersion) {
    throw InputError(path, fmt::format("vocabulary format version {} is not supported (this build reads {})",
                                       file.version, kFormatVersion));
  }
  BinaryReader reader(file.payload, path);
  reader.set_context("vocabulary");
  const auto branching = reader.Get<std::uint32_t>();
  const auto depth = reader.Get<std::uint32_t>();
  const auto weighting = reader.Get<std::uint32_t>();
  const auto pattern = reader.Get<std::uint32_t>();
  if (branching < 2 || branching > kMaxBranching)
    reader.Fail(fmt::format("bad branching factor {}", branching));
  if (depth < 1 || depth > kMaxDepth) reader.Fail(fmt::format("bad depth {}", depth));
  if (weighting > 3) reader.Fail(fmt::format("bad weighting {}", weighting));
  if (pattern > 1) reader.Fail(fmt::format("bad descriptor pattern {}", pattern));
  const auto children = reader.GetVector<std::uint16_t>();
  auto descriptors = reader.GetVector<Descriptor>();
  const auto stored_weights = reader.GetVector<float>();
  if (children.size() != descriptors.size()) reader.Fail("node counts of the tree and descriptors differ");
  // Parents from the child counts: node i's children follow those of nodes 0..i-1.
  std::vector<NodeId> parent(children.size(), 0);
  size_t next = 1;
  for (size_t i = 0; i < children.size(); ++i) {
    if (children[i] > branching)
      reader.Fail(fmt::format("node {} has {} children, more than k", i, children[i]));
    if (i >= next && i > 0) reader.Fail(fmt::format("node {} is not reachable from the root", i));
    for (size_t c = 0; c < children[i]; ++c, ++next) {
      if (next >= parent.size()) reader.Fail("the tree has more children than nodes");
      parent[next] = static_cast<NodeId>(i);
    }
  }
  if (next != parent.size()) reader.Fail("the tree's child counts do not add up to its nodes");
  std::vector<double> weights(stored_weights.begin(), stored_weights.end());
  if (!reader.AtEnd()) reader.Fail("trailing bytes after the vocabulary");
  try {
    return FromTree(static_cast<int>(branching), static_cast<int>(depth),
                    static_cast<BowWeighting>(weighting), static_cast<OrbDescriptorPattern>(pattern),
                    std::move(parent), std::move(descriptors), std::move(weights));
  } catch (const InvalidArgument& e) {
    throw InputError(path, e.what());
  }
}

Vocabulary Vocabulary::LoadDbow2Text(const std::filesystem::path& path) {
  TextReader reader(path);
  auto header = reader.NextLine();
  while (header && Trim(*header).empty()) header = reader.NextLine();
  if (!header) throw InputError(path, "empty file: not a vocabulary");
  const auto head = SplitTokens(*header);
  if (head.size() != 4) {
    throw InputError(reader.Where(), "header",
                     "not a semslam vocabulary nor DBoW2 text (expected 'k L scoring weighting')");
  }
  const long long k = ParseInt(head[0], reader.Where(), "k");
  const long long levels = ParseInt(head[1], reader.Where(), "L");
  const long long scoring = ParseInt(head[2], reader.Where(), "scoring");
  const long long weighting = ParseInt(head[3], reader.Where(), "weighting");
  if (k < 2 || k > kMaxBranching)
    throw InputError(reader.Where(), "k", "branching factor must be in [2, 256]");
  if (levels < 1 || levels > kMaxDepth) throw InputError(reader.Where(), "L", "depth must be in [1, 16]");
  if (scoring < 0 || scoring > 5) throw InputError(reader.Where(), "scoring", "must be in [0, 5]");
  if (weighting < 0 || weighting > 3) throw InputError(reader.Where(), "weighting", "must be in [0, 3]");
  if (scoring != 0) {
    spdlog::warn("{}: vocabulary made for scoring type {}; semslam scores with L1 (type 0)", path.string(),
                 scoring);
  }

  // Nodes in file order (id = position, root = 0).
  std::vector<NodeId> file_parent = {0};
  std::vector<Descriptor> file_descriptor = {Descriptor{}};
  std::vector<double> file_weight = {0.0};
  std::vector<char> file_leaf = {0};
  std::vector<std::vector<NodeId>> children(1);
  std::vector<int> line_of = {0};
  while (auto line = reader.NextLine()) {
    const auto tokens = SplitTokens(*line);
    if (tokens.empty()) continue;
    const SourceLocation where = reader.Where();
    if (tokens.size() != 35) {
      throw InputError(where, fmt::format("expected 35 fields (parent, is_leaf, 32 bytes, weight), found {}",
                                          tokens.size()));
    }
    const auto id = static_cast<NodeId>(file_parent.size());
    const long long parent = ParseInt(tokens[0], where, "parent");
    if (parent < 0 || parent >= static_cast<long long>(id)) {
      throw InputError(where, "parent",
                       fmt::format("node {} names parent {}, which is not an earlier node", id, parent));
    }
    if (file_leaf[static_cast<size_t>(parent)]) {
      throw InputError(where, "parent", fmt::format("parent {} is a leaf", parent));
    }
    const long long leaf = ParseInt(tokens[1], where, "is_leaf");
    if (leaf != 0 && leaf != 1) throw InputError(where, "is_leaf", "must be 0 or 1");
    std::uint8_t bytes[32];
    for (size_t b = 0; b < 32; ++b) {
      const long long value = ParseInt(tokens[2 + b], where, "descriptor byte");
      if (value < 0 || value > 255)
        throw InputError(where, "descriptor byte", fmt::format("{} is not in [0, 255]", value));
      bytes[b] = static_cast<std::uint8_t>(value);
    }
    const double weight = ParseDouble(tokens[34], where, "weight");
    if (weight < 0.0) throw InputError(where, "weight", "must be >= 0");
    Descriptor d;
    std::memcpy(d.data(), bytes, sizeof(d));
    file_parent.push_back(static_cast<NodeId>(parent));
    file_descriptor.push_back(d);
    file_weight.push_back(weight);
    file_leaf.push_back(static_cast<char>(leaf));
    children.emplace_back();
    line_of.push_back(where.line);
    children[static_cast<size_t>(parent)].push_back(id);
    if (static_cast<long long>(children[static_cast<size_t>(parent)].size()) > k) {
      throw InputError(where, "parent", fmt::format("node {} has more than k = {} children", parent, k));
    }
  }
  if (file_parent.size() < 2) throw InputError(path, "the vocabulary has no nodes");
  for (size_t i = 1; i < file_parent.size(); ++i) {
    if (!file_leaf[i] && children[i].empty()) {
      throw InputError(SourceLocation{path, line_of[i]}, "is_leaf",
                       fmt::format("node {} is not a leaf but has no children", i));
    }
  }
  // Renumber breadth first.
  std::vector<NodeId> order = {0};
  std::vector<NodeId> new_id(file_parent.size(), 0);
  for (size_t head_index = 0; head_index < order.size(); ++head_index) {
    for (const NodeId c : children[order[head_index]]) {
      new_id[c] = static_cast<NodeId>(order.size());
      order.push_back(c);
    }
  }
  std::vector<NodeId> parent(order.size());
  std::vector<Descriptor> descriptors(order.size());
  std::vector<double> weights;
  for (size_t i = 0; i < order.size(); ++i) {
    const NodeId old = order[i];
    parent[i] = i == 0 ? 0 : new_id[file_parent[old]];
    descriptors[i] = file_descriptor[old];
    if (i > 0 && file_leaf[old]) weights.push_back(file_weight[old]);
  }
  try {
    return FromTree(static_cast<int>(k), static_cast<int>(levels), static_cast<BowWeighting>(weighting),
                    OrbDescriptorPattern::kOpenCv, std::move(parent), std::move(descriptors),
                    std::move(weights));
  } catch (const InvalidArgument& e) {
    throw InputError(path, e.what());
  }
}

std::filesystem::path DefaultVocabularyPath() {
  if (const char* env = std::getenv("SEMSLAM_VOCABULARY"); env != nullptr && *env != '\0') return env;
  const std::filesystem::path relative = std::filesystem::path("vocabulary") / "semslam.voc";
  std::vector<std::filesystem::path> candidates;
  // Installed: <prefix>/bin/semslam -> <prefix>/share/semslam/vocabulary/semslam.voc (first, so that an installed
  // binary uses its own vocabulary even while the source tree it was built from is still there).
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (!ec) candidates.push_back(exe.parent_path().parent_path() / "share" / "semslam" / relative);
  const std::filesystem::path source = std::filesystem::path(SEMSLAM_SOURCE_DIR) / "data" / relative;
  if (std::string_view(SEMSLAM_SOURCE_DIR).size() > 0) candidates.push_back(source);
  if (std::string_view(SEMSLAM_INSTALL_DATADIR).size() > 0) {
    candidates.push_back(std::filesystem::path(SEMSLAM_INSTALL_DATADIR) / relative);
  }
  for (const auto& c : candidates) {
    if (std::filesystem::exists(c, ec)) return c;
  }
  return std::string_view(SEMSLAM_SOURCE_DIR).size() > 0 ? source : std::filesystem::path("data") / relative;
}

}  // namespace semslam
